"""``galvoscan store``, ``flash`` and ``standalone``: a job that runs with no PC attached.

``store`` plans a drawing exactly as ``mark`` does (the same options and refusals) and writes
it as a job image; ``flash`` puts a bitstream and an image into the board's flash (the
iCEBreaker's through its FTDI, the ULX3S's through its ECP5's JTAG; pyftdi and pyspiflash, from
PyPI), reads them back and compares; ``standalone --sim`` presses the foot switch of a
simulated stand-alone board whose flash holds the image, and reports what ``mark --sim
--json`` reports, with the player's verdict.
"""

import json
import sys
from pathlib import Path

from ..flashing.icebreaker import DEFAULT_URL as ICEBREAKER_URL
from ..flashing.ulx3s import DEFAULT_URL as ULX3S_URL
from ..settings.laser import PRESS_TIMEOUT
from .args import (add_backend_option, add_setting, fail, failed, int_in, number_in, output_file,
                   read_bytes)
from .machine import add_machine_option, profile_from
from .job_reports import FIELD_FRAME
from .mark import add_drawing_options, add_plan_outputs, planned_job


__all__ = ["add_parsers"]


#: The bitstream that plays images on each board, as a person names it.
_PLAYER_BUILD = {"icebreaker": "build --preset marker", "ulx3s": "build --board ulx3s"}


def _player_config(board):
    """The configuration of the bitstream that plays images on ``board``: the iCEBreaker's
    marker preset, or the ULX3S's one bitstream (every feature)."""
    from ..build import PRESETS, board_config
    return board_config("ulx3s") if board == "ulx3s" else PRESETS["marker"]


def _player_map(board="icebreaker"):
    """The register map of the bitstream that plays images on ``board``."""
    from ..build import preset_register_map, preset_settings
    if board == "ulx3s":
        config = _player_config(board)
        settings = preset_settings(config)
        return config.register_map(resets=settings.register_resets() if settings else None)
    return preset_register_map("marker")


