"""meerk40t's planned cutcode as galvoscan's job: one :class:`~galvoscan.plan.layers.Layer` an
operation (its speed, power and frequency), its cuts as the polylines of one
:class:`~galvoscan.plan.objects.MarkObject` in field mm, in meerk40t's order.

The cuts' coordinates are the device's native units, which the device's view makes galvoscan's
galvo units (0 … 65535 across the lens field, Y up): :func:`~galvoscan.geometry.field.from_galvo`
turns them into field mm. Curves are flattened to the job's chord tolerance by the SVG reader's
own rule; a PlotCut's (a plotted path: what meerk40t's G-code reader makes) steps at half the
operation's power or more are lines at its power; a dwell is a dot whose pulses are the dwell's
time at the operation's frequency; a RasterCut's (a raster or image operation's) runs of dark
pixels are lines, in the order meerk40t's own galvo driver walks them, each from its first
pixel's centre to its last's (one pixel: a dot), as ``mark --image`` marks a photo's runs.
A WaitCut (a wait operation's) splits the job (:func:`job_parts`): the driver holds the board
for its time between the parts. An InputCut or OutputCut (meerk40t's input and output
operations) splits it too, into I/O steps the board's queue does between the parts
(:func:`io_steps`: a bitstream with I/O in the queue, the ULX3S's): an input cut waits for each
input of its mask to be at its value's level, an output cut sets each output of its mask to its
value's, held.
"""

import math
from dataclasses import dataclass, replace

import numpy as np
from meerk40t.core.cutcode.cubiccut import CubicCut
from meerk40t.core.cutcode.dwellcut import DwellCut
from meerk40t.core.cutcode.inputcut import InputCut
from meerk40t.core.cutcode.linecut import LineCut
from meerk40t.core.cutcode.outputcut import OutputCut
from meerk40t.core.cutcode.plotcut import PlotCut
from meerk40t.core.cutcode.quadcut import QuadCut
from meerk40t.core.cutcode.rastercut import RasterCut
from meerk40t.core.cutcode.waitcut import WaitCut
from meerk40t.core.plotplanner import PlotPlanner
from meerk40t.device.basedevice import PLOT_FINISH, PLOT_JOG, PLOT_RAPID
from svgelements import CubicBezier, QuadraticBezier

from ..api import Job, Layer, job_settings
from ..gateware.fields import IOKind
from ..geometry.drawing import Drawing
from ..geometry.field import Placement, PlanError, from_galvo
from ..geometry.segments import IOStep
from ..inputs.svg import bezier_points
from ..plan.objects import MarkObject
from ..settings.io import DEFAULT_WAIT_TIMEOUT_S


__all__ = ["POWER_FULL", "DARK", "job_from_cuts", "job_parts", "operation_layer", "outline_cuts"]

#: meerk40t's power setting at full power (its galvo devices show it as 100 %).
POWER_FULL = 1000.0
#: A PlotCut step at this share of the operation's power or more is marked; below it, jumped
#: (the board holds one power a layer: no grey levels).
DARK = 0.5
#: The longest wait (ms) a WaitCut may ask for: an hour.
MAX_WAIT_MS = 3.6e6


@dataclass
class _Operation:
    """The cuts of one meerk40t operation: its settings and the polylines (galvo units)."""
    settings: dict
    dwell_ms: float = None
    paths: list = None

    def __post_init__(self):
        self.paths = []

    def add(self, points):
        """Continue the last polyline when ``points`` starts where it ends, else begin one."""
        if self.paths and tuple(self.paths[-1][-1]) == tuple(points[0]) and \
                self.dwell_ms is None:
            self.paths[-1].extend(points[1:])
        else:
            self.paths.append(list(points))


def operation_layer(name, settings):
    """The :class:`~galvoscan.plan.layers.Layer` of a meerk40t operation's ``settings`` (its
    ``speed`` mm/s, ``power`` per mille, ``frequency`` kHz; what it lacks is the job's)."""
    speed = settings.get("speed")
    power = settings.get("power")
    frequency = settings.get("frequency")
    return Layer(name,
                 speed_mm_s=float(speed) if speed is not None else None,
                 power_percent=float(power) * 100 / POWER_FULL if power is not None else None,
                 prr_khz=float(frequency) if frequency is not None else None)


def _cut_points(cut, tolerance_units):
    """The polylines (galvo units) that mark ``cut``: a list of point lists."""
    if isinstance(cut, LineCut):
        return [[cut.start, cut.end]]
    if isinstance(cut, QuadCut):
        curve = QuadraticBezier(cut.start, cut.c(), cut.end)
        return [[cut.start, *bezier_points(curve, tolerance_units)]]
    if isinstance(cut, CubicCut):
        curve = CubicBezier(cut.start, cut.c1(), cut.c2(), cut.end)
        return [[cut.start, *bezier_points(curve, tolerance_units)]]
    if isinstance(cut, DwellCut):
        return [[cut.start, cut.start]]
    if isinstance(cut, PlotCut):
        runs, last = [], None
        for x0, y0, on, x1, y1 in cut.plot:
            if on < DARK:
                last = None
                continue
            if last is not None and last == (x0, y0):
                runs[-1].append((x1, y1))
            else:
                runs.append([(x0, y0), (x1, y1)])
            last = (x1, y1)
        return runs
    if isinstance(cut, RasterCut):
        return _raster_runs(cut)
    if isinstance(cut, (InputCut, OutputCut)):
        raise PlanError(f"meerk40t's {type(cut).__name__} (an I/O operation) is no mark: "
                        f"job_parts takes it out of the cuts as I/O steps")
    raise PlanError(f"meerk40t's {type(cut).__name__} is not one the galvoscan device marks "
                    f"(lines, curves, dwells, waits, PlotCuts and RasterCuts are)")


