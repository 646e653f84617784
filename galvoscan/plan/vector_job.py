"""A drawing made into a vector job for one machine: placed in the field, hatched, ordered to
cut jumps, turned into galvo units, checked against the field through the lens correction,
and timed; every register value it needs worked out and checked before anything is sent.
"""

from dataclasses import dataclass, field

import numpy as np
from shapely.geometry import box, LineString, MultiPoint, Point

from ..gateware.host.regmap import BY_NAME, DEFAULT_CLOCK_HZ
from ..gateware.points import FIELD_CENTRE
from ..gateware.sources.dda import SETUP_CLOCKS
from ..geometry.field import PlanError, field_check, from_galvo, place, to_galvo
from ..geometry.fill import contour_rings, hatch_strokes, oriented
from ..geometry.order import jump_length, order_paths
from ..geometry.segments import PIXELS, has_pixel_lines
from ..geometry.speed import (choose_pitch, estimate_seconds, fixed_pitch, jump_mark_lengths,
                              settled_jumps)
from .objects import MarkObject
from .pixel_lines import pixel_line_segments
from .sky import sky_registers, sky_segments


__all__ = ["VectorJob", "plan_vector_job", "plan_objects", "check_clear", "segments_from_paths"]

#: Points a second (PRR / pulses per point) the vector mode steps without stalling at the joint
#: between two marks: the next segment's set-up must fit in a point (at the board's clock).
_STALL_FREE_POINTS_HZ = DEFAULT_CLOCK_HZ / SETUP_CLOCKS


@dataclass
class VectorJob:
    """A planned job.

    Attributes
    ----------
    segments : list of (str, int, int)
        ``("jump" | "mark", x, y)`` in galvo units, every pass.
    paths_mm : list of ndarray
        The marked paths in field mm, in marking order (one pass).
    jump_before_mm, jump_after_mm : float
        Jump length of one pass in the drawing's order and in the order chosen.
    pitch : :class:`~galvoscan.geometry.speed.Pitch`
    registers : dict
        What the board is set to for the job.
    estimate_s : float
    mark_mm, jump_mm : float
        Lengths marked and jumped, all passes.
    bounds_mm : tuple
        ``(xmin, ymin, xmax, ymax)`` of the marks in field mm.
    """
    segments: list
    paths_mm: list
    jump_before_mm: float
    jump_after_mm: float
    pitch: object
    registers: dict
    estimate_s: float
    mark_mm: float
    jump_mm: float
    bounds_mm: tuple
    notes: list = field(default_factory=list)
    layers: list = None             # a job of layers: its LayerJobs (.layers), run in turn
    sky_s: float = 0.0              # the time SkyWriting adds (its runs and corner jumps), s
    sky_mode: int = 0               # SkyWriting's mode (a job of layers: the highest of theirs)


def segments_from_paths(paths_units):
    """Jump to each path's first point, mark along the rest."""
    segments = []
    for path in paths_units:
        x0, y0 = (int(v) for v in path[0])
        segments.append(("jump", x0, y0))
        for x, y in path[1:]:
            segments.append(("mark", int(x), int(y)))
    return segments


def _check_corrected(segments, table):
    """Refuse a job that the correction table would push past the galvo range (the board
    would clamp it, and mark it out of shape)."""
    if table is None:
        return
    xy = np.array([(x, y) for op, x, y in segments if op != PIXELS], dtype=float)
    cx, cy = table.apply(xy[:, 0], xy[:, 1])
    low = min(np.min(cx), np.min(cy))
    high = max(np.max(cx), np.max(cy))
    if low < 0 or high > BY_NAME["vec_x"].high:
        raise PlanError(f"through the lens correction the job reaches galvo position "
                        f"{int(low) if low < 0 else int(high)}, outside 0 … 65535: move it "
                        f"towards the field centre or make it smaller")


def _machine_settings(settings, profile, *, pitch_units=None):
    """``(prr_register, prr_hz, pitch)`` for the job's speed and PRR on this machine
    (``pitch_units``: at that pitch, a photo's pixel lines', only the pulses per point
    chosen)."""
    prr_register = profile.prr_register(settings.prr_khz)     # refuses a PRR the laser lacks
    prr_hz = prr_register * 100.0
    if settings.speed_mm_s > profile.galvo.max_speed_mm_s:
        raise PlanError(f"{settings.speed_mm_s:g} mm/s is faster than the machine's "
                        f"{profile.galvo.max_speed_mm_s:g} mm/s ([galvo] max_speed_mm_s)")
    if pitch_units is not None:
        return prr_register, prr_hz, fixed_pitch(
            settings.speed_mm_s, prr_hz, profile.units_per_mm, pitch_units,
            pulses_per_point=settings.pulses_per_point)
    # A pitch of at most half the spot keeps the marked points overlapping.
    pitch = choose_pitch(settings.speed_mm_s, prr_hz, profile.units_per_mm,
                         max_pitch_mm=profile.laser.spot_mm / 2,
                         pulses_per_point=settings.pulses_per_point, strict="range")
    return prr_register, prr_hz, pitch


