"""``galvoscan mark``: a drawing (SVG, DXF, G-code or a ``.job``) marked on a board, in
millimetres.

Everything is planned and checked first (the drawing read, placed, hatched, ordered, inside
the field through the lens correction, every register value in range); only then is the link
opened. ``--sim`` runs the job on the simulated board through the same link code, and with
``--json`` reports what the scan head and the laser did.
"""

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from .. import api
from ..inputs.job_file import JobError, parse_job
from ..geometry.drawing import DrawingError
from ..geometry.fill import LineOrder
from ..geometry.field import PlanError
from ..geometry.segments import has_pixel_lines
from ..geometry.speed import path_length_mm
from ..outputs.link_budget import expected_underruns, link_segments_per_s
from ..outputs.stream import JobStreamer, StreamReport
from ..plan.vector_job import hull_outline, plan_job_file
from ..platforms.ulx3s import ULX3S_BAUD
from ..settings.fly import BELT_SPEED, ENCODER, FLY_DIRECTION, FLY_SPEED
from ..gateware.host.regmap import IOState
from ..settings.io import INPUTS, IO_SETTINGS, LEVELS, OUTPUTS
from ..settings.sky import SKY_SETTINGS
from .args import check_backend_needs_sim, fail, failed, image_file, int_in, read_text
from .jobargs import (add_job_link_options, board_link, frame_job, has_link, link_baud,
                      job_settings_values, load_lens_table, progress_bar,
                      stopped_in_one_line)
from .content import check_content_options, content_objects, part_serials
from .job_options import add_job_file_options, option_of_flag as option
from .jobfile import save_job_file, use_job_file
from .job_reports import describe_job, mark_estimate_record, sim_report
from .layers import add_wobble, add_z, describe_layers
from .machine import add_machine_option, profile_from


__all__ = ["add_parsers", "add_drawing_options", "add_plan_outputs", "planned_job",
           "fly_from_args", "io_from_args"]


def job_from_args(args):
    """The command line's (and its job file's) job settings and layers, as
    :class:`~galvoscan.api.Job` takes them; its objects are made by :func:`_plan`, each
    refused with the place (a job file's table) it came from."""
    return dict(layers=tuple(args.layers or ()), speed_mm_s=args.speed,
                power_percent=args.power, prr_khz=args.prr, passes=args.passes,
                hatch=tuple(args.hatch or ()), hatch_lines=LineOrder(args.hatch_lines),
                contour=args.contour, outline=not args.no_outline, tolerance_mm=args.tolerance,
                z_mm=args.z,
                **{setting.name: getattr(args, option(setting.flag).dest)
                   for setting in (*SKY_SETTINGS, *IO_SETTINGS)})


#: The options that say how a job flies (``--fly`` says that it does).
_FLY_OPTIONS = (ENCODER, FLY_SPEED, FLY_DIRECTION, BELT_SPEED)


def fly_from_args(args):
    """The command line's (and its job file's) :class:`~galvoscan.api.Fly`, or None (standing
    still); one line and exit for an option of the fly without ``--fly``, or two that do not
    go together."""
    values = {setting: getattr(args, setting.flag.lstrip("-").replace("-", "_"), None)
              for setting in _FLY_OPTIONS}
    if args.fly is None:
        given = [setting.flag for setting, value in values.items() if value is not None]
        if given:
            fail(f"{given[0]} is for marking on the fly: give --fly X or --fly Y too")
        return None
    try:
        return api.Fly(args.fly, counts_per_mm=values[ENCODER],
                       speed_mm_s=values[FLY_SPEED], belt_speed_mm_s=values[BELT_SPEED],
                       direction=values[FLY_DIRECTION])
    except ValueError as error:
        fail(error)


def io_from_args(args):
    """The command line's (and its job file's) :class:`~galvoscan.api.PartIO`, or None (no
    part sensor, no output); a :class:`~galvoscan.geometry.field.PlanError` for a wait's or
    an output's setting without the wait or the output."""
    return api.part_io(**{setting.name: getattr(args, option(setting.flag).dest)
                          for setting in IO_SETTINGS})