def _raster_runs(cut):
    """A RasterCut's (a raster or image operation's) dark runs, as meerk40t's own galvo driver
    walks it: its plot planner's moves, a step at half the power or more marked; each run
    moved onto meerk40t's own geometry of the image (pixel ``i`` of a row from ``offset + i ×
    step`` to ``offset + (i + 1) × step``, a row likewise), and marked from its first pixel's
    centre to its last's (:func:`_on_the_pixels`)."""
    planner = PlotPlanner(dict(), single=True, ppi=False, shift=False, group=True,
                          require_uniform_movement=False)
    planner.settings_then_jog = True
    planner.push(cut)
    runs, last = [], None
    for x, y, on in planner.gen():
        if on > 1:                      # the planner's own commands: a move, or the end
            if on & PLOT_FINISH:
                break
            if on & (PLOT_RAPID | PLOT_JOG):
                last = (x, y)
            continue
        if on >= DARK and last is not None:
            if runs and runs[-1][-1] == last:
                runs[-1].append((x, y))
            else:
                runs.append([last, (x, y)])
        last = (x, y)
    return [_on_the_pixels(run, cut.step_x, cut.step_y) for run in runs]


def _on_the_pixels(run, step_x, step_y):
    """A run of meerk40t's raster plotter on the pixels it stands for: the plotter puts pixel
    ``i`` at ``offset + i × step`` and a run of ``n`` pixels from half a step before its first
    pixel's place to half a step after its last's; the image's pixel ``i`` is the square from
    ``offset + i × step`` to ``offset + (i + 1) × step``. So the run moves half a step along
    both axes (onto the pixels' centres' line, from its first pixel's left edge to its last's
    right edge), and each end comes in half a pixel along the run: first pixel's centre to
    last's, one pixel a dot."""
    points = np.array(run, dtype=float) + (step_x / 2, step_y / 2)
    ends = []
    for end, inner in ((0, 1), (-1, -2)):
        along = points[inner] - points[end]
        length = math.hypot(*along)
        if length == 0:
            ends.append(points[end])
            continue
        unit = along / length
        # Half a pixel along the run's direction (a row's: step_x; a column's: step_y); no
        # further than the middle of the step (a run of one pixel: a dot).
        half = 0.5 * math.hypot(unit[0] * step_x, unit[1] * step_y)
        ends.append(points[end] + unit * min(half, length / 2))
    points[0], points[-1] = ends
    return [(float(x), float(y)) for x, y in points]


#: Inputs and outputs a bitstream with I/O in the queue has (the bits of a cut's mask).
IO_BITS = 2


def io_steps(cut):
    """The :class:`~galvoscan.geometry.segments.IOStep` s of meerk40t's InputCut (a wait for
    each input of ``input_mask`` to be at its ``input_value`` bit's level, at most
    :data:`~galvoscan.settings.io.DEFAULT_WAIT_TIMEOUT_S`: then the board stops the job) or
    OutputCut (each output of ``output_mask`` set to its ``output_value`` bit, held), bit 0
    first. A mask that is not a whole number with bits among the board's two is a
    :class:`~galvoscan.geometry.field.PlanError` (one line)."""
    output = isinstance(cut, OutputCut)
    mask = cut.output_mask if output else cut.input_mask
    value = cut.output_value if output else cut.input_value
    what = "output" if output else "input"
    for name, number in (("mask", mask), ("value", value)):
        if isinstance(number, bool) or not isinstance(number, int) or number < 0:
            raise PlanError(f"meerk40t's {what} operation's {name} is {number!r}: a whole "
                            f"number of bits")
    if not mask or mask >> IO_BITS:
        raise PlanError(f"meerk40t's {what} operation's mask is {mask:#b}: the board has "
                        f"{what}s 0 and 1 (bits 0 and 1)")
    bits = [bit for bit in range(IO_BITS) if mask >> bit & 1]
    if output:
        return [IOStep(IOKind.SET_OUTPUT, index=bit, level=value >> bit & 1) for bit in bits]
    return [IOStep(IOKind.WAIT_INPUT, index=bit, level=value >> bit & 1,
                   arg_x=round(DEFAULT_WAIT_TIMEOUT_S * 1000)) for bit in bits]


