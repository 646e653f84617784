"""galvoscan's Python API: a job built from drawings, text, codes and photos, planned for a
machine (its profile), estimated, and run on a board (a real one over its link, or the
simulated one), its report returned. What a program (a meerk40t device) uses without the
command line; ``galvoscan mark`` maps its arguments onto it.

A sketch (``docs/examples/first_job.py`` runs one whole)::

    from galvoscan import api
    job = api.Job(drawings=[api.Drawing("logo.svg")],
                  texts=[api.Text("SN {serial:04d}", height_mm=3, at_mm=(-12, -10))],
                  speed_mm_s=1000, power_percent=30)
    plan = api.plan(job, serial=7)           # the default profile; or api.load_profile(path)
    print(plan.estimate_s)                   # seconds, the board's own time
    board = api.SimulatedBoard(config=api.PRESETS["default"], backend="compiled")
    report = api.run(plan, board)
    print(report.segments, report.pulses, report.marks_mm[:3])

A job's layers may be built from tables as a job file's ``[[layer]]`` gives them
(:func:`layer_from_table`, by the key table :data:`LAYER_KEYS` that ``--layer`` and job files
read too). Every value is checked where it is given, with the command line's one-line refusal
(:class:`~galvoscan.settings.schema.SettingError`, :class:`~galvoscan.geometry.field.PlanError`,
:class:`~galvoscan.geometry.drawing.DrawingError`; all are :class:`ValueError`), and the whole
job is planned and checked before any byte goes to a board.
"""

import math
from dataclasses import dataclass, field, replace
from datetime import datetime

import numpy as np

from .link.client import FTDISPITransport, HostClient, SerialTransport
from .correction.upload import upload_table
from .gateware.fields import IOKind, WobbleShape
from .gateware.points import FIELD_CENTRE
from .inputs.codes import CodeFill, CodeKind, CodeSpec
from .plan.objects import code_object
from .inputs.drawings import UNITS, load_drawing
from .geometry.fill import HatchSet, LineOrder
from .plan.fly import Fly, check_fly, plan_fly
from .plan.part_io import PartIO, first_point, part_io
from .plan.layer_keys import LAYER_KEYS, check_layer, layer_from_table
from .plan.layers import Layer, merged, plan_layers, with_file_layers
from .inputs.photo import Dither, PhotoSpec
from .plan.objects import photo_object
from .plan.pixel_lines import PHOTO_LINES, cell_units
from .geometry.field import Placement, PlanError, from_galvo
from .profile.machine import default_profile, load_profile
from .outputs.stream import JobAborted, JobStreamer, Pause, StreamReport
from .inputs.text import TextSpec, text_drawing
from .plan.objects import JobSettings, MarkObject
from .plan.sky import job_sky
from .plan.wobble import WobbleSettings, wobble_registers
from .settings.io import IO_SETTINGS
from .settings.sky import SKY_SETTINGS
from .settings.laser import (PASSES, POWER, PRR, SPEED, TOLERANCE, WOBBLE, WOBBLE_ALONG,
                             WOBBLE_HZ, Z)
from .sim.board import SimTransport, SimulatedBoard
# The bitstreams `galvoscan build --preset` builds, by name: a SimulatedBoard of one
# (config=PRESETS["default"]) is the board that bitstream makes.
from .build import PRESETS, simulated_bitstream


__all__ = ["Drawing", "Text", "Code", "Photo", "Layer", "layer_from_table", "LAYER_KEYS",
           "HatchSet", "LineOrder", "Fly", "PartIO", "part_io", "Job", "job_io",
           "Plan", "Report", "Pause", "plan", "plan_made", "run", "run_io", "simulated_board",
           "mark_objects",
           "mark_object",
           "fields",
           "job_settings", "job_wobble", "apply_wobble", "apply_z", "check_fly", "plan_fly",
           "stream_layers",
           "load_lens_table",
           "load_profile",
           "default_profile", "SimulatedBoard", "PRESETS", "HostClient", "SerialTransport",
           "FTDISPITransport",
           "PlanError", "UNITS"]


# --- what a job is made of -------------------------------------------------------------------