def _finish(segments, paths_mm, before, after, settings, profile, notes, *, settle=True,
            pitch_units=None):
    """Registers, timing and bounds of a job's segments (``settle``: each jump held as long
    as its length needs, :func:`~galvoscan.geometry.speed.settled_jumps`; ``pitch_units``:
    the pitch of its pixel lines)."""
    prr_register, prr_hz, pitch = _machine_settings(settings, profile, pitch_units=pitch_units)
    units_per_mm = profile.units_per_mm
    table = profile.correction_table()
    sky = settings.sky if settings.sky is not None and settings.sky.on else None
    plain = segments
    if sky is not None:
        dwell_us = pitch.pulses_per_point / prr_hz * 1e6
        sky_plan = sky_segments(segments, sky, pitch_units=pitch.pitch_units, dwell_us=dwell_us)
        segments = sky_plan.segments
    _check_corrected(segments, table)
    notes = list(notes)
    jump_delay = dict(settings.delays_us).get("jump_delay")        # a layer's own
    if sky is not None:
        # The time SkyWriting adds: the job's estimate against the same job without it.
        timing = dict(pitch_units=pitch.pitch_units, pulses_per_point=pitch.pulses_per_point,
                      prr_hz=prr_hz)
        if jump_delay is None:
            plain, plain_delay, _, _ = settled_jumps(plain, profile, units_per_mm, settle=settle)
        plain_s = estimate_seconds(plain, jump_delay_us=plain_delay if jump_delay is None
                                   else jump_delay, **timing)
    if jump_delay is None:
        segments, jump_delay, extra, longest = settled_jumps(segments, profile, units_per_mm,
                                                             settle=settle)
        if extra:
            notes.append(f"each jump held as long as its length needs: a {jump_delay} µs jump "
                         f"delay, held again after the longer jumps ({extra:,} holds; every "
                         f"jump held for the longest would wait {longest:,} µs)")
    registers = {
        "pitch": pitch.pitch_units,
        "pulses_per_point": pitch.pulses_per_point,
        "jump_delay": jump_delay,
        "laser_prr": prr_register,
        "laser_power": profile.power_register(settings.power_percent),
        **profile.delay_registers(),
        **profile.head_registers(),
    }
    if sky is None and has_pixel_lines(segments):
        # A pixel line is timed by its scan offset: the laser follows each point's bit, at
        # once, and the line's run-out ends it.
        moved = [name for name in ("laser_on_delay", "laser_off_delay", "mark_delay")
                 if registers.get(name)]
        registers.update(laser_on_delay=0, laser_off_delay=0, mark_delay=0)
        if moved:
            notes.append(f"pixel lines: {', '.join(moved)} 0 (the scan offset and the run-in "
                         f"and run-out stand for them)")
    registers.update(dict(settings.delays_us))
    if sky is not None:
        notes += sky_registers(sky, registers, dwell_us=dwell_us,
                               out_points=sky_plan.out_points)
    if table is not None:
        registers["cor_enable"] = 1
    estimate = estimate_seconds(segments, pitch_units=pitch.pitch_units,
                                pulses_per_point=pitch.pulses_per_point, prr_hz=prr_hz,
                                jump_delay_us=jump_delay)
    mark_mm, jump_mm = jump_mark_lengths(segments, units_per_mm, pitch_units=pitch.pitch_units)
    if abs(pitch.error) > 0.02:
        notes.append(f"{settings.speed_mm_s:g} mm/s falls between the speeds whole galvo "
                     f"units and pulses make at {prr_hz / 1e3:g} kHz: marked at the nearest, "
                     f"{pitch.speed_mm_s:.1f} mm/s ({pitch.error:+.1%})")
    if prr_hz / pitch.pulses_per_point > _STALL_FREE_POINTS_HZ:
        joints = sum(1 for a, b in zip(segments, segments[1:]) if a[0] == b[0] == "mark")
        notes.append(f"a point every {pitch.pulses_per_point / prr_hz * 1e6:.0f} µs is faster "
                     f"than the board sets up a segment ({SETUP_CLOCKS} clocks at "
                     f"{DEFAULT_CLOCK_HZ / 1e6:g} MHz): expect about {joints} stalls, a "
                     f"10 µs pause with the laser off at each joint between two marks (a "
                     f"lower PRR, or more pulses per point, avoids them)")
    sky_s = 0.0
    if sky is not None:
        sky_s = estimate - plain_s
        def points(n):
            return f"{n} point{'' if n == 1 else 's'}"
        notes.append(f"{sky.said()}: run-ins of {points(sky_plan.in_points)} "
                     f"({sky_plan.in_points * dwell_us:g} µs), run-outs of "
                     f"{points(sky_plan.out_points)} ({sky_plan.out_points * dwell_us:g} µs), "
                     f"laser off"
                     + (f"; {sky_plan.corners} corner{'' if sky_plan.corners == 1 else 's'} "
                        f"taken apart" if sky.mode > 1 else "")
                     + f"; laser on {registers['laser_on_delay']} µs and off "
                     f"{registers['laser_off_delay']} µs after the set point crosses a mark's "
                     + (f"ends; adds {sky_s * 1e3:.2f} ms" if sky_s < 1 else
                        f"ends; adds {sky_s:.3f} s"))
    marks = np.concatenate(paths_mm)
    bounds = (*marks.min(axis=0), *marks.max(axis=0))
    return VectorJob(segments=segments, paths_mm=paths_mm, jump_before_mm=before,
                     jump_after_mm=after, pitch=pitch, registers=registers,
                     estimate_s=estimate, mark_mm=mark_mm, jump_mm=jump_mm,
                     bounds_mm=tuple(float(v) for v in bounds), notes=list(notes),
                     sky_s=sky_s, sky_mode=sky.mode if sky is not None else 0)