def _cmd_store(args):
    from ..outputs.image import ImageError, job_image, read_image
    from ..outputs.queue_words import job_segments
    from .jobfile import use_job_file
    from .. import api
    from ..plan.part_io import first_point, part_steps
    from .mark import fly_from_args, io_from_args
    use_job_file(args)
    if not args.output and not args.estimate:
        fail("give -o FILE for the image (or --estimate to plan only)")
    ulx3s = args.board == "ulx3s"
    player = _PLAYER_BUILD[args.board]
    if args.wobble and not ulx3s:
        fail("the stand-alone bitstream (build --preset marker) has no wobble stage: it does "
             "not fit beside the job player; store the job without --wobble (or for the "
             "ULX3S: --board ulx3s)")
    from ..geometry.field import PlanError
    from .content import part_serials
    if args.repeat != 1:
        fail("an image holds one part: --repeats N plays it N times a start (the same serial "
             "each time)")
    if args.fly is not None and not ulx3s:
        fail("the iCEBreaker's stand-alone bitstream (build --preset marker) does not mark on "
             "the fly: store the job for the ULX3S (--board ulx3s), or `galvoscan mark --fly` "
             "runs it from the PC")
    profile = profile_from(args)
    fly = fly_from_args(args)
    try:
        if fly is not None:
            api.check_fly(fly, profile)
        io = io_from_args(args)
        _, (serial,) = part_serials(args, profile)
    except PlanError as error:
        fail(error)
    if io is not None and not ulx3s:
        fail("the iCEBreaker's stand-alone bitstream (build --preset marker) has no I/O in the "
             "queue: store the job for the ULX3S (--board ulx3s), whose player waits for the "
             "part sensor and sets the outputs")
    job, _, _, _, _, say = planned_job(args, profile=profile, serial=serial)
    if job.sky_mode and not ulx3s:
        fail("the iCEBreaker's stand-alone job player does not take SkyWriting's run-ins and "
             "run-outs (pixel lines, which the marker build has not): store the job with "
             "--sky 0, or for the ULX3S (--board ulx3s)")
    flown = None
    if fly is not None:
        try:
            flown = api.plan_fly(fly, job, profile)
        except PlanError as error:
            fail(error)
        say(flown.line())
    if io is not None:
        say(io.line())
    if job.layers and len(job.layers) > 1:
        fail(f"the job has {len(job.layers)} layers, each at its own settings; an image holds "
             f"one set (the player sets the registers once): mark it from the PC, or store "
             f"each layer's drawing as an image of its own")
    if serial is not None:
        say(f"the image marks serial {serial} at every start (the player does not count; the "
            f"counter beside the profile is left as it is)")
    registers = dict(job.registers)
    if flown is not None:
        # The fly set up off; the queue turns it on as the part comes (or as the job starts).
        registers.update(flown.registers())
    if "head_check" not in _player_map(args.board) and registers.pop("head_check", 0):
        # (Off, it is simply not written: the marker has no head to obey.)
        fail("the profile's [galvo] head_check makes the laser obey the scan head, but the "
             "stand-alone bitstream (build --preset marker) does not read the head's STATUS "
             "line: set head_check = false to store the job")
    try:
        before, after = part_steps(io, fly=flown, queued_fly=True,
                                   at=first_point(job.segments))
    except PlanError as error:
        fail(error)
    segments = [*before, *job.segments, *after]
    try:
        image = job_image(segments, registers, repeats=args.repeats)
        # What the player's register file takes.
        read_image(image, regmap=_player_map(args.board))
    except ImageError as error:
        fail(error)
    if args.estimate:
        say(f"the image would be {len(image):,} bytes; nothing written")
        return 0
    Path(args.output).write_bytes(image)
    added = len(job_segments(segments)) - len(segments)
    steps = sum(1 for op, *_ in (*before, *after) if op == "io")
    say(f"wrote {args.output}: {len(image):,} bytes, {len(job.segments)} segments"
        f"{f' and {added} jump(s), laser off, before I/O steps and at the end' if added else ''}"
        f"{f', {steps} I/O step(s)' if steps else ''}, "
        f"{args.repeats} repeat(s) a start; put it on the board with `galvoscan flash"
        f"{' --board ulx3s' if ulx3s else ''} --job {args.output}` (a bitstream built with "
        f"`galvoscan {player}` plays it)")
    return 0


def _check_plays_jobs(bitstream):
    """Refuse a bitstream that its build record (beside it) says has no job player."""
    record = Path(bitstream).with_suffix(".build.json")
    try:
        player = json.loads(record.read_text()).get("player")
    except (OSError, ValueError):
        print(f"galvoscan: note: no build record beside {bitstream} ({record.name}): cannot "
              f"tell whether it has the job player (build --preset marker builds one)",
              file=sys.stderr)
        return
    if not player:
        fail(f"{bitstream} has no job player (its build record {record.name} says so: "
             f"build it with --preset marker); the board would ignore the start input")