@dataclass(frozen=True)
class Drawing:
    """An SVG, DXF or G-code drawing, ``origin`` (``centre``, ``lower-left`` or ``page``: the
    drawing's own 0,0) placed at ``offset_mm`` from the field's centre, scaled by ``scale``
    about its centre and turned ``rotate_deg`` counter-clockwise; ``units``: the unit its
    numbers are in (``mm``, ``cm``, ``m``, ``in``, ``pt``, ``px``: :data:`UNITS`), in place
    of those it declares (None: those); ``s_max``: a G-code file's S of full power (None:
    GRBL's default $30, 1000). Each distinct S and F of a G-code file is a layer of its own,
    at that speed and power (S as a share of ``s_max``)."""
    path: str
    origin: str = "centre"
    offset_mm: tuple = (0.0, 0.0)
    scale: float = 1.0
    rotate_deg: float = 0.0
    units: str = None
    s_max: float = None


@dataclass(frozen=True)
class Text:
    """A text: ``height_mm`` the capital height, the first line's baseline at ``at_mm``
    (its left end, centre or right end by ``align``), in an outline font (``font``: a family
    or a .ttf/.otf; None: DejaVu Sans) filled, or a Hershey single-line font
    (``hershey[:NAME]``). ``{serial}``, ``{date}`` and ``{time}`` fields are filled when
    planned (:func:`fields`). ``layer``: the layer (by name) whose settings it takes."""
    text: str
    height_mm: float = 5.0
    at_mm: tuple = (0.0, 0.0)
    font: str = None
    align: str = "left"
    letter_spacing_mm: float = 0.0
    line_height: float = 1.4
    layer: str = None


@dataclass(frozen=True)
class Code:
    """A code (``kind``: ``qr``, ``datamatrix`` or ``code128``) of ``data`` (fields filled),
    ``size_mm`` wide, centred at ``at_mm``; ``ec``: QR error correction (L, M, Q, H; None:
    M); ``fill``: ``hatch`` or ``dots``; ``quiet_modules``: None, the symbology's;
    ``height_mm``: Code 128's bar height."""
    kind: str
    data: str
    size_mm: float
    at_mm: tuple = (0.0, 0.0)
    ec: str = None
    fill: str = CodeFill.HATCH.value
    quiet_modules: int = None
    height_mm: float = None
    layer: str = None


@dataclass(frozen=True)
class Photo:
    """A PNG or JPEG engraved ``width_mm`` wide, centred at ``at_mm``, as dithered scan lines
    ``line_spacing_mm`` apart (None: the profile's spot), each line one pixel line
    (``lines="pixels"``: swept at one speed, each cell lit by its own bit; its cells then the
    whole galvo units nearest that spacing) or a mark for each run of dark cells
    (``"runs"``)."""
    path: str
    width_mm: float
    at_mm: tuple = (0.0, 0.0)
    dither: str = Dither.FLOYD.value
    line_spacing_mm: float = None
    one_way: bool = False
    lines: str = PHOTO_LINES[0]
    layer: str = None

    def __post_init__(self):
        if self.lines not in PHOTO_LINES:
            raise PlanError(f"a photo's lines are {' or '.join(PHOTO_LINES)}, not "
                            f"{self.lines!r}")