def job_parts(cuts):
    """``cuts`` split at meerk40t's WaitCuts, InputCuts and OutputCuts: a list of ``("cuts",
    [cut, …])``, ``("hold", seconds)`` and ``("io", [IOStep, …])`` in order (empty cut lists
    left out, the steps of I/O cuts in a row together). A wait that is not a time of 0 ms or
    more (meerk40t gives its WaitCut's in ms), or an I/O cut :func:`io_steps` refuses, is a
    :class:`~galvoscan.geometry.field.PlanError` (one line)."""
    parts, current = [], []
    for cut in cuts:
        if isinstance(cut, (InputCut, OutputCut)):
            steps = io_steps(cut)
            if current:
                parts.append(("cuts", current))
                current = []
            if parts and parts[-1][0] == "io":
                parts[-1][1].extend(steps)
            else:
                parts.append(("io", steps))
        elif isinstance(cut, WaitCut):
            wait_ms = cut.dwell_time
            try:
                wait_ms = float(wait_ms)
            except (TypeError, ValueError):
                raise PlanError(f"a wait of {wait_ms!r} ms: a wait is a time of 0 ms or more")\
                    from None
            if not (math.isfinite(wait_ms) and 0 <= wait_ms <= MAX_WAIT_MS):
                raise PlanError(f"a wait of {wait_ms:g} ms: a wait is from 0 to "
                                f"{MAX_WAIT_MS:g} ms")
            if current:
                parts.append(("cuts", current))
                current = []
            if wait_ms > 0:
                parts.append(("hold", wait_ms / 1e3))
        else:
            current.append(cut)
    if current:
        parts.append(("cuts", current))
    return parts


def job_from_cuts(cuts, profile, *, tolerance_mm):
    """``cuts`` (meerk40t's planned cutcode, in the device's native units: galvo units) as
    ``(job, objects)``: a :class:`~galvoscan.api.Job` of a layer an operation and the
    :class:`~galvoscan.plan.objects.MarkObject` s that :func:`galvoscan.api.plan_made` plans.
    A :class:`~galvoscan.geometry.field.PlanError` (one line) for a cut it cannot mark."""
    field_mm = profile.field.size_mm
    tolerance_units = tolerance_mm * profile.units_per_mm
    operations = {}
    for cut in cuts:
        settings = cut.settings if cut.settings is not None else {}
        dwell = float(cut.dwell_time) if isinstance(cut, DwellCut) else None
        key = (id(settings), dwell)
        operation = operations.get(key)
        if operation is None:
            operation = operations[key] = _Operation(settings, dwell)
        for points in _cut_points(cut, tolerance_units):
            operation.add([tuple(float(v) for v in p) for p in points])
    # Marked as meerk40t ordered and filled them: no hatch, no re-ordering; the settings are
    # each operation's layer's, the rest the profile's.
    fill = replace(job_settings(Job(tolerance_mm=tolerance_mm), profile), hatch=(),
                   contour=None, outline=True)
    layers, objects = [], []
    for number, operation in enumerate(op for op in operations.values() if op.paths):
        name = f"meerk40t operation {number + 1}"
        layer = operation_layer(name, operation.settings)
        if operation.dwell_ms is not None:
            if not math.isfinite(operation.dwell_ms) or operation.dwell_ms <= 0:
                raise PlanError(f"{name}: a dwell of {operation.dwell_ms:g} ms: a dwell is a "
                                f"time above 0 ms")
            prr_khz = layer.prr_khz if layer.prr_khz is not None else profile.defaults.prr_khz
            # (A PRR that is not a number is refused with the layer's other settings.)
            pulses = max(1, round(operation.dwell_ms * prr_khz)) if math.isfinite(prr_khz) \
                else None
            # A dwell's dot does not move: its speed is one its pulses make (a galvo unit's
            # pitch), whatever the operation's or the profile's.
            speed = prr_khz * 1e3 / profile.units_per_mm / pulses if pulses else \
                layer.speed_mm_s
            layer = Layer(name, speed_mm_s=speed, power_percent=layer.power_percent,
                          prr_khz=layer.prr_khz, pulses_per_point=pulses)
        paths = tuple(np.asarray(from_galvo(np.array(p, dtype=float), field_mm))
                      for p in operation.paths)
        drawing = Drawing(name=name, paths=paths,
                          closed=tuple(bool(len(p) > 2 and (p[0] == p[-1]).all())
                                       for p in paths))
        objects.append(MarkObject(drawing, Placement(origin="page"), fill, keep_order=True,
                                  layer=name, own_fill=True))
        layers.append(layer)
    if not objects:
        raise PlanError("the meerk40t job has nothing to mark")
    return Job(layers=tuple(layers), tolerance_mm=tolerance_mm), objects


def outline_cuts(points):
    """A closed outline (native units: galvo units), as meerk40t's trace goes round it, as
    the line cuts of one operation with no settings of its own (the profile's defaults): for
    :func:`job_from_cuts` to check it lies in the field and give the settings to walk it
    at."""
    settings = {}
    return [LineCut(a, b, settings=settings) for a, b in zip(points, points[1:])]
