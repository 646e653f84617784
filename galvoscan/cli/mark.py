"""``galvoscan mark``: a drawing (SVG, DXF or a ``.job``) marked on a board, in millimetres.

Everything is planned and checked first (the drawing read, placed, hatched, ordered, inside
the field through the lens correction, every register value in range); only then is the link
opened. ``--sim`` runs the job on the simulated board through the same link code, and with
``--json`` reports what the scan head and the laser did.
"""

import argparse
import json
import math
import sys
from pathlib import Path

from ..gateware.limits import WOBBLE_MAX_HZ
from .args import check_backend_needs_sim, fail, image_file, int_in, number_in
from .jobargs import (add_job_link_options, add_job_options, board_link, frame_job, has_link,
                      job_settings_values, load_lens_table, pair_mm, progress_bar,
                      stopped_in_one_line)
from .machine import add_machine_option, profile_from


__all__ = ["add_parsers", "add_drawing_options", "add_plan_outputs", "planned_job", "FIELD_FRAME"]


def _hatch(text):
    """``SPACING[,ANGLE]``: mm, degrees."""
    parts = text.replace(" ", "").split(",")
    try:
        spacing = float(parts[0])
        angle = float(parts[1]) if len(parts) == 2 else 0.0
    except (ValueError, IndexError):
        raise argparse.ArgumentTypeError(f"--hatch must be SPACING[,ANGLE] (mm, degrees), not "
                                         f"{text!r}")
    if len(parts) > 2 or not (0.001 <= spacing <= 100) or not math.isfinite(angle):
        raise argparse.ArgumentTypeError(f"--hatch spacing must be from 0.001 to 100 mm, and "
                                         f"the angle a number of degrees, not {text!r}")
    return spacing, angle


def _wobble(args, profile):
    """The job's :class:`~galvoscan.jobs.wobble.WobbleSettings` (the command line's, else the
    profile's [wobble]) and its ``wob_*`` registers (empty: no wobble), or one line and exit."""
    from ..jobs.plan import PlanError
    from ..jobs.wobble import WobbleSettings, wobble_registers
    section = profile.wobble
    across = args.wobble if args.wobble is not None else section.across_um
    along = args.wobble_along if args.wobble_along is not None else \
        (args.wobble if args.wobble is not None else section.along_um)
    hz = args.wobble_hz if args.wobble_hz is not None else section.freq_hz
    wobble = WobbleSettings(across_um=across, along_um=along, freq_hz=hz)
    try:
        return wobble, wobble_registers(wobble, profile)
    except PlanError as error:
        fail(error)


def _plan(args, profile):
    """The planned :class:`~galvoscan.jobs.vector_job.VectorJob` and the placement, or one
    line and exit."""
    from ..job import JobError, parse_job
    from ..jobs.drawing import DrawingError, load_drawing
    from ..jobs.plan import Placement, PlanError
    from ..jobs.vector_job import JobSettings, plan_vector_job, plan_job_file
    from .args import read_text
    speed, power, prr = job_settings_values(args, profile)
    settings = JobSettings(speed_mm_s=speed, power_percent=power, prr_khz=prr,
                           passes=args.passes or profile.defaults.passes,
                           hatch_mm=args.hatch[0] if args.hatch else None,
                           hatch_deg=args.hatch[1] if args.hatch else 0.0,
                           outline=not args.no_outline)
    try:
        if Path(args.file).suffix.lower() == ".job":
            segments = parse_job(read_text(args.file, "job file"), name=args.file)
            return plan_job_file(segments, settings, profile), None, None
        placement = Placement(origin=args.origin, offset_mm=args.offset, scale=args.scale,
                              rotate_deg=args.rotate)
        drawing = load_drawing(args.file, tolerance_mm=args.tolerance)
        return plan_vector_job(drawing, placement, settings, profile), placement, drawing
    except (DrawingError, PlanError, JobError, ValueError) as error:
        fail(error)