@dataclass(frozen=True)
class Job:
    """A job: its drawings, texts, codes and photos, its layers
    (:class:`~galvoscan.plan.layers.Layer`), and its own settings: speed (mm/s), power (% of
    the laser's maximum), PRR (kHz) and passes (None: the profile's ``[defaults]``), the hatch
    sets (:class:`~galvoscan.geometry.fill.HatchSet`), their line order, a contour fill, whether
    outlines are marked, the chord tolerance (mm), and the wobble laid over the lines
    (``wobble_um`` across, ``wobble_along_um`` along, ``wobble_hz``; None: the profile's
    ``[wobble]``; it needs a bitstream with the wobble stage), ``fly``: marking on the fly
    (a :class:`Fly`; None: standing still; it needs a bitstream with the fly), ``z_mm``: the
    focus shift on the Z channel (None: Z left alone, unless a layer gives one; it needs the
    profile's ``[field] z_units_per_mm`` and a bitstream with the Z channel), and SkyWriting
    (``sky_mode`` 0 … 3, ``timelag_us``, ``laser_on_shift_us``, ``nprev_us``, ``npost_us``,
    ``sky_limit``; None: the profile's ``[sky]``; it needs a bitstream with pixel lines,
    :mod:`galvoscan.plan.sky`), and I/O on a production line: ``wait_input`` (each part
    waits in the board's queue for that input: ``part``, the part sensor), ``wait_level``,
    ``wait_timeout_s``, ``set_output`` (set for a PLC once the part is marked: ``done``),
    ``output_pulse_ms`` and, on the fly, ``sensor_distance_mm`` (None: the defaults of :mod:`galvoscan.settings.io`; it needs a
    bitstream with I/O in the queue, :mod:`galvoscan.plan.part_io`). The numbers are
    checked against their settings (:mod:`galvoscan.settings.laser`,
    :mod:`galvoscan.settings.sky`, :mod:`galvoscan.settings.io`) here."""
    drawings: tuple = ()
    texts: tuple = ()
    codes: tuple = ()
    photos: tuple = ()
    layers: tuple = ()
    speed_mm_s: float = None
    power_percent: float = None
    prr_khz: float = None
    passes: int = None
    hatch: tuple = ()
    hatch_lines: LineOrder = LineOrder.SERPENTINE
    contour: object = None
    outline: bool = True
    tolerance_mm: float = TOLERANCE.default
    wobble_um: float = None
    wobble_along_um: float = None
    wobble_hz: float = None
    fly: Fly = None
    z_mm: float = None
    sky_mode: int = None
    timelag_us: float = None
    laser_on_shift_us: float = None
    nprev_us: float = None
    npost_us: float = None
    sky_limit: float = None
    wait_input: str = None
    wait_level: str = None
    wait_timeout_s: float = None
    set_output: str = None
    output_pulse_ms: float = None
    sensor_distance_mm: float = None

    def __post_init__(self):
        if self.fly is not None and not isinstance(self.fly, Fly):
            raise PlanError(f"a job's fly is an api.Fly, not {self.fly!r}")
        for setting in (SPEED, POWER, PRR, PASSES, TOLERANCE, WOBBLE, WOBBLE_ALONG, WOBBLE_HZ,
                        Z, *SKY_SETTINGS, *IO_SETTINGS):
            value = getattr(self, setting.name)
            if value is not None:
                setting.check(value)
        job_io(self)                    # (a wait's setting without the wait: refused here)
        for name in ("drawings", "texts", "codes", "photos", "layers", "hatch"):
            object.__setattr__(self, name, tuple(getattr(self, name)))


def job_io(job):
    """``job``'s :class:`PartIO` (what each part waits for and sets), or None."""
    return part_io(**{setting.name: getattr(job, setting.name) for setting in IO_SETTINGS})


# --- planning --------------------------------------------------------------------------------

class _Moment:
    """The time of marking as a field: ``{date:%d.%m.%Y}`` its strftime; bare ``{date}`` the
    ISO date, ``{time}`` hours and minutes (not Python's microseconds)."""

    def __init__(self, now, plain):
        self.now, self.plain = now, plain

    def __format__(self, spec):
        return self.now.strftime(spec or self.plain)


def fields(text, *, serial=None, what="--text"):
    """``text`` with its fields filled: ``{serial}`` (``serial``), ``{date:…}``, ``{time:…}``
    (now); one line (:class:`~galvoscan.geometry.field.PlanError`, naming ``what``) for a field it
    does not know or one written wrong."""
    now = datetime.now()
    values = {"serial": serial if serial is not None else 0,
              "date": _Moment(now, "%Y-%m-%d"), "time": _Moment(now, "%H:%M")}
    known = "{serial}, {serial:05d}, {date}, {date:%d.%m.%Y}, {time}, {time:%H:%M:%S}"
    try:
        return text.replace("\\n", "\n").format(**values)
    except (KeyError, IndexError, AttributeError) as error:
        raise PlanError(f"{what} {text!r}: {{{' '.join(str(error).split()).strip(chr(39))}}} "
                        f"is not a field galvoscan knows ({known}; a brace itself as {{{{ "
                        f"or }}}})") from None
    except ValueError as error:
        raise PlanError(f"{what} {text!r}: a field written wrong ({' '.join(str(error).split())}"
                        f"); fields are {known}, a brace itself {{{{ or }}}}") from None