def _fly_plans(args, parts, profile, fly):
    """Each part's :class:`~galvoscan.plan.fly.FlyPlan` (``fly``: the
    :class:`~galvoscan.api.Fly`; None: not on the fly), checked: one line and exit for a part
    that would leave the field before its job is done."""
    if fly is None:
        return [None] * len(parts)
    try:
        return [api.plan_fly(fly, job, profile) for job, *_ in parts]
    except PlanError as error:
        fail(error)


def _plan(args, profile, serial=None):
    """The planned :class:`~galvoscan.plan.vector_job.VectorJob` (of layers, when ``--layer``
    gives them) and the placement, or one line and exit: the arguments mapped onto the API
    (:mod:`galvoscan.api`), which plans."""
    entries = args.entries
    if not any(entries[kind] for kind in ("drawing", "text", "code", "image")):
        fail("give a drawing (FILE) or something to make (--text, --code, --image)")
    try:
        check_content_options(args)
        job = api.Job(**job_from_args(args))
        settings = api.job_settings(job, profile)
        objects = content_objects(args, settings, profile, serial=serial)
        if args.file is not None and Path(args.file).suffix.lower() == ".job":
            if objects or args.layers:
                fail("a .job is in galvo units, already placed, at one setting: mark text, a "
                     "code or layers with a drawing (.svg, .dxf, .gcode), or alone")
            segments = parse_job(read_text(args.file, "job file"), name=args.file)
            return plan_job_file(segments, settings, profile), None, None
        drawings = []
        for entry in entries["drawing"]:
            drawing = api.Drawing(entry["file"], origin=entry["origin"],
                                  offset_mm=entry["offset"], scale=entry["scale"],
                                  rotate_deg=entry["rotate"], units=entry["units"],
                                  s_max=entry["s_max"])
            try:
                drawings.append(api.mark_object(drawing, settings, profile,
                                                tolerance_mm=args.tolerance))
            except DrawingError as error:
                where = entry.get("_where")
                raise DrawingError(f"{where}: {error}" if where else str(error)) from None
        plan = api.plan_objects(drawings + objects, job, settings, profile)
        return plan.vector_job, plan.placement, plan.drawing
    except (DrawingError, PlanError, JobError, ValueError) as error:
        fail(error)


def _link_warnings(job, baud):
    """What the link at ``baud`` leaves the board short of, a line a layer that underruns
    (:func:`~galvoscan.outputs.link_budget.expected_underruns`)."""
    return [f"warning: {f'layer {label!r}: ' if label else ''}the link at {baud:,} baud "
            f"({link_segments_per_s(baud):,.0f} segments/s) brings segments slower than the "
            f"board marks them: expect about {count:,} underruns, a mark that finds the queue "
            f"empty and waits for the next, laser off (longer jump delays, a lower speed, a "
            f"coarser --tolerance or a faster link, as the ULX3S's {ULX3S_BAUD / 1e6:g} Mbaud, "
            f"avoid them)"
            for label, count in expected_underruns(job, baud)]


def planned_job(args, *, profile=None, serial=None, quiet=False):
    """What ``mark`` and ``store`` do before any board: the profile, the job planned and
    checked (the wobble's reach too), its description said (not ``quiet``), the preview drawn.
    ``serial``: the part's number, for a ``{serial}`` field. Returns ``(job, placement,
    drawing, profile, wobbles, say)``; one line and exit on a fault."""
    profile = profile or profile_from(args)
    job, placement, drawing = _plan(args, profile, serial)
    wobbles = add_wobble(job, args, profile)
    add_z(job, args, profile)
    speed, power, prr = job_settings_values(args, profile)
    say = (lambda line: print(line, file=sys.stderr)) if getattr(args, "json", False) \
        else print
    if quiet:
        return job, placement, drawing, profile, wobbles, say
    for line in describe_job(job, profile, f"laser {power:g} % ({profile.power_w(power):.3g} W "
                                           f"of {profile.laser.max_power_w:g} W), {prr:g} kHz, "
                                           f"{args.passes or profile.defaults.passes} pass(es)"):
        say(line)
    if job.layers:
        for line in describe_layers(job, profile):
            say(line)
    if args.preview:
        _draw_preview(args, job, drawing, profile)
        say(f"wrote {args.preview}")
    return job, placement, drawing, profile, wobbles, say