def _cmd_flash(args):
    from ..flashing import FlashingError, ModelPort, flash_regions, program
    from ..outputs.image import ImageError, read_image
    from .jobargs import progress_bar
    ulx3s = args.board == "ulx3s"
    # The board's FPGA (its bitstream's check) and the board (its FTDI's URL and opening).
    if ulx3s:
        from ..flashing import ecp5 as fpga, ulx3s as board
    else:
        from ..flashing import ice40 as fpga, icebreaker as board
    bitstream = read_bytes(args.bitstream, "bitstream") if args.bitstream else None
    job = read_bytes(args.job, "job image") if args.job else None
    try:
        # (A file that is no bitstream for the board: first.)
        regions = flash_regions(bitstream, job, check=fpga.check_bitstream)
        if job is not None:
            # The player's own checks, and the marker's register file's, before any byte
            # goes out.
            read_image(job, regmap=_player_map())
        if bitstream is not None and job is not None:
            _check_plays_jobs(args.bitstream)
    except (ImageError, FlashingError) as error:
        fail(f"{args.job if isinstance(error, ImageError) else args.bitstream or ''}: "
             f"{error}".lstrip(": "))
    total = sum(len(data) for _, data in regions)
    bar = progress_bar(total, "B")
    configured = None
    try:
        if args.to:
            from ..sim.spi_flash import SPIFlashModel
            path = Path(args.to)
            model = SPIFlashModel(path.read_bytes() if path.is_file() else None,
                                  powered_down=False)
            what = program(ModelPort(model), regions, progress=bar.update, any_flash=ulx3s)
            path.write_bytes(bytes(model.memory))
        else:
            url = args.url or board.DEFAULT_URL
            if ulx3s:
                # (The ECP5 is checked against the bitstream before its configuration goes.)
                port, release = board.open_ulx3s(url, bitstream=bitstream)
            else:
                port, release = board.open_icebreaker(url)
            try:
                what = program(port, regions, progress=bar.update, any_flash=ulx3s)
            finally:
                configured = release()
    except FlashingError as error:
        failed(error)
    finally:
        bar.close()
    for address, data in regions:
        name = "job image" if address else "bitstream"
        print(f"wrote the {name} at {address:#08x}: {len(data):,} bytes, read back and "
              f"compared")
    print(f"{what}{f' (the file {args.to})' if args.to else ''}")
    if configured is False:             # (the ULX3S's ECP5 says whether it took the flash)
        if bitstream is not None:
            failed("the ECP5 did not configure from the bitstream written (DONE stays low)")
        print("galvoscan: note: the ECP5 did not configure from the flash (DONE stays low): "
              "is there a bitstream at 0? (galvoscan flash BITSTREAM writes one)",
              file=sys.stderr)
    return 0


