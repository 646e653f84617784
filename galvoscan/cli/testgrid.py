"""``galvoscan test-grid``: a material test, a square for each speed and power, labelled."""

import argparse
import json
import sys

from ..geometry.field import PlanError
from ..outputs.stream import JobStreamer
from ..plan.test_grid import axis_values, plan_test_grid
from ..settings.laser import POWER, PRR, PULSES, SPEED
from .args import (add_setting, check_backend_needs_sim, fail, failed, image_file, int_in,
                   number_in, setting_type)
from .jobargs import (add_job_link_options, board_link, has_link, load_lens_table,
                      progress_bar, stopped_in_one_line)
from .machine import add_machine_option, profile_from


__all__ = ["add_parsers"]


def _axis(what, setting):
    """``A:B:N``: N values from A to B, each within ``setting``'s range."""

    def parse(text):
        parts = text.split(":")
        try:
            if len(parts) == 1:
                low = high = float(parts[0])
                count = 1
            else:
                low, high, count = float(parts[0]), float(parts[1]), int(parts[2])
        except (ValueError, IndexError):
            raise argparse.ArgumentTypeError(f"{what} must be A:B:N (from A to B in N steps) "
                                             f"or one value, not {text!r}")
        try:
            values = axis_values(low, high, count, what)
        except PlanError as error:
            raise argparse.ArgumentTypeError(str(error))
        if not all(setting.low <= v <= setting.high for v in values):
            raise argparse.ArgumentTypeError(f"{what} must be from {setting.low:g} to "
                                             f"{setting.high:g} {setting.unit}, not {text}")
        return values
    return parse


def _cmd_test_grid(args):
    check_backend_needs_sim(args)
    profile = profile_from(args)
    prr = args.prr if args.prr is not None else profile.defaults.prr_khz
    try:
        grid = plan_test_grid(args.speeds, args.powers, profile, prr_khz=prr,
                              cell_mm=args.cell, gap_mm=args.gap,
                              label_height_mm=args.label_height,
                              label_speed_mm_s=args.label_speed,
                              label_power_percent=args.label_power,
                              hatch_mm=args.hatch, passes=args.passes,
                              pulses_per_point=args.pulses_per_point)
    except (PlanError, ValueError) as error:
        fail(error)
    cells, labels = grid.cells, grid.labels
    say = (lambda line: print(line, file=sys.stderr)) if args.json else print
    total = sum(c.job.estimate_s for c in cells) + labels.estimate_s
    pulses = grid.pulses_per_point
    say(f"{len(cells)} square{'' if len(cells) == 1 else 's'} of {args.cell:g} mm, {prr:g} kHz, "
        f"{pulses} pulse{'' if pulses == 1 else 's'} per point in every square, labels at "
        f"{args.label_speed:g} mm/s; estimated time {total:.1f} s")
    for c in cells:
        say(f"  {c.speed_mm_s:7.1f} mm/s  {c.power_percent:5.1f} %  at ({c.centre_mm[0]:g}, "
            f"{c.centre_mm[1]:g}) mm: {c.job.estimate_s:.2f} s, pitch "
            f"{c.job.pitch.pitch_mm * 1000:.1f} µm × {c.job.pitch.pulses_per_point}")
    if args.preview:
        # Here, not at the top: matplotlib's import would slow every command; only
        # --preview draws.
        from ..plan.preview import preview
        paths = [p for c in cells for p in c.job.paths_mm] + list(labels.paths_mm)
        preview(args.preview, paths, field_mm=profile.field.size_mm,
                spot_mm=profile.laser.spot_mm, title=f"test grid: {len(cells)} squares")
        say(f"wrote {args.preview}")
    for note in grid.notes:
        say(f"note: {note}")
    record = {"prr_khz": prr, "pulses_per_point": pulses, "notes": list(grid.notes),
              "estimate_s": round(total, 3),
              "cells": [{"speed_mm_s": round(c.speed_mm_s, 2), "power_percent": c.power_percent,
                         "centre_mm": list(c.centre_mm),
                         "estimate_s": round(c.job.estimate_s, 3)} for c in cells]}
    if args.estimate or not has_link(args, profile):
        if not args.estimate and not args.preview:
            say("no board given (--port, --spi or --sim): nothing sent")
        if args.json:
            print(json.dumps(record))
        return 0
    timeout = 1e4 if args.sim else max(60.0, 10 * total)
    with board_link(args, profile) as (client, board):
        bar = progress_bar(len(cells) + 1, "job")
        try:
            with stopped_in_one_line():
                load_lens_table(client, profile, say)
                streamer = JobStreamer(client)
                for entry, job in [*zip(record["cells"], (c.job for c in cells)),
                                   (None, labels)]:
                    before = len(board.pulses) if board is not None else 0
                    report = streamer.run_vector(job.segments, job.registers,
                                                 timeout_s=timeout, ready_timeout_s=timeout)
                    if not report.clean:
                        failed("the board refused frames or the queue ran dry: the grid was not "
                             "marked as planned")
                    if entry is not None:
                        entry["pulses"] = report.pulses if board is None else \
                            len(board.pulses) - before
                    bar.update(1)
        finally:
            bar.close()
    say(f"marked {len(cells)} squares and their labels")
    if args.json:
        print(json.dumps(record))
    return 0