def _draw_preview(args, job, drawing, profile):
    """The preview of one pass (each layer's in its colour), the title saying all passes'."""
    # Here, not at the top: the preview draws with matplotlib, whose import would slow every
    # command down by a third of a second; only --preview needs it.
    from ..plan.preview import preview
    source = args.file or getattr(args, "job_file", None)
    dots = sum(1 for p in job.paths_mm if not np.ptp(p, axis=0).any())
    passes = max(lj.settings.passes for lj in job.layers) if job.layers else \
        (args.passes or profile.defaults.passes)
    title = f"{Path(source).name if source else drawing.name}: {job.mark_mm:.1f} mm marked" + \
        (f", {dots} dots" if dots else "") + (" (a pass drawn)" if passes > 1 else "")
    groups = None
    if job.layers:
        groups = [(f"{lj.label}: {path_length_mm(lj.job.paths_mm):.1f} mm"
                   f"{f' × {lj.settings.passes} passes' if lj.settings.passes > 1 else ''}",
                   lj.colour, lj.job.paths_mm) for lj in job.layers]
    # (Pixel lines sweep their rows with the laser gated, not jumping between the runs: the
    # gaps are no jumps, and are not drawn as jumps.)
    preview(args.preview, job.paths_mm, field_mm=profile.field.size_mm,
            spot_mm=profile.laser.spot_mm, title=title, groups=groups,
            jumps=not has_pixel_lines(job.segments))