def plan_job_file(segments, settings, profile):
    """A ``.job`` (galvo units, already placed and ordered) for this machine."""
    paths, current = [], None
    here = (FIELD_CENTRE, FIELD_CENTRE)
    for op, x, y in segments:
        if op == "mark":
            if current is None:
                current = [here]
                paths.append(current)
            current.append((x, y))
        else:
            current = None
        here = (x, y)
    paths_mm = [from_galvo(np.array(p, dtype=float), profile.field.size_mm) for p in paths]
    if not paths_mm:
        raise PlanError("the job has no mark segments")
    _, jumps = jump_mark_lengths(list(segments), profile.units_per_mm)    # one pass, as it is
    return _finish(list(segments) * settings.passes, paths_mm, jumps, jumps, settings, profile,
                   ["a .job is in galvo units: no placement, hatch or reordering"], settle=False)


def plan_vector_job(drawing, placement, settings, profile):
    """Plan ``drawing`` for ``profile``'s machine; raises
    :class:`~galvoscan.geometry.field.PlanError` (one line) for anything that cannot run, before
    any link is opened."""
    return plan_objects([MarkObject(drawing, placement, settings)], settings, profile)


def plan_objects(objects, settings, profile):
    """Plan :class:`MarkObject` s, marked one after the other on each pass, for ``profile``'s
    machine at ``settings``' speed, power, PRR and passes."""
    field_mm = profile.field.size_mm
    cells = {o.pixels.cell_units for o in objects if o.pixels is not None}
    if len(cells) > 1:
        raise PlanError("photos of different cell sizes in one layer: their pixel lines need "
                        "one pitch (one --line-spacing, or a layer each)")
    pitch_units = cells.pop() if cells else None
    # The speed and PRR first: the cheap checks.
    _, _, pitch = _machine_settings(settings, profile, pitch_units=pitch_units)
    for o in objects:
        for hatch_set in o.fill.hatch:
            if hatch_set.spacing_mm < profile.mm_per_unit:
                raise PlanError(f"hatch spacing {hatch_set.spacing_mm:g} mm is finer than a "
                                f"galvo unit ({profile.mm_per_unit * 1000:.2f} µm on this "
                                f"field): the lines would fall on one another")
    placed = [place(o.drawing, o.placement) for o in objects]
    _check_clear(objects, placed)
    # A pass's fills differ from the last only where a hatch set turns a step each pass.
    turning = any(s.step_deg % 360 for o in objects for s in o.fill.hatch)
    planned, here = [], np.zeros(2)
    for index in range(settings.passes if turning else 1):
        for o, drawing in zip(objects, placed):
            paths, before, after = _plan_pass(drawing, o.fill, index, here,
                                              keep_order=o.keep_order)
            if paths:
                here = paths[-1][-1]
            elif index == 0 and len(objects) > 1:
                raise PlanError(f"{o.drawing.name}: nothing to mark at its settings (no "
                                f"outline, and no closed shape to fill)")
            planned.append((paths, before, after, o))
    ordered = [path for paths, *_ in planned for path in paths]
    if not ordered:
        raise PlanError(f"{' and '.join(o.drawing.name for o in objects)}: nothing to mark "
                        f"(no outline, and no closed shape to fill)")
    field_check(ordered, field_mm)
    segments, line_notes = [], []
    for k, (paths, before, after, o) in enumerate(planned):
        if o.pixels is not None and paths:
            lines, line_notes = pixel_line_segments(
                o.pixels, o.placement.offset_mm, field_mm=field_mm,
                speed_mm_s=pitch.speed_mm_s, tracking_delay_us=profile.galvo.tracking_delay_us)
            segments += lines
            # Its jumps are the lines' (from one line's end to the next's start).
            jumps = jump_mark_lengths(lines, profile.units_per_mm)[1]
            planned[k] = (paths, jumps, jumps, o)
        else:
            segments += segments_from_paths([to_galvo(path, field_mm) for path in paths])
    if not turning:
        segments *= settings.passes
    one_pass = planned[:len(objects)]
    before, after = sum(p[1] for p in one_pass), sum(p[2] for p in one_pass)
    notes = [note for o in objects for note in (*o.drawing.notes, *o.drawing.skipped)]
    return _finish(segments, ordered, before, after, settings, profile, notes + line_notes,
                   pitch_units=pitch_units)