def _describe(job, profile, settings_line):
    pitch = job.pitch
    regs = job.registers
    lines = [
        f"{len(job.segments)} segments: {job.mark_mm:.1f} mm marked, {job.jump_mm:.1f} mm "
        f"jumped (one pass: jumps {job.jump_before_mm:.1f} mm in the drawing's order, "
        f"{job.jump_after_mm:.1f} mm as ordered)",
        f"bounds X {job.bounds_mm[0]:.2f} … {job.bounds_mm[2]:.2f} mm, "
        f"Y {job.bounds_mm[1]:.2f} … {job.bounds_mm[3]:.2f} mm in the "
        f"{profile.field.size_mm:g} mm field",
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
    if "wob_shape" in regs:
        lines.append(f"wobble: ±{regs['wob_across'] * profile.mm_per_unit * 1000:.0f} µm across "
                     f"× ±{regs['wob_along'] * profile.mm_per_unit * 1000:.0f} µm along "
                     f"({regs['wob_across']} × {regs['wob_along']} units) at "
                     f"{regs['wob_freq']} Hz: a turn every "
                     f"{pitch.speed_mm_s / regs['wob_freq'] * 1000:.0f} µm of line")
    lines += [f"note: {note}" for note in job.notes]
    return lines


def _estimate_record(job, profile, power, prr, passes, preview):
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


def _link_warning(job, baud):
    from ..jobs.stream import QUEUE_DEPTH
    from ..jobs.vector_job import link_segments_per_s
    if len(job.segments) <= QUEUE_DEPTH or job.estimate_s <= 0:
        return None
    needed = len(job.segments) / job.estimate_s
    carried = link_segments_per_s(baud)
    if needed > carried:
        return (f"warning: the job needs {needed:,.0f} segments/s on average; the link at "
                f"{baud:,} baud carries {carried:,.0f}: the queue will run dry and the laser "
                f"pause (use a lower speed, a coarser --tolerance or a faster --baud build)")
    return None


#: The frames ``mark --sim --json`` gives the marks in.
FIELD_FRAME = "field: mm from the field's centre, X right, Y up (as the plan's bounds)"
_SVG_FRAME = "the SVG's own: mm from its top-left corner, X right, Y down"
_DXF_FRAME = "the DXF's own, in mm: X right, Y up"


def _sim_report(board, job, placement, drawing, profile, report):
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
            "drawing_frame": _SVG_FRAME if svg else _DXF_FRAME})
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


def planned_job(args):
    """What ``mark`` and ``store`` do before any board: the profile, the job planned and
    checked (the wobble's reach too), its description said, the preview drawn. Returns
    ``(job, placement, drawing, profile, wobble_regs, say)``; one line and exit on a fault."""
    profile = profile_from(args)
    wobble, wobble_regs = _wobble(args, profile)
    job, placement, drawing = _plan(args, profile)
    if wobble_regs:
        # The figure reaches past the lines by its larger amplitude: that too must be in the
        # field (the board would clamp it at the edge).
        reach = max(wobble_regs["wob_across"], wobble_regs["wob_along"]) * profile.mm_per_unit
        half = profile.field.size_mm / 2
        xmin, ymin, xmax, ymax = job.bounds_mm
        if min(xmin, ymin) - reach < -half or max(xmax, ymax) + reach > half:
            fail(f"with the wobble's {reach * 1000:.0f} µm the job reaches past the field "
                 f"(−{half:g}…{half:g} mm): move it towards the centre or wobble less")
        job.registers.update(wobble_regs)
    speed, power, prr = job_settings_values(args, profile)
    say = (lambda line: print(line, file=sys.stderr)) if getattr(args, "json", False) \
        else print
    for line in _describe(job, profile, f"laser {power:g} % ({profile.power_w(power):.3g} W "
                                        f"of {profile.laser.max_power_w:g} W), "
                                        f"{prr:g} kHz, {args.passes or profile.defaults.passes} pass(es)"):
        say(line)
    if args.preview:
        from ..jobs.preview import preview
        preview(args.preview, job.paths_mm, field_mm=profile.field.size_mm,
                title=f"{Path(args.file).name}: {job.mark_mm:.1f} mm marked")
        say(f"wrote {args.preview}")
    return job, placement, drawing, profile, wobble_regs, say


def _cmd_mark(args):
    from ..jobs.stream import JobStreamer
    check_backend_needs_sim(args)
    job, placement, drawing, profile, wobble_regs, say = planned_job(args)
    if args.estimate or not has_link(args, profile):
        if not args.estimate and not args.preview:
            say("no board given (--port, --spi or --sim): nothing sent")
        if args.json:
            speed, power, prr = job_settings_values(args, profile)
            print(json.dumps(_estimate_record(
                job, profile, power, prr, args.passes or profile.defaults.passes,
                args.preview)))
        return 0
    baud = args.baud or profile.link.baud
    warning = _link_warning(job, baud)
    if warning:
        say(warning)
    timeout = 1e4 if args.sim else max(60.0, 10 * job.estimate_s)
    with board_link(args, profile, wobble=bool(wobble_regs)) as (client, board):
        bar = progress_bar(None if args.frame else len(job.segments), "seg")
        streamer = JobStreamer(client, progress=bar.update)
        try:
            with stopped_in_one_line():
                load_lens_table(client, profile, say)
                if args.frame:
                    from ..jobs.vector_job import hull_outline
                    frame_job(streamer, profile, hull_outline(job.paths_mm), args.frame,
                              job.registers, timeout_s=timeout, say=say, what="job")
                    return 0
                report = streamer.run_vector(job.segments, job.registers, timeout_s=timeout,
                                             ready_timeout_s=timeout)
        finally:
            bar.close()
        counters = report.counters
        say(f"marked {report.segments} segments in {report.seconds:.1f} s (host time); "
            f"{report.pulses} pulses; underruns {counters['vec_underruns']}, stalls "
            f"{counters['vec_stalls']}, rejected {counters['vec_rejected']}, errors "
            f"{counters['errors']}")
        if args.json and board is not None:
            print(json.dumps(_sim_report(board, job, placement, drawing, profile, report)))
        elif args.json:
            print(json.dumps({"segments": report.segments, "pulses": report.pulses,
                              **report.counters}))
    if not report.clean:
        fail("the board refused frames or the queue ran dry: the job was not marked as "
             "planned (see the counts above)")
    return 0


