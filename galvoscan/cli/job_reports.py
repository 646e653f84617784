"""What ``mark`` reports as JSON: the plan (``--estimate --json``, or ``--json`` with no
board) and what the simulated board's wires carried (``--sim --json``); ``standalone`` shares
the marks' frame."""

from pathlib import Path
from collections import Counter

import numpy as np

from ..gateware.points import FIELD_CENTRE
from ..geometry.field import from_galvo
from .jobargs import job_settings_values


__all__ = ["describe_job", "estimate_record", "mark_estimate_record", "sim_report", "FIELD_FRAME", "SVG_FRAME", "DXF_FRAME"]


def describe_job(job, profile, settings_line):
    """The plan as lines: segments, bounds, settings, speed, delays, time, wobble, notes."""
    pitch = job.pitch
    regs = job.registers
    lines = [
        f"{len(job.segments)} segments: {job.mark_mm:.1f} mm marked, {job.jump_mm:.1f} mm "
        f"jumped (one pass: jumps {job.jump_before_mm:.1f} mm in the drawing's order, "
        f"{job.jump_after_mm:.1f} mm as ordered)",
        f"bounds X {job.bounds_mm[0]:.2f} … {job.bounds_mm[2]:.2f} mm, "
        f"Y {job.bounds_mm[1]:.2f} … {job.bounds_mm[3]:.2f} mm in the "
        f"{profile.field.size_mm:g} mm field",
    ]
    if job.layers:
        # Each layer has its own settings: they are said a layer a line (describe_layers).
        many = len(job.layers) > 1
        lines.append(f"{len(job.layers)} layer{'s, each' if many else ','} marked as a job of "
                     f"its own; estimated time {job.estimate_s:.3f} s")
        return lines + [f"note: {note}" for note in job.notes]
    lines += [
        settings_line,
        f"speed: pitch {pitch.pitch_mm * 1000:.1f} µm ({pitch.pitch_units} units) × "
        f"{regs['laser_prr'] / 10:g} kHz / {pitch.pulses_per_point} pulse"
        f"{'s' if pitch.pulses_per_point > 1 else ''} per point = {pitch.speed_mm_s:.1f} mm/s "
        f"({pitch.error:+.2%})",
        f"jump delay {regs['jump_delay']} µs; laser on/off delay {regs['laser_on_delay']} / "
        f"{regs['laser_off_delay']} µs; mark/polygon delay {regs['mark_delay']} / "
        f"{regs['polygon_delay']} µs{' × (1 - cos φ)' if regs['polygon_scaled'] else ''}; "
        f"estimated time {job.estimate_s:.3f} s",
    ]
    if regs.get("wob_shape"):
        lines.append(f"wobble: ±{regs['wob_across'] * profile.mm_per_unit * 1000:.0f} µm across "
                     f"× ±{regs['wob_along'] * profile.mm_per_unit * 1000:.0f} µm along "
                     f"({regs['wob_across']} × {regs['wob_along']} units) at "
                     f"{regs['wob_freq']} Hz: a turn every "
                     f"{pitch.speed_mm_s / regs['wob_freq'] * 1000:.0f} µm of line")
    if "z" in regs:
        lines.append(f"Z {z_mm(regs, profile):+g} mm (the focus shifter's {regs['z']}, "
                     f"{FIELD_CENTRE} its middle)")
    lines += [f"note: {note}" for note in job.notes]
    return lines