def job_settings(job, profile):
    """The :class:`~galvoscan.plan.objects.JobSettings` of ``job``: its own, else the
    profile's ``[defaults]``."""
    defaults = profile.defaults
    return JobSettings(
        speed_mm_s=job.speed_mm_s if job.speed_mm_s is not None else defaults.speed_mm_s,
        power_percent=job.power_percent if job.power_percent is not None
        else defaults.power_percent,
        prr_khz=job.prr_khz if job.prr_khz is not None else defaults.prr_khz,
        passes=job.passes or defaults.passes, hatch=job.hatch,
        hatch_lines=LineOrder(job.hatch_lines), contour=job.contour, outline=job.outline,
        sky=job_sky(profile, mode=job.sky_mode, timelag_us=job.timelag_us,
                    laser_on_shift_us=job.laser_on_shift_us, nprev_us=job.nprev_us,
                    npost_us=job.npost_us, limit=job.sky_limit))


def mark_object(item, settings, profile, *, serial=None, tolerance_mm=TOLERANCE.default):
    """``item`` (a :class:`Drawing`, :class:`Text`, :class:`Code` or :class:`Photo`) as the
    :class:`~galvoscan.plan.objects.MarkObject` the planner places and fills."""
    if isinstance(item, Drawing):
        placement = Placement(origin=item.origin, offset_mm=tuple(item.offset_mm),
                              scale=item.scale, rotate_deg=item.rotate_deg)
        return MarkObject(load_drawing(item.path, tolerance_mm=tolerance_mm, units=item.units,
                                       scale=item.scale, s_max=item.s_max), placement,
                          settings)
    if isinstance(item, Text):
        spec = TextSpec(fields(item.text, serial=serial), item.height_mm, font=item.font,
                        align=item.align, letter_spacing_mm=item.letter_spacing_mm,
                        line_spacing=item.line_height)
        drawing = text_drawing(spec, tolerance_mm=tolerance_mm)
        if spec.hershey:        # single strokes: the lines themselves, marked once
            fill = replace(settings, hatch=(), contour=None, outline=True)
        else:                   # glyphs filled: the job's fill, else lines half a spot apart
            fill = settings if settings.hatch or settings.contour else replace(
                settings, hatch=(HatchSet(profile.laser.spot_mm / 2),), outline=True)
        made = MarkObject(drawing, Placement(origin="page", offset_mm=tuple(item.at_mm)),
                          fill, own_fill=bool(spec.hershey))
    elif isinstance(item, Code):
        spec = CodeSpec(CodeKind(item.kind), fields(item.data, serial=serial, what="--data"),
                        item.size_mm, ec_level=item.ec, fill=CodeFill(item.fill),
                        quiet_modules=item.quiet_modules, height_mm=item.height_mm)
        made = code_object(spec, settings, centre_mm=tuple(item.at_mm),
                           spot_mm=profile.laser.spot_mm)
    elif isinstance(item, Photo):
        spacing = item.line_spacing_mm or profile.laser.spot_mm
        pixels = None
        if item.lines == "pixels":
            # The cells a pitch of whole galvo units: a pixel line steps its points at it.
            pixels = cell_units(spacing, profile.units_per_mm)
            spacing = pixels / profile.units_per_mm
        spec = PhotoSpec(item.path, item.width_mm, spacing, dither=Dither(item.dither),
                         bidirectional=not item.one_way)
        made = photo_object(spec, settings, centre_mm=tuple(item.at_mm or (0.0, 0.0)),
                            pixel_units=pixels)
    else:
        raise TypeError(f"not a drawing, text, code or photo: {item!r}")
    return replace(made, layer=item.layer) if item.layer else made


