"""``galvoscan clean``: a rectangle cleaned with the spiral or the raster, in mm, mm/s, %, kHz,
for a number of passes, a time or a dose."""

import json
import math
import sys

from ..geometry.field import PlanError
from ..plan.area import plan_area_job
from .args import fail, field_mm, int_in, number_in
from .args import check_backend_needs_sim
from .jobargs import (add_job_link_options, add_job_options, board_link, frame_job, has_link,
                      job_settings_values, load_lens_table, pair_mm, progress_bar,
                      stopped_in_one_line)
from .machine import add_machine_option, profile_from


__all__ = ["add_parsers"]


def _frame_registers(profile, prr_register):
    """Vector-mode settings to walk the area's outline at (with the guide laser)."""
    pitch = max(1, round(profile.laser.spot_mm / 2 * profile.units_per_mm))
    return {"pitch": pitch, "pulses_per_point": 1, "laser_prr": prr_register,
            "jump_delay": profile.jump_delay_register(), **profile.delay_registers()}


def _passes(passes):
    """How many passes, and how the last one ends when it is not whole."""
    whole = math.floor(passes + 1e-9)
    part = passes - whole
    if part < 1e-6:
        return f"{whole} pass{'es' if whole != 1 else ''}"
    return (f"{passes:.2f} passes ({whole} whole, then the run stops {part:.0%} of the way "
            f"through the next: the rest of the area gets one pass less)")


def _cmd_clean(args):
    # Here: outputs.stream takes 0.1 s to import; `galvoscan --help` need not wait.
    from ..outputs.stream import JobStreamer
    check_backend_needs_sim(args)
    profile = profile_from(args)
    speed, power, prr = job_settings_values(args, profile)
    how = {"passes": args.passes, "duration_s": args.duration, "dose_j_cm2": args.dose}
    if all(v is None for v in how.values()):
        how["passes"] = profile.defaults.passes
    try:
        job = plan_area_job(area_mm=args.area, centre_mm=args.centre, pattern=args.pattern,
                            speed_mm_s=speed, power_percent=power, prr_khz=prr,
                            profile=profile, **how)
    except (PlanError, ValueError) as error:
        fail(error)
    say = (lambda line: print(line, file=sys.stderr)) if args.json else print
    say(f"{job.pattern} over {args.area[0]:g} x {args.area[1]:g} mm at ({args.centre[0]:g}, "
        f"{args.centre[1]:g}) mm: {job.speed_mm_s:.0f} mm/s, one pass {job.pass_s:.3f} s")
    say(f"laser {power:g} % ({job.power_w:.3g} W), {prr:g} kHz: {_passes(job.passes)}, "
        f"{job.seconds:.3f} s, mean dose {job.dose_j_cm2:.3g} J/cm²")
    for note in job.notes:
        say(f"note: {note}")
    if args.estimate or not has_link(args, profile):
        if not args.estimate:
            say("no board given (--port, --spi or --sim): nothing sent")
        if args.json:
            print(json.dumps({
                "pattern": job.pattern, "area_mm": list(args.area),
                "centre_mm": list(args.centre), "speed_mm_s": round(job.speed_mm_s, 3),
                "pass_s": round(job.pass_s, 6), "power_percent": power,
                "power_w": round(job.power_w, 4), "prr_khz": prr,
                "passes": round(job.passes, 4), "whole_passes": math.floor(job.passes + 1e-9),
                "seconds": round(job.seconds, 6),
                "dose_j_cm2": job.dose_j_cm2, "notes": list(job.notes)}))
        return 0
    registers = {**job.registers, **profile.head_registers()}
    if profile.correction_table() is not None:
        registers["cor_enable"] = 1
    pulses = max(1, math.ceil(job.seconds * registers["laser_prr"] * 100))
    with board_link(args, profile) as (client, board):
        streamer = JobStreamer(client)
        with stopped_in_one_line():
            load_lens_table(client, profile, say)
            if args.frame:
                # Here: plan.vector_job takes 0.1 s to import; `galvoscan --help` need not wait.
                from ..plan.vector_job import box_outline
                frame_job(streamer, profile, box_outline(job.bounds_mm), args.frame,
                          _frame_registers(profile, registers["laser_prr"]),
                          timeout_s=1e4 if args.sim else 60, say=say, what="area")
                return 0
            bar = progress_bar(pulses, "pulse")
            streamer.progress = lambda done: bar.update(done - bar.n)
            try:
                report = streamer.run_area(registers, pulses=pulses,
                                           timeout_s=1e5 if args.sim else job.seconds + 60,
                                           ready_timeout_s=1e4 if args.sim else 5)
            finally:
                bar.close()
    delivered = report.pulses / (registers["laser_prr"] * 100)
    say(f"done: {report.pulses} pulses ({delivered:.3f} s of emission, mean dose "
        f"{job.power_w * delivered / (args.area[0] * args.area[1] / 100):.3g} J/cm²); errors "
        f"{report.counters['errors']}")
    if args.json:
        print(json.dumps({"pattern": job.pattern, "pulses": report.pulses,
                          "seconds": delivered, "dose_j_cm2": job.dose_j_cm2,
                          "errors": report.counters["errors"],
                          "frames": len(board.frames) if board is not None else None}))
    return 0


def add_parsers(commands):
    clean = commands.add_parser(
        "clean", help="clean a rectangle with the spiral or the raster, in mm",
        description="Clean a rectangle: the spiral (or raster) fill sized to it, the speed in "
                    "mm/s, the laser in % and kHz, for a number of passes, a time or a dose. "
                    "Prints the time and dose first; with a board, arms, runs and disarms "
                    "(Ctrl-C disarms first).")
    clean.add_argument("--area", type=field_mm, required=True, metavar="WxH",
                       help="width x height in mm")
    clean.add_argument("--centre", "--center", type=pair_mm("--centre"), default=(0.0, 0.0),
                       metavar="X,Y", help="centre in field mm (default: 0,0)")
    clean.add_argument("--pattern", choices=["spiral", "raster"], default="spiral",
                       help="the fill (default: spiral)")
    add_job_options(clean)
    amount = clean.add_mutually_exclusive_group()
    amount.add_argument("--passes", type=int_in(1, 100_000, "passes"),
                        help="whole patterns (default: the profile's)")
    amount.add_argument("--duration", type=number_in("duration", 1e-4, 86_400), metavar="S",
                        help="seconds of emission")
    amount.add_argument("--dose", type=number_in("dose", 1e-6, 1e6), metavar="J_CM2",
                        help="mean areal dose in J/cm²")
    clean.add_argument("--estimate", action="store_true",
                       help="print the time and dose; send nothing")
    clean.add_argument("--frame", type=int_in(1, 100, "frame"), nargs="?", const=1,
                       default=None, metavar="N",
                       help="trace the area's outline N times with the guide laser, laser "
                            "off; cleans nothing")
    clean.add_argument("--json", action="store_true", help="print the result as JSON")
    add_job_link_options(clean)
    add_machine_option(clean)
    clean.set_defaults(run=_cmd_clean)