def estimate_record(job, profile, power, prr, passes, preview):
    """The ``--estimate --json`` record (or ``--json`` with no board): the plan, in the units
    the text gives it in."""
    pitch, regs = job.pitch, job.registers
    record = {
        "segments": len(job.segments), "mark_mm": round(job.mark_mm, 3),
        "jump_mm": round(job.jump_mm, 3), "bounds_mm": [round(v, 3) for v in job.bounds_mm],
        "field_mm": profile.field.size_mm, "power_percent": power,
        "power_w": round(profile.power_w(power), 4), "prr_khz": prr, "passes": passes,
        "pitch_um": round(pitch.pitch_mm * 1000, 3), "pitch_units": pitch.pitch_units,
        "pulses_per_point": pitch.pulses_per_point, "speed_mm_s": round(pitch.speed_mm_s, 3),
        "speed_error": round(pitch.error, 6), "jump_delay_us": regs["jump_delay"],
        "laser_on_delay_us": regs["laser_on_delay"], "laser_off_delay_us": regs["laser_off_delay"],
        "mark_delay_us": regs["mark_delay"], "polygon_delay_us": regs["polygon_delay"],
        "polygon_scaled": bool(regs["polygon_scaled"]), "estimate_s": round(job.estimate_s, 6),
        "sky_s": round(getattr(job, "sky_s", 0.0), 6),
        "notes": list(job.notes), "preview": preview,
    }
    if regs.get("wob_shape"):
        record["wobble_um"] = {
            "across": round(regs["wob_across"] * profile.mm_per_unit * 1000, 1),
            "along": round(regs["wob_along"] * profile.mm_per_unit * 1000, 1),
            "hz": regs["wob_freq"]}
    if "z" in regs:
        record["z_mm"] = z_mm(regs, profile)
    return record


def z_mm(registers, profile):
    """The focus shift a job's ``z`` register stands for, mm (to the µm)."""
    return round((registers["z"] - FIELD_CENTRE) / profile.field.z_units_per_mm, 3)


def mark_estimate_record(job, args, profile, *, parts, total_s, fly=None):
    """``mark --estimate --json``: the plan (a job of layers: its totals and each layer's
    own), the parts and their time, the fill asked for; ``fly``: a job on the fly's
    :class:`~galvoscan.plan.fly.FlyPlan` (how long the part stays in the field, how long the
    job takes)."""
    speed, power, prr = job_settings_values(args, profile)
    record = estimate_record(job, profile, power, prr,
                              args.passes or profile.defaults.passes, args.preview)
    if job.layers:
        # Each layer's settings are its own: the top level keeps the totals only.
        record = {key: record[key] for key in ("segments", "mark_mm", "jump_mm",
                                                "bounds_mm", "field_mm", "estimate_s",
                                                "sky_s", "notes", "preview")}
        record["layers"] = [
            {"match": lj.label, "sets": lj.layer.changes() if lj.layer else None,
             **estimate_record(lj.job, profile, lj.settings.power_percent,
                               lj.settings.prr_khz, lj.settings.passes, None)}
            for lj in job.layers]
    record.update(parts=parts, estimate_all_parts_s=round(total_s, 6))
    record["fill"] = {
        "hatch": [[s.spacing_mm, s.angle_deg, s.step_deg, s.offset_mm]
                  for s in args.hatch or ()],
        "hatch_lines": args.hatch_lines,
        "contour": [args.contour.spacing_mm, args.contour.count] if args.contour
        else None}
    record["fly"] = fly.record() if fly is not None else None
    return record


#: The frames ``mark --sim --json`` gives the marks in.
FIELD_FRAME = "field: mm from the field's centre, X right, Y up (as the plan's bounds)"
SVG_FRAME = "the SVG's own: mm from its top-left corner, X right, Y down"
DXF_FRAME = ("the drawing's own, in mm, X right, Y up (a DXF's or G-code's; a code's from its "
             "lower-left corner)")


def _wire_speeds(marked, wire_mm, pitch_mm, unit_mm, clk_freq):
    """``(line, path)`` speeds (mm/s, None without a step) of marked points off the wires:
    consecutive points of one line, their distance on the XY2-100 wires over the time
    between their first pulses on the DB25 pins.

    Two figures: the line speed, over steps of a whole pitch (give or take the rounding of
    each axis to a galvo unit), which is what --speed sets; and the speed along the whole
    path, which is lower on short segments: a segment's last step, onto its end point, is
    shorter than a pitch and takes as long (Wan et al.'s DDA starts afresh at every vertex).
    """
    line, path = [0.0, 0.0], [0.0, 0.0]
    for i in range(1, len(marked)):
        step = float(np.hypot(*(wire_mm[i] - wire_mm[i - 1])))
        dt = (marked[i][5] - marked[i - 1][5]) / clk_freq
        if 0 < step <= pitch_mm + 1.5 * unit_mm:
            path[0] += step
            path[1] += dt
            if step >= pitch_mm - 1.5 * unit_mm:
                line[0] += step
                line[1] += dt
    return tuple(round(d / t, 2) if t else None for d, t in (line, path))