def check_clear(objects):
    """Refuse an object that reaches into another's keep-clear zone (a code's quiet zone)."""
    if any(o.keep_clear_mm for o in objects):
        _check_clear(objects, [place(o.drawing, o.placement) for o in objects])


def _check_clear(objects, placed):
    for i, (o, drawing) in enumerate(zip(objects, placed)):
        if not o.keep_clear_mm:
            continue
        xmin, ymin, xmax, ymax = drawing.bounds()
        m = o.keep_clear_mm
        zone = box(xmin - m, ymin - m, xmax + m, ymax + m)
        for j, other in enumerate(placed):
            if j == i:
                continue
            if any(zone.intersects(LineString(p) if len(p) > 1 and np.ptp(p, axis=0).any()
                                   else Point(p[0])) for p in other.paths):
                raise PlanError(f"{objects[j].drawing.name} reaches into the quiet zone of the "
                                f"{o.drawing.name} ({m:.2f} mm around it): place them apart")


def _plan_pass(placed, settings, index, start=(0.0, 0.0), *, keep_order=False):
    """``(paths, jumps before, jumps after)`` of pass ``index``: the outlines and contour rings
    ordered to cut the jumps from ``start`` (``keep_order``: in the drawing's order), then
    each hatch set's strokes in their own order (the whole set taken from whichever end is
    nearer)."""
    free, closed = [], []
    if settings.outline:
        free += [np.asarray(p) for p in placed.paths]
        closed += list(placed.closed)
    if settings.contour is not None:
        rings = contour_rings(placed.paths, placed.closed, settings.contour)
        free += rings
        closed += [True] * len(rings)
    blocks = [hatch_strokes(placed.paths, placed.closed, hatch_set, pass_index=index,
                            order=settings.hatch_lines) for hatch_set in settings.hatch]
    blocks = [block for block in blocks if block]
    ordered = list(free) if keep_order else order_paths(free, closed, start)[0]
    in_order = list(free)
    for block in blocks:
        here = ordered[-1][-1] if ordered else np.asarray(start, dtype=float)
        block = oriented(block, here, settings.hatch_lines)
        ordered += block
        in_order += block
    return ordered, jump_length(in_order, start), jump_length(ordered, start)


def box_outline(bounds_mm):
    """A rectangle ``(xmin, ymin, xmax, ymax)`` as a closed outline, mm."""
    xmin, ymin, xmax, ymax = bounds_mm
    return np.array([(xmin, ymin), (xmax, ymin), (xmax, ymax), (xmin, ymax), (xmin, ymin)])


def hull_outline(paths_mm):
    """The convex hull of every point of ``paths_mm`` as a closed outline, mm: what a part's
    fixture must clear (a line's hull is the line there and back, a dot's the dot)."""
    hull = MultiPoint(np.concatenate([np.asarray(p, dtype=float) for p in paths_mm])).convex_hull
    if hull.geom_type == "Polygon":
        return np.asarray(hull.exterior.coords)
    points = np.asarray(hull.coords)
    return np.vstack([points, points[::-1][1:]]) if len(points) > 1 else np.vstack([points] * 2)


def frame_segments(outline_mm, field_mm, times):
    """A closed outline (mm, :func:`hull_outline` or :func:`box_outline`) traced ``times``
    times (for the guide laser), in galvo units."""
    units = to_galvo(np.asarray(outline_mm, dtype=float), field_mm)
    return segments_from_paths([units]) * times