def add_parsers(commands):
    grid = commands.add_parser(
        "test-grid", help="mark a material test: a square for each speed and power, labelled",
        description="A square for each combination of --speeds and --powers (a column a "
                    "speed, a row a power), each hatched and outlined at its own settings "
                    "and marked as a job of its own, the columns and rows labelled in a "
                    "single-line font; centred in the field. meerk40t calls it a material "
                    "test. Every square is marked at one number of pulses per point (the one "
                    "that makes the asked speeds best, or --pulses-per-point), so that the "
                    "columns differ in speed alone; each speed is the nearest the machine "
                    "makes at it (whole galvo units), its label says the speed made, and a "
                    "note says which columns are more than 2 % from the speed asked.")
    grid.add_argument("--speeds", type=_axis("--speeds", SPEED), required=True,
                      metavar="A:B:N", help=f"marking speeds, {SPEED.unit}: N from A to B "
                                            f"(or one)")
    grid.add_argument("--powers", type=_axis("--powers", POWER), required=True,
                      metavar="A:B:N", help=f"laser powers, {POWER.unit}%: N from A to B "
                                            f"(or one)")
    grid.add_argument("--prr", type=setting_type(PRR), default=None, metavar=PRR.metavar,
                      help=f"pulse repetition rate, {PRR.unit} (default: the profile's)")
    add_setting(grid, PULSES, default_text="the one that makes the asked speeds best")
    grid.add_argument("--passes", type=int_in(1, 100, "passes"), default=1, metavar="N",
                      help="times each square is marked (default 1)")
    grid.add_argument("--cell", type=number_in("cell", 0.5, 100), default=5.0, metavar="MM",
                      help="square side, mm (default 5)")
    grid.add_argument("--gap", type=number_in("gap", 0, 100), default=2.0, metavar="MM",
                      help="between squares, mm (default 2)")
    grid.add_argument("--hatch", type=number_in("hatch", 0.001, 10), default=None,
                      metavar="MM", help="hatch spacing, mm (default: half the spot)")
    grid.add_argument("--label-height", type=number_in("label height", 0.3, 20), default=1.5,
                      metavar="MM", help="label capitals, mm (default 1.5)")
    grid.add_argument("--label-speed", type=number_in("label speed", 1, 10_000),
                      default=500.0, metavar="MM_S", help="labels' speed, mm/s (default 500)")
    grid.add_argument("--label-power", type=number_in("label power", 0, 100), default=None,
                      metavar="PERCENT", help="labels' power, %% (default: the profile's)")
    grid.add_argument("--preview", type=image_file, metavar="PNG", help="plot the grid")
    grid.add_argument("--estimate", action="store_true",
                      help="print the squares and the time; send nothing")
    grid.add_argument("--json", action="store_true", help="print the result as one JSON "
                                                          "object")
    add_job_link_options(grid)
    add_machine_option(grid)
    grid.set_defaults(run=_cmd_test_grid)