def add_drawing_options(parser):
    """The drawing, its placement, hatch, wobble and the job's laser and speed: what ``mark``
    and ``store`` plan a job from."""
    parser.add_argument("file", metavar="FILE", help="the drawing: .svg, .dxf or .job")
    add_job_options(parser)
    parser.add_argument("--passes", type=int_in(1, 1000, "passes"), default=None,
                        metavar="N", help="times the job is marked (default: the profile's)")
    shape = parser.add_argument_group("drawing")
    shape.add_argument("--hatch", type=_hatch, metavar="SPACING[,ANGLE]",
                       help="fill closed shapes with lines SPACING mm apart at ANGLE degrees "
                            "(holes by the even-odd rule)")
    shape.add_argument("--no-outline", action="store_true",
                       help="mark the hatch only, not the outlines")
    shape.add_argument("--tolerance", type=number_in("tolerance", 0.0005, 1), default=0.01,
                       metavar="MM", help="curves as chords at most this far off "
                                          "(default: 0.01 mm)")
    wobble = parser.add_argument_group(
        "wobble (an ellipse laid over marked lines; needs a bitstream with the wobble stage; "
        "defaults: the profile's [wobble])")
    wobble.add_argument("--wobble", type=number_in("wobble", 0, 10_000), metavar="UM",
                        help="amplitude across the line (to each side), µm; a circle unless "
                             "--wobble-along; 0: no wobble")
    wobble.add_argument("--wobble-along", type=number_in("wobble-along", 0, 10_000),
                        metavar="UM", help="amplitude along the line, µm (an ellipse)")
    wobble.add_argument("--wobble-hz", type=number_in("wobble-hz", 1, WOBBLE_MAX_HZ), metavar="HZ",
                        help="turns of the figure a second (default: the profile's, 1000)")
    place = parser.add_argument_group("placement")
    place.add_argument("--origin", choices=["centre", "center", "lower-left", "page"],
                       default="centre", help="what of the drawing goes to --offset: its "
                                              "bounding box's centre (default) or lower-left "
                                              "corner, or (page) its own origin, the drawing "
                                              "keeping its own coordinates (a DXF's 0,0; an "
                                              "SVG's top-left corner)")
    place.add_argument("--offset", type=pair_mm("--offset"), default=(0.0, 0.0),
                       metavar="X,Y", help="where in the field, mm from its centre "
                                           "(default: 0,0; a negative X as --offset=-5,2)")
    place.add_argument("--scale", type=number_in("scale", 1e-3, 1e3), default=1.0, metavar="K",
                       help="size factor, about the drawing's centre (default: 1)")
    place.add_argument("--rotate", type=number_in("rotate", -360, 360), default=0.0,
                       metavar="DEG", help="counter-clockwise, degrees")


def add_plan_outputs(group):
    """``--preview`` and ``--estimate``."""
    group.add_argument("--preview", type=image_file, metavar="PNG",
                       help="draw the marks, jumps and field")
    group.add_argument("--estimate", action="store_true",
                       help="print the plan and the estimated time; send or write nothing")


def add_parsers(commands):
    mark = commands.add_parser(
        "mark", help="mark a drawing (SVG, DXF or .job) in mm",
        description="Mark a drawing: read it (SVG, DXF, or a .job in galvo units), place it in "
                    "the field, hatch closed shapes, order the paths to cut jumps, check it "
                    "against the field, then stream it to a board (--port, --spi or --sim). "
                    "Without a board: plan, --preview and --estimate only.")
    add_drawing_options(mark)
    out = mark.add_argument_group("output")
    add_plan_outputs(out)
    out.add_argument("--frame", type=int_in(1, 100, "frame"), nargs="?", const=1,
                     default=None, metavar="N",
                     help="trace the job's outline, its convex hull, N times (default 1) with "
                          "the guide laser on and the laser off, to position the part; marks "
                          "nothing")
    out.add_argument("--json", action="store_true",
                     help="print the result as JSON (with --sim: the marked points, decoded "
                          "off the XY2-100 wires, in the drawing's mm)")
    add_job_link_options(mark)
    add_machine_option(mark)
    mark.set_defaults(run=_cmd_mark)
