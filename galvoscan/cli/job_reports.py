"""What ``mark`` reports as JSON: the plan (``--estimate --json``, or ``--json`` with no
board) and what the simulated board's wires carried (``--sim --json``); ``standalone`` shares
the marks' frame."""

from pathlib import Path


__all__ = ["estimate_record", "sim_report", "FIELD_FRAME", "SVG_FRAME", "DXF_FRAME"]


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
        "notes": list(job.notes), "preview": preview,
    }
    if "wob_shape" in regs:
        record["wobble_um"] = {
            "across": round(regs["wob_across"] * profile.mm_per_unit * 1000, 1),
            "along": round(regs["wob_along"] * profile.mm_per_unit * 1000, 1),
            "hz": regs["wob_freq"]}
    return record


#: The frames ``mark --sim --json`` gives the marks in.
FIELD_FRAME = "field: mm from the field's centre, X right, Y up (as the plan's bounds)"
SVG_FRAME = "the SVG's own: mm from its top-left corner, X right, Y down"
DXF_FRAME = ("the drawing's own, in mm, X right, Y up (a DXF's; a code's from its lower-left "
             "corner)")


def sim_report(board, job, placement, drawing, profile, report):
    """The ``--json`` record of a simulated job: the marked points off the wires."""
    import numpy as np
    from ..jobs.plan import from_galvo
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
    # The speed on the wires: consecutive marked points of one line, their distance on the
    # XY2-100 wires over the time between their first pulses on the DB25 pins.
    pitch_mm = job.pitch.pitch_mm
    # Two figures: the line speed, over steps of a whole pitch (give or take the rounding of
    # each axis to a galvo unit), which is what --speed sets; and the speed along the whole
    # path, which is lower on short segments: a segment's last step, onto its end point, is
    # shorter than a pitch and takes as long (Wan et al.'s DDA starts afresh at every vertex).
    unit_mm = profile.mm_per_unit
    line = [0.0, 0.0]
    path = [0.0, 0.0]
    wire_mm = from_galvo(xy, profile.field.size_mm)
    for i in range(1, len(marked)):
        step = float(np.hypot(*(wire_mm[i] - wire_mm[i - 1])))
        dt = (marked[i][5] - marked[i - 1][5]) / board.clk_freq
        if 0 < step <= pitch_mm + 1.5 * unit_mm:
            path[0] += step
            path[1] += dt
            if step >= pitch_mm - 1.5 * unit_mm:
                line[0] += step
                line[1] += dt
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
        "speed_mm_s": round(line[0] / line[1], 2) if line[1] else None,
        "path_speed_mm_s": round(path[0] / path[1], 2) if path[1] else None,
        "pulses_per_point": job.pitch.pulses_per_point,
        "pulses": len(board.pulses),
        "underruns": report.counters["vec_underruns"],
        "stalls": report.counters["vec_stalls"],
        "rejected": report.counters["vec_rejected"],
        "errors": report.counters["errors"],
    }