def _cmd_mark(args):
    check_backend_needs_sim(args)
    if args.save and args.file and Path(args.file).suffix.lower() == ".job":
        fail("a .job is in galvo units and marked as it is: there is no job to --save")
    use_job_file(args)
    profile = profile_from(args)
    fly = fly_from_args(args)
    try:
        if fly is not None:
            api.check_fly(fly, profile)     # (what needs no plan: refused before one)
        io = io_from_args(args)
        counter, serials = part_serials(args, profile)
    except PlanError as error:
        fail(error)
    # Every part planned (and refused, if it must be) before the link is opened: once, when
    # the parts are the same (no serial), else each with its own number.
    first = planned_job(args, profile=profile, serial=serials[0])
    parts = [first] * len(serials)
    if counter is not None and len(serials) > 1:
        bar = progress_bar(len(serials) - 1, "part")
        try:
            for k in range(1, len(serials)):
                parts[k] = planned_job(args, profile=profile, serial=serials[k], quiet=True)
                bar.update(1)
        finally:
            bar.close()
    job, placement, drawing, profile, wobbles, say = parts[0]
    flies = _fly_plans(args, parts, profile, fly)
    if io is not None:
        try:
            io.before(fly=flies[0])     # (a sensor distance off the fly, or past the count)
        except PlanError as error:
            fail(error)
    if flies[0] is not None:
        say(flies[0].line())
    if io is not None:
        say(io.line())
    if args.save:
        save_job_file(args, args.save)
        say(f"wrote {args.save} (`galvoscan mark {args.save}` marks it again" +
            (f"; --repeat {args.repeat} is the command line's, not the job's: give it again"
             if args.repeat != 1 else "") + ")")
    if counter is not None:
        say(f"serial{'s' if len(serials) > 1 else ''} {serials[0]}" +
            (f" … {serials[-1]}" if len(serials) > 1 else "") +
            f" (kept in {counter.path}; advanced when a part has been marked"
            f"{', not by a simulation' if args.sim else ''})")
    total_s = sum(part.estimate_s for part, *_ in parts)
    if len(parts) > 1:
        hours, rest = divmod(round(total_s), 3600)
        said = f"{hours} h {rest // 60:02d} min" if hours else \
            (f"{rest // 60} min {rest % 60:02d} s" if rest >= 60 else f"{total_s:.2g} s")
        say(f"{len(parts)} parts: estimated time {said} in all, the time to send each part "
            f"aside")
    if args.estimate or not has_link(args, profile):
        if not args.estimate and not args.preview:
            say("no board given (--port, --spi or --sim): nothing sent")
        if args.json:
            record = mark_estimate_record(job, args, profile, parts=len(parts),
                                          total_s=total_s, fly=flies[0])
            print(json.dumps(record))
        return 0
    if counter is not None and not args.sim:
        try:
            counter.check_writable()
        except PlanError as error:
            fail(error)
    for warning in _link_warnings(job, link_baud(args, profile)):
        say(warning)
    timeout = 1e4 if args.sim else max(60.0, 10 * job.estimate_s)
    reports = []
    pixel_lines = any(has_pixel_lines(part.segments) for part, *_ in parts)
    fly = flies[0]
    # A real encoder on the simulated board: its belt runs at the top speed the plan was
    # checked at, from before the first byte.
    belt = (fly.speed_mm_s, fly.counts_per_mm, fly.axis.lower()) \
        if fly is not None and not fly.simulated and args.sim else None
    sensor = None
    if args.sim and io is not None and io.wait_input is not None:
        # The simulated line: a part at the sensor every part's time and a little more, the
        # first a moment after the board is up.
        every_s = 1.2 * max(part.estimate_s for part, *_ in parts) + 20e-3 + \
            (io.sensor_distance_mm / flies[0].speed_mm_s if flies[0] is not None else 0.0)
        sensor = dict(input=INPUTS[io.wait_input], first_s=5e-3, every_s=every_s,
                      seen_s=min(2e-3, every_s / 2), level=LEVELS[io.wait_level])
    with board_link(args, profile, wobble=wobbles, pixel_lines=pixel_lines, belt=belt,
                    sensor=sensor) as (client, board):
        if sensor is not None:
            say(f"the simulated part sensor sees a part every {sensor['every_s'] * 1e3:.0f} "
                f"ms")
        for number, (part, *_) in enumerate(parts):
            serial = serials[number]
            fly = flies[number]
            if fly is not None and board is not None:
                try:
                    fly = fly.at_clock(board.clk_freq)
                except PlanError as error:
                    fail(f"on the simulated board's {board.clk_freq / 1e6:g} MHz clock: "
                         f"{error}")
                if number == 0 and fly.sim_period != flies[0].sim_period:
                    say(f"on the simulated board's {board.clk_freq / 1e6:g} MHz clock the "
                        f"simulated encoder counts every {fly.sim_period} clocks "
                        f"({fly.speed_mm_s:.6g} mm/s)")
            bar = progress_bar(None if args.frame else len(part.segments), "seg")
            streamer = JobStreamer(client, progress=bar.update)

            def part_done(serial=serial):
                # The part was marked whole before the job stopped: its number is taken.
                if counter is None or args.sim:
                    return ""
                try:
                    counter.advance()
                except PlanError as error:
                    return f"; {error}"
                return f"; serial {serial} was marked whole, and the counter advanced"
            try:
                with stopped_in_one_line(on_complete=part_done):
                    if number == 0:
                        load_lens_table(client, profile, say)
                    if args.frame:
                        frame_job(streamer, profile, hull_outline(part.paths_mm), args.frame,
                                  part.registers, timeout_s=timeout, say=say, what="job")
                        return 0
                    report, layer_starts = api.stream_layers(
                        streamer, part, board, timeout,
                        fly=fly.registers() if fly is not None else None, io=io,
                        fly_plan=fly)
                    reports.append(report)
            finally:
                bar.close()
            counters = report.counters
            which = (f"part {number + 1} of {len(parts)}" if len(parts) > 1 else "") + \
                (f"{', ' if len(parts) > 1 else ''}serial {serial}" if serial is not None
                 else "")
            say(f"{which + ': ' if which else ''}marked {report.segments} segments in "
                f"{report.seconds:.1f} s (host time)" +
                (": the part is done" if report.clean else "") +
                f"; {report.pulses} pulses; underruns "
                f"{counters['vec_underruns']}, stalls {counters['vec_stalls']}, rejected "
                f"{counters['vec_rejected']}, errors {counters['errors']}" +
                (f" (damaged on the link and sent again {report.resent} time(s): every "
                 f"frame landed)" if counters["errors"] else ""))
            if report.clipped:
                failed(f"the belt carried {report.clipped} point(s) past the field's edge, "
                       f"held there with the laser off: the part is not marked whole (did the "
                       f"belt run faster than {fly.speed_mm_s:g} mm/s?)" +
                       ("; the serial was not advanced" if serial is not None else ""))
            if not report.clean:
                failed("the board refused segments or the queue ran dry: the job was not marked "
                     "as planned (see the counts above)" +
                     ("; the serial was not advanced" if serial is not None else ""))
            if counter is not None and not args.sim:
                try:
                    counter.advance()       # this part is marked: its number is taken
                except PlanError as error:
                    failed(error)
        if board is not None and io is not None and io.set_output is not None and \
                io.pulse_frames:
            # The simulated line runs on (a read takes its time) until the last part's output
            # pulse has ended, so the record holds all of it.
            bit = 1 << OUTPUTS[io.set_output]
            for _ in range(round(io.output_pulse_ms * 10) + 100):
                if not IOState.from_bits(client.read("io")).outputs & bit:
                    break
        # Every part's, summed: the marks and pulses off the wires are all of them too.
        every = StreamReport.total(reports)
        counts = every.counters
        if args.json and board is not None:
            record = sim_report(board, part, placement, drawing, profile, report,
                                layer_starts=layer_starts)
            record.update(
                parts=len(parts), serials=[s for s in serials if s is not None],
                segments=every.segments,
                jumps=sum(1 for p, *_ in parts for op, *_ in p.segments if op == "jump"),
                mark_length_mm=round(sum(p.mark_mm for p, *_ in parts), 4),
                underruns=counts["vec_underruns"], stalls=counts["vec_stalls"],
                rejected=counts["vec_rejected"], errors=counts["errors"])
            if part.layers:     # each layer's own, in "layers"
                record["pulses_per_point"] = None
            if fly is not None:
                record["fly"] = dict(fly.record(), clipped=every.clipped)
            if io is not None:
                # Each change of the board's outputs off its pins: [s, outputs (bit 0:
                # output 0)]; and each part's first pulse, s (when its wait let it go).
                record["io"] = dict(
                    outputs=[[round(cycle / board.clk_freq, 6), value]
                             for cycle, value in board.io_changes])
            print(json.dumps(record))
        elif args.json:
            print(json.dumps({"segments": every.segments, "pulses": every.pulses,
                              "parts": len(parts),
                              "serials": [s for s in serials if s is not None], **counts}))
    return 0