def _cmd_standalone(args):
    from ..build import PRESETS
    from ..link.client import HostClient
    from ..gateware.fields import PlayerResult, PlayerState, PlayerStatus
    from ..outputs.image import ImageError, read_image
    from ..sim.board import SimTransport
    from .args import simulated_board
    if not args.sim:
        fail("a real stand-alone board runs on its own: press its start input (this command "
             "simulates one: give --sim)")
    from ..sim.spi_flash import FLASH_BYTES
    from ..outputs.image import JOB_OFFSET, image_in_flash
    image = read_bytes(args.flash, "job image")
    if len(image) == FLASH_BYTES:
        # A whole flash, as `flash --to` writes it: the job image is at its offset.
        image = image_in_flash(image)
    elif len(image) > FLASH_BYTES - JOB_OFFSET:
        fail(f"{args.flash}: {len(image):,} bytes do not fit the flash above the bitstream "
             f"({FLASH_BYTES - JOB_OFFSET:,} bytes from {JOB_OFFSET:#x}); give a job image, "
             f"or a whole {FLASH_BYTES // 2**20} MiB flash image as `flash --to` writes")
    try:
        planned = read_image(image, regmap=_player_map(args.board))
    except ImageError as error:
        planned = None
        print(f"galvoscan: note: {args.flash}: {error}; the board's player will refuse it",
              file=sys.stderr)
    profile = profile_from(args)
    from ..build import simulated_bitstream
    from ..gateware.fields import IOKind
    from ..gateware.limits import FRAME_US
    from ..gateware.settings import ScanSettings
    if args.board == "ulx3s":
        config, contents = simulated_bitstream("ulx3s")
    else:
        config, contents = PRESETS["marker"], {}
    board = simulated_board(args, **{**contents, "config": config,
                                     "settings": ScanSettings(mode="vector", run=False)},
                            flash=image)
    waits = [op for op, *_ in (planned.segments if planned else ())
             if getattr(op, "kind", None) == IOKind.WAIT_INPUT]
    if waits:
        # The simulated line: a part at the sensor the image waits on, every --part-every.
        every_s = args.part_every / 1e3
        board.parts_arrive(input=waits[0].index, first_s=min(5e-3, every_s / 2),
                           every_s=every_s, seen_s=min(2e-3, every_s / 2), level=waits[0].level)
        print(f"the simulated part sensor sees a part every {args.part_every:g} ms",
              file=sys.stderr)
    client = HostClient(SimTransport(board))
    presses = []
    step = 2e-3
    for _ in range(args.presses):
        board.press_start()
        waited = 0.0
        while True:
            status = PlayerStatus.from_bits(client.read("player"))
            if status.state == PlayerState.IDLE:
                break
            board.run_for(step)
            waited += step
            if waited > args.timeout:
                failed(f"the player was still busy after {args.timeout:g} s of the board's "
                       f"time (--timeout)")
        result = PlayerResult(status.result)
        presses.append(result)
        print(f"press {len(presses)}: {result.label}", file=sys.stderr if args.json else
              sys.stdout)
    # On past the image's longest output pulse (10 µs frames), so the record holds its end.
    pulses = [op[1] for op, *_ in (planned.segments if planned else ())
              if getattr(op, "kind", None) == IOKind.SET_OUTPUT]
    board.run_for(1e-3 + max(pulses, default=0) * FRAME_US * 1e-6)
    refused = PlayerStatus.from_bits(client.read("player")).refused
    report = _report(board, profile, planned, presses, refused)
    report.update({name.removeprefix("vec_"): client.read(name) for name in
                   ("vec_underruns", "vec_stalls", "vec_rejected", "errors")})
    if config.queue_io:
        # Each change of the board's outputs off its pins: [s, outputs (bit 0: output 0)].
        report["io"] = dict(outputs=[[round(cycle / board.clk_freq, 6), value]
                                     for cycle, value in board.io_changes])
    if args.json:
        print(json.dumps(report))
    else:
        print(f"{report['pulses']} pulses, {len(report['marks'])} marked points; images "
              f"refused {report['refused']}")
    board.close()
    return 0 if all(result == PlayerResult.DONE for result in presses) else 1


def _report(board, profile, planned, presses, refused):
    """What ``mark --sim --json`` reports, off the wires, and the player's verdicts."""
    import numpy as np
    from ..geometry.field import from_galvo
    points = board.points()
    marked = [p for p in points if p[2] > 0]
    xy = np.array([(p[0], p[1]) for p in marked], dtype=float).reshape(-1, 2)
    mm = from_galvo(xy, profile.field.size_mm)
    registers = planned.registers if planned else {}
    pitch_mm = registers.get("pitch", 0) * profile.mm_per_unit
    distance = seconds = 0.0
    for i in range(1, len(marked)):
        step = float(np.hypot(*(mm[i] - mm[i - 1])))
        if pitch_mm and abs(step - pitch_mm) <= 1.5 * profile.mm_per_unit:
            distance += step
            seconds += (marked[i][5] - marked[i - 1][5]) / board.clk_freq
    return {
        "presses": [result.label for result in presses],
        # The player's count of images its check refused (a write the register file refused
        # is a press's "refused", not counted here).
        "refused": int(refused),
        "marks": [[round(float(x), 4), round(float(y), 4)] for x, y in mm],
        "marks_frame": FIELD_FRAME, "field_mm": profile.field.size_mm,
        "pulses": len(board.pulses),
        "pulses_per_point": registers.get("pulses_per_point"),
        "speed_mm_s": round(distance / seconds, 2) if seconds else None,
        "segments": len(planned.segments) if planned else 0,
        "repeats": planned.repeats if planned else 0,
    }