def mark_objects(job, settings, profile, *, serial=None):
    """Every object of ``job``, in the order they are marked: drawings, texts, photos,
    codes."""
    return [mark_object(item, settings, profile, serial=serial, tolerance_mm=job.tolerance_mm)
            for item in (*job.drawings, *job.texts, *job.photos, *job.codes)]


@dataclass
class Plan:
    """A planned job: ``vector_job`` (:class:`~galvoscan.plan.vector_job.VectorJob`, of
    layers when the job has them), the ``profile`` it was planned for, and its first
    object's ``placement`` and ``drawing`` (to turn marks back into the drawing's own
    coordinates); ``wobbles``: whether any of it wobbles (the board needs the wobble
    stage); ``fly``: a job on the fly's :class:`~galvoscan.plan.fly.FlyPlan` (its registers,
    and how long the part stays in the field against how long the job takes), else None;
    ``io``: what each part waits for and sets (:class:`PartIO`), else None."""
    vector_job: object
    profile: object
    placement: object
    drawing: object
    wobbles: bool = False
    fly: object = None
    io: PartIO = None

    @property
    def estimate_s(self):
        """Time to mark it, in seconds (every pass, jumps and delays)."""
        return self.vector_job.estimate_s

    @property
    def mark_mm(self):
        """Length marked, mm (one pass)."""
        return self.vector_job.mark_mm

    @property
    def segments(self):
        """``(op, x, y)`` segments in galvo units, as the board is sent them."""
        return self.vector_job.segments


def plan_objects(objects, job, settings, profile):
    """``objects`` planned as ``job``'s (its layers, then those its drawings' files set, as a
    G-code file's S and F: each a job of its own), checked against ``profile``'s machine: a
    :class:`Plan`."""
    if not objects:
        raise PlanError("a job needs something to mark: a drawing, a text, a code or a photo")
    layers = with_file_layers(job.layers, [o.drawing for o in objects])
    vector_job = merged(plan_layers(objects, layers, settings, profile))
    return Plan(vector_job, profile, objects[0].placement, objects[0].drawing)


def plan(job, profile=None, *, serial=None):
    """Plan ``job`` for ``profile`` (a :class:`~galvoscan.profile.machine.MachineProfile`;
    None: the default one): placed, filled, ordered, inside the field, every register value
    in range. ``serial``: the part's number, for ``{serial}`` fields. Raises a
    :class:`ValueError` (one line) for anything that cannot be marked."""
    profile = profile or default_profile()
    if not (job.drawings or job.texts or job.codes or job.photos):
        raise PlanError("a job needs something to mark: a drawing, a text, a code or a photo")
    settings = job_settings(job, profile)
    return plan_made(mark_objects(job, settings, profile, serial=serial), job, profile)


def plan_made(objects, job, profile):
    """``objects`` (:class:`~galvoscan.plan.objects.MarkObject` s a program made itself: a
    meerk40t device's from its cutcode) planned and checked as :func:`plan` plans a job's:
    ``job``'s layers held to the layer keys, its settings, its wobble. A :class:`Plan`; a
    :class:`ValueError` (one line) for anything that cannot be marked."""
    for number, layer in enumerate(job.layers, 1):
        # A program's Layer, held to the declarations a job file's [[layer]] is read by.
        check_layer(layer, f"layer {number} ({getattr(layer, 'match', layer)!r})")
    planned = plan_objects(objects, job, job_settings(job, profile), profile)
    planned.wobbles = apply_wobble(planned.vector_job, job_wobble(
        job.wobble_um, job.wobble_along_um, job.wobble_hz, profile), profile)
    apply_z(planned.vector_job, job.z_mm, profile)
    if job.fly is not None:
        planned.fly = plan_fly(job.fly, planned.vector_job, profile)
    planned.io = job_io(job)
    if planned.io is not None:
        planned.io.before(fly=planned.fly)  # (a sensor distance off the fly: refused now)
    return planned


# --- wobble ---------------------------------------------------------------------------------