def _layer_reports(board, job, marked, wire_mm, profile, layer_starts):
    """Each layer's speed and pulses per point as planned and as measured on the wires (its
    points: those whose first pulse came after the layer's first)."""
    edges = [board.pulses[i] if i < len(board.pulses) else float("inf")
             for i in layer_starts] + [float("inf")]
    firsts = np.array([p[5] for p in marked], dtype=float)
    out = []
    for k, lj in enumerate(job.layers):
        chosen = np.flatnonzero((firsts >= edges[k]) & (firsts < edges[k + 1]))
        points = [marked[i] for i in chosen]
        speed, _ = _wire_speeds(points, wire_mm[chosen], lj.job.pitch.pitch_mm,
                                profile.mm_per_unit, board.clk_freq)
        counts = Counter(p[2] for p in points)
        out.append({"match": lj.label, "points": len(points),
                    "speed_mm_s": speed, "planned_speed_mm_s": round(lj.job.pitch.speed_mm_s, 2),
                    "pulses_per_point": counts.most_common(1)[0][0] if counts else None,
                    "planned_pulses_per_point": lj.job.pitch.pulses_per_point,
                    "power_percent": lj.settings.power_percent, "prr_khz": lj.settings.prr_khz,
                    "passes": lj.settings.passes})
    return out


def sim_report(board, job, placement, drawing, profile, report, *, layer_starts=None):
    """The ``--json`` record of a simulated job: the marked points off the wires (and, for a
    job of layers, each layer's speed and pulses per point on them; ``layer_starts``: the
    index of each layer's first pulse)."""
    points = board.points()
    marked = [p for p in points if p[2] > 0]
    xy = np.array([(p[0], p[1]) for p in marked], dtype=float).reshape(-1, 2)
    field_xy = from_galvo(xy, profile.field.size_mm)
    frames = {"marks_frame": FIELD_FRAME}
    if placement is not None:
        # The drawing's own coordinates too: an SVG's Y runs down (the reader turned it up).
        own = placement.inverse(field_xy, drawing.bounds())
        svg = Path(drawing.name).suffix.lower() == ".svg"
        frames.update({
            "drawing_marks": [[round(float(x), 4), round(float(-y if svg else y), 4)]
                              for x, y in own],
            "drawing_frame": SVG_FRAME if svg else DXF_FRAME})
    if job.layers:
        frames["layers"] = _layer_reports(board, job, marked, field_xy, profile, layer_starts)
    if getattr(board, "z_frames", None):
        # The Z channel's frame with each marked point's first frame, off the Z line's wire.
        z_at = dict(board.z_frames)
        units = [z_at.get(p[4]) for p in marked]
        frames["marks_z_units"] = units
        if profile.field.z_units_per_mm:
            frames["marks_z_mm"] = [None if z is None else
                                    round((z - FIELD_CENTRE) / profile.field.z_units_per_mm, 4)
                                    for z in units]
    line_speed, path_speed = _wire_speeds(marked, field_xy, job.pitch.pitch_mm,
                                          profile.mm_per_unit, board.clk_freq)
    prr_hz = job.registers["laser_prr"] * 100.0
    return {
        "segments": report.segments,
        "jumps": sum(1 for op, *_ in job.segments if op == "jump"),
        "marks": [[round(float(x), 4), round(float(y), 4)] for x, y in field_xy],
        **frames,
        "mark_length_mm": round(job.mark_mm, 4),
        # From the first pulse to the end of the last one's period: the time spent marking.
        "duration_s": round((board.pulses[-1] - board.pulses[0]) / board.clk_freq + 1 / prr_hz,
                            6) if board.pulses else 0.0,
        "speed_mm_s": line_speed,
        "path_speed_mm_s": path_speed,
        "pulses_per_point": job.pitch.pulses_per_point,
        "pulses": len(board.pulses),
        "underruns": report.counters["vec_underruns"],
        "stalls": report.counters["vec_stalls"],
        "rejected": report.counters["vec_rejected"],
        "errors": report.counters["errors"],
    }