def add_parsers(commands):
    store = commands.add_parser(
        "store", help="plan a drawing as mark does and write it as a job image",
        description="Plan a drawing exactly as `galvoscan mark` does (the same options, the "
                    "same checks) and write it as a job image for the board's flash, which "
                    "a stand-alone bitstream (build --preset marker) plays on each press of "
                    "its start input.")
    add_drawing_options(store)
    store.add_argument("-o", "--output", type=output_file, metavar="FILE",
                       help="the job image to write (.img)")
    store.add_argument("--repeats", type=int_in(1, 65535, "repeats"), default=1, metavar="N",
                       help="times the job runs on each start (default 1; with --wait-input, "
                            "N parts a start, each when the sensor sees it)")
    store.add_argument("--board", choices=list(_PLAYER_BUILD), default="icebreaker",
                       help="the board whose bitstream plays the image: icebreaker (build "
                            "--preset marker; the default) or ulx3s (every feature: the fly, "
                            "I/O, SkyWriting, wobble)")
    add_plan_outputs(store.add_argument_group("output"))
    add_machine_option(store)
    store.set_defaults(run=_cmd_store)

    flash = commands.add_parser(
        "flash", help="write a bitstream and a job image into the board's flash",
        description="Write a bitstream (at 0) and a job image (at 1 MiB) into the board's "
                    "configuration flash, read them back and compare; the FPGA then "
                    "configures from it. The iCEBreaker's flash is written through its FTDI, "
                    "the ULX3S's through its ECP5's JTAG on the FT231X. Needs no system "
                    "tools: pyftdi and pyspiflash drive the FTDI, libusb comes from PyPI.")
    flash.add_argument("bitstream", nargs="?", metavar="BITSTREAM",
                       help="the bitstream galvoscan build wrote: the iCEBreaker's .bin, the "
                            "ULX3S's .bit (default: none, the job only)")
    flash.add_argument("--job", metavar="IMAGE", help="a job image (galvoscan store)")
    flash.add_argument("--board", choices=["icebreaker", "ulx3s"], default="icebreaker",
                       help="the board (default icebreaker)")
    where = flash.add_mutually_exclusive_group()
    where.add_argument("--url",
                       help=f"pyftdi URL of the board's FTDI (default: {ICEBREAKER_URL}, on "
                            f"the ULX3S {ULX3S_URL})")
    where.add_argument("--to", type=output_file, metavar="FILE",
                       help="write a 16 MiB flash image file instead of a board (for another "
                            "programmer; a file that is one already is updated as a board's "
                            "flash would be: what is not written stays)")
    flash.set_defaults(run=_cmd_flash)

    standalone = commands.add_parser(
        "standalone", help="press the start input of a simulated stand-alone board",
        description="A simulated stand-alone board (the marker preset's bitstream, or the "
                    "ULX3S's) whose "
                    "flash holds IMAGE: press its start input, let the player check and "
                    "play the job, and report what the wires and the laser did.")
    standalone.add_argument("--sim", action="store_true", help="the simulated board")
    standalone.add_argument("--flash", required=True, metavar="IMAGE",
                            help="what its flash holds at 1 MiB (a job image, or anything), or "
                                 "a whole 16 MiB flash image as `flash --to` writes it")
    standalone.add_argument("--presses", type=int_in(1, 100, "presses"), default=1,
                            metavar="N", help="presses of the start input (default 1)")
    standalone.add_argument("--board", choices=list(_PLAYER_BUILD), default="icebreaker",
                            help="the board: icebreaker (the marker preset's bitstream; the "
                                 "default) or ulx3s (its one bitstream)")
    standalone.add_argument("--part-every", type=number_in("part every", 1, 60_000),
                            default=100.0, metavar="MS",
                            help="an image that waits for a part sensor: the simulated line "
                                 "brings a part to it every MS ms (default 100)")
    add_setting(standalone, PRESS_TIMEOUT)
    standalone.add_argument("--json", action="store_true",
                            help="print the marks off the wires, the pulses and the "
                                 "player's verdicts as JSON")
    add_backend_option(standalone)
    add_machine_option(standalone)
    standalone.set_defaults(run=_cmd_standalone)