def job_wobble(across_um, along_um, freq_hz, profile):
    """The job's :class:`~galvoscan.plan.wobble.WobbleSettings`: ``across_um`` (µm),
    ``along_um`` (µm; None: ``across_um``'s, a circle) and ``freq_hz`` given, else the
    profile's ``[wobble]``."""
    section = profile.wobble
    across = across_um if across_um is not None else section.across_um
    along = along_um if along_um is not None else \
        (across_um if across_um is not None else section.along_um)
    hz = freq_hz if freq_hz is not None else section.freq_hz
    return WobbleSettings(across_um=across, along_um=along, freq_hz=hz)


def layer_wobble(layer, base):
    """The :class:`~galvoscan.plan.wobble.WobbleSettings` of a layer (None: the rest), its
    amplitudes and frequency in place of ``base``'s where it gives them."""
    if layer is None:
        return base
    across = layer.wobble_um if layer.wobble_um is not None else base.across_um
    along = layer.wobble_along_um if layer.wobble_along_um is not None else \
        (layer.wobble_um if layer.wobble_um is not None else base.along_um)
    hz = layer.wobble_hz if layer.wobble_hz is not None else base.freq_hz
    return replace(base, across_um=across, along_um=along, freq_hz=hz)


def apply_wobble(vector_job, base, profile):
    """Each layer's ``wob_*`` registers (``base``, a
    :class:`~galvoscan.plan.wobble.WobbleSettings`, a layer's own in its place) into its
    registers, its reach checked against the field; a layer that does not wobble among ones
    that do turns it off. Returns whether anything wobbles; a
    :class:`~galvoscan.geometry.field.PlanError` (one line) for a figure past the field."""
    parts = [(lj.layer, lj.job) for lj in vector_job.layers] if vector_job.layers else \
        [(None, vector_job)]
    found = [wobble_registers(layer_wobble(layer, base), profile) for layer, _ in parts]
    if not any(found):
        return False
    for (layer, part), regs in zip(parts, found):
        if not regs:
            part.registers["wob_shape"] = WobbleShape.OFF.value
            continue
        # The figure reaches past the lines by its larger amplitude: that too must be in the
        # field (the board would clamp it at the edge).
        reach = max(regs["wob_across"], regs["wob_along"]) * profile.mm_per_unit
        half = profile.field.size_mm / 2
        xmin, ymin, xmax, ymax = part.bounds_mm
        if min(xmin, ymin) - reach < -half or max(xmax, ymax) + reach > half:
            raise PlanError(f"with the wobble's {reach * 1000:.0f} µm the job reaches past the "
                            f"field (−{half:g}…{half:g} mm): move it towards the centre or "
                            f"wobble less")
        part.registers.update(regs)
    if vector_job.layers:
        vector_job.registers.update(vector_job.layers[0].job.registers)
    return True


# --- Z ---------------------------------------------------------------------------------------

def apply_z(vector_job, z_mm, profile):
    """Each layer's ``z`` register: the job's focus shift ``z_mm`` (mm; None: none of its own),
    a layer's own in its place; once any gives one, every layer has one (0 mm, the focus
    shifter's middle, where neither does). Returns whether anything sets Z; a
    :class:`~galvoscan.geometry.field.PlanError` (one line) without a focus shifter in the
    profile, or past its range."""
    parts = [(lj.layer, lj.job) for lj in vector_job.layers] if vector_job.layers else \
        [(None, vector_job)]
    found = [layer.z_mm if layer is not None and layer.z_mm is not None else z_mm
             for layer, _ in parts]
    if all(z is None for z in found):
        return False
    for number, ((layer, part), z) in enumerate(zip(parts, found), 1):
        z = 0.0 if z is None else z
        try:
            part.registers["z"] = units = profile.z_register(z)
        except ValueError as error:
            where = f"layer {number} ({layer.match!r}): " if layer is not None and \
                layer.z_mm is not None else ""
            raise PlanError(f"{where}{error}") from None
        sent = (units - FIELD_CENTRE) / profile.field.z_units_per_mm
        note = f"Z {z:g} mm is not a whole step"
        if abs(sent - z) > 0.0005 and not any(n.startswith(note) for n in vector_job.notes):
            vector_job.notes.append(f"{note} of the focus shifter "
                                    f"({profile.field.z_units_per_mm:g} units/mm): sent as "
                                    f"{sent:+.4g} mm")
    if vector_job.layers:
        vector_job.registers.update(vector_job.layers[0].job.registers)
    return True