def _job_file_path(text):
    if not text.lower().endswith(".toml"):
        raise argparse.ArgumentTypeError(f"a job file ends in .toml, not {text!r}")
    return text


def add_drawing_options(parser):
    """The drawing, its text, codes and photos, their placement, hatch, wobble and the job's
    laser and speed: what ``mark`` and ``store`` plan a job from (:mod:`.job_options`)."""
    add_job_file_options(parser)


def add_plan_outputs(group):
    """``--preview`` and ``--estimate``."""
    group.add_argument("--preview", type=image_file, metavar="PNG",
                       help="draw the marks (each the spot's width, mm), jumps and field")
    group.add_argument("--estimate", action="store_true",
                       help="print the plan and the estimated time; send or write nothing")


def add_parsers(commands):
    mark = commands.add_parser(
        "mark", help="mark a drawing (SVG, DXF, G-code or .job) in mm",
        description="Mark a drawing: read it (SVG, DXF, G-code, or a .job in galvo units), "
                    "place it in "
                    "the field, hatch closed shapes, order the paths to cut jumps, check it "
                    "against the field, then stream it to a board (--port, --spi or --sim). "
                    "Without a board: plan, --preview and --estimate only.")
    add_drawing_options(mark)
    out = mark.add_argument_group("output")
    add_plan_outputs(out)
    out.add_argument("--save", type=_job_file_path, metavar="JOB.toml",
                     help="write the job, with its settings, drawings, text, codes, photos and "
                          "layers, to a job file that `mark JOB.toml` runs again")
    out.add_argument("--frame", type=int_in(1, 100, "frame"), nargs="?", const=1,
                     default=None, metavar="N",
                     help="trace the job's outline, its convex hull, N times (default 1) with "
                          "the guide laser on and the laser off, to position the part; marks "
                          "nothing")
    out.add_argument("--json", action="store_true",
                     help="print the result as one JSON object on stdout (with --sim: the "
                          "marked points decoded off the XY2-100 wires, in field mm and in the "
                          "drawing's own, and on a board with the Z channel each one's Z)")
    add_job_link_options(mark)
    add_machine_option(mark)
    mark.set_defaults(run=_cmd_mark)