# --- running ---------------------------------------------------------------------------------

def load_lens_table(client, profile, say=None):
    """Write the profile's correction table into the board (at the board's node count), so
    that the job is corrected with the table it was checked against. Nothing without one."""
    table = profile.correction_table()
    if table is None:
        return
    nodes = client.read("cor_nodes")
    if nodes != table.n:
        table = table.resampled(nodes)
    if say is not None:
        say(f"loading the lens correction table ({nodes} x {nodes} nodes) into the board")
    upload_table(client, table)


def stream_layers(streamer, vector_job, board, timeout_s, *, fly=None, io=None,
                  fly_plan=None):
    """Run ``vector_job`` (its layers one after the other, each at its own settings) with
    ``streamer``: the reports summed into one, and (``board``: a simulated board) the index
    of each layer's first pulse. ``fly``: a job on the fly's registers
    (:meth:`~galvoscan.plan.fly.FlyPlan.registers`), each layer's too, the count zeroed as
    the first starts (the part is one); ``fly_plan``: its
    :class:`~galvoscan.plan.fly.FlyPlan` (the encoder's counts a mm, for a sensor distance).
    ``io``: the part's :class:`PartIO`, its steps queued before the first layer's segments
    and after the last's (a wait's time-out added to ``timeout_s``)."""
    reports, starts = [], []
    parts = [lj.job for lj in vector_job.layers] if vector_job.layers else [vector_job]
    for index, part in enumerate(parts):
        starts.append(len(board.pulses) if board is not None else None)
        segments = part.segments
        wait_s = 0.0
        if io is not None:
            flying = fly_plan or fly is not None
            at = first_point(segments)
            segments = [*(io.before(fly=flying, at=at) if index == 0 else ()), *segments,
                        *(io.after(fly=flying) if index == len(parts) - 1 else ())]
            wait_s = io.wait_s if index == 0 else 0.0
        try:
            reports.append(streamer.run_vector(segments, {**part.registers, **(fly or {})},
                                               timeout_s=timeout_s + wait_s,
                                               ready_timeout_s=timeout_s,
                                               clear_count=index == 0))
        except JobAborted as error:
            # A layer marked whole is the part done only if it is the last.
            error.complete = error.complete and index == len(parts) - 1
            raise
        if not reports[-1].clean:
            break
    return StreamReport.total(reports), starts


@dataclass
class Report:
    """What a run did: ``segments`` sent, ``pulses`` the laser fired, the board's
    ``counters`` (``vec_underruns``, ``vec_stalls``, ``vec_rejected``, ``errors``),
    ``clean`` (marked as planned), ``clipped`` (on the fly: points the belt carried past the
    field's edge, held there unmarked), and on a simulated board ``marks_mm``, the marked points
    off the XY2-100 wires in field mm (None on a real board)."""
    stream: StreamReport
    marks_mm: np.ndarray = field(default=None)

    @property
    def segments(self):
        return self.stream.segments

    @property
    def pulses(self):
        return self.stream.pulses

    @property
    def counters(self):
        return self.stream.counters

    @property
    def clean(self):
        return self.stream.clean

    @property
    def clipped(self):
        """On the fly: points the belt carried past the field's edge, held there unmarked."""
        return self.stream.clipped


def run(plan, board, *, timeout_s=None, progress=None, say=None, pause=None):
    """Mark ``plan`` on ``board``: a :class:`~galvoscan.sim.board.SimulatedBoard` (run in
    this process; ``SimulatedBoard(wobble=True)`` for a plan that ``wobbles``), or a
    :class:`~galvoscan.link.client.HostClient` of a real board's link
    (``HostClient(SerialTransport("/dev/ttyUSB1", baud=1_000_000))``). The
    profile's lens table is loaded first; the laser is disarmed at the end and on any fault
    (:class:`~galvoscan.outputs.stream.JobAborted`). ``timeout_s``: the longest the job may take
    (None: ten times the estimate, a minute at least); ``progress(n)``: called as segments
    go; ``pause``: a :class:`Pause` that another thread may set to hold the job on the board
    (the feed stopped, the queue marked out, the laser disarmed) and clear
    to let it go on. A plan on the fly needs a board with the fly (refused, nothing sent, on
    one without); its simulated encoder counts in a simulated board's own clock, else in
    the profile's ``[fly] board_clock_mhz``; a real encoder's belt is the board's
    (``SimulatedBoard.belt_moves``). Returns a :class:`Report`."""
    simulated = isinstance(board, SimulatedBoard)
    if simulated and plan.io is not None and plan.io.wait_input is not None and \
            board.part_sensor is None:
        # (Else the board would wait, armed, for a part no one brings: the wait's time-out
        # of the board's own time, half an hour of the host's on the ULX3S's simulated board.)
        raise PlanError(f"the plan waits for a part at input {plan.io.wait_input}, and the "
                        f"simulated board has no part sensor: give it one first "
                        f"(board.parts_arrive(every_s=…)); nothing was sent")
    client = HostClient(SimTransport(board)) if simulated else board
    if timeout_s is None:
        timeout_s = 1e4 if simulated else max(60.0, 10 * plan.estimate_s)
    fly = fly_plan = None
    if plan.fly is not None:
        fly_plan = plan.fly.at_clock(board.clk_freq) if simulated else plan.fly
        fly = fly_plan.registers()
    load_lens_table(client, plan.profile, say)
    streamer = JobStreamer(client, progress=progress, pause=pause)
    report, _ = stream_layers(streamer, plan.vector_job, board if simulated else None,
                              timeout_s, fly=fly, io=plan.io, fly_plan=fly_plan)
    marks = None
    if simulated:
        if plan.io is not None and plan.io.set_output is not None and plan.io.pulse_frames:
            # The board runs on until the last part's output pulse has ended (io_changes).
            board.run_for(plan.io.output_pulse_ms / 1e3 + 0.1e-3)
        points = [p for p in board.points() if p[2] > 0]
        xy = np.array([(p[0], p[1]) for p in points], dtype=float).reshape(-1, 2)
        marks = from_galvo(xy, plan.profile.field.size_mm)
    return Report(report, marks)


def simulated_board(board="icebreaker", *, preset="default", backend="auto", **options):
    """A :class:`SimulatedBoard` of ``board``'s bitstream (``"icebreaker"``, with a
    ``preset`` of :data:`PRESETS`; or ``"ulx3s"``, every feature: the fly, I/O in the queue,
    the head's status, Z), with what its memories start with (the ULX3S's correction table);
    ``options``: the board's own (``mo_lead``, ``clk_freq``, …). A job that waits for a part
    sensor needs one on it: ``board.parts_arrive(every_s=0.05)``."""
    config, contents = simulated_bitstream(board, preset=preset)
    return SimulatedBoard(config=config, backend=backend, **contents, **options)


def run_io(steps, board, *, timeout_s=None, pause=None):
    """Do I/O steps (:class:`~galvoscan.geometry.segments.IOStep` s: waits for inputs,
    outputs set) alone on ``board`` (a :class:`~galvoscan.link.client.HostClient`), between
    two jobs (meerk40t's input and output operations between its others): queued and done by
    the board's queue, the laser never armed. ``timeout_s``: how long it may take (None: the
    waits' time-outs and a minute more; a wait with none: no limit). Refused
    (:class:`~galvoscan.outputs.stream.JobRefused`, nothing sent) by a board without I/O in
    the queue; a wait that times out stops it (:class:`~galvoscan.outputs.stream.JobAborted`).
    Returns a :class:`Report`."""
    steps = list(steps)
    if timeout_s is None:
        waits = [step[1] for step in steps if step.kind == IOKind.WAIT_INPUT]
        timeout_s = math.inf if 0 in waits else 60.0 + sum(waits) / 1e3
    streamer = JobStreamer(board, pause=pause)
    return Report(streamer.run_vector(steps, {}, armed=False, timeout_s=timeout_s,
                                      ready_timeout_s=5.0))
