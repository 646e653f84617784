"""``galvoscan rom`` and ``galvoscan sim``: the spiral tables, and the system top simulated from
its pins (the spiral, or a vector job sent through the SPI link)."""

import json
import sys
import time

from tqdm import tqdm

from ..correction.files import load_table, TableFileError
from ..gateware.host.regmap import BY_NAME
from ..gateware.settings import ScanSettings
from ..gateware.sources.spiral import PARK_FRAMES
from ..inputs.job_file import JobError, parse_job
from .args import (INTERPOLATIONS, add_backend_option, add_table_options, fail, failed, image_file,
                   int_in, number_in, output_file, prr_khz, read_text, register_int, settings_from,
                   table_from)


__all__ = ["add_parsers"]


# --- rom -----------------------------------------------------------------------------------------

def _cmd_rom(args):
    table = table_from(args)
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

def _correction(args):
    """The correction table a simulation starts with: a file's, or the identity."""
    if not args.correction:
        return "identity"
    # Here: gateware.top takes 0.3 s to import; `galvoscan --help` need not wait.
    from ..gateware.top import DEFAULT_CORRECTION_NODES
    try:
        return load_table(args.correction, nodes=DEFAULT_CORRECTION_NODES)
    except TableFileError as error:
        fail(error)


def _marking_speed(points, pitch):
    """Mean marking speed over chains of marked points one pitch or less apart, galvo units per
    frame: from the arrival of each chain's second point to that of its last (the first
    point's hold includes the wait after a jump)."""
    distance = held = 0
    chain_start = True
    for a, b in zip(points, points[1:]):
        step = ((a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2) ** 0.5
        if a[2] and b[2] and 0 < step <= pitch * 1.001:
            if not chain_start:
                distance += step
                held += a[3]
            chain_start = False
        else:
            chain_start = True
    return distance / held if held else None


def _sim_vector(args):

    if args.points is not None:
        fail("--points is for the spiral; a vector job is as long as its file")
    try:
        job = parse_job(read_text(args.job, "job"), name=args.job)
    except JobError as error:
        fail(error)
    correction = _correction(args)
    # The simulator only once every input is known good.
    from ..sim.plots import plot_job
    from ..sim.vector import replay_job
    start = time.monotonic()
    with _FrameBar() as bar:
        try:
            result = replay_job(job, correction=correction, prr_hz=args.prr * 1e3,
                                pulses_per_point=args.pulses_per_point, pitch=args.pitch,
                                jump_delay=args.jump_delay, vcd=args.vcd,
                                progress=bar.update, backend=_backend(args), say=_say)
        except ValueError as error:
            fail(error)
    seconds = time.monotonic() - (bar.started or start)
    marked = result.marked()
    counts = sorted({p[2] for p in marked})
    mm_per_unit = args.lens_field / 65536
    units_per_frame = _marking_speed(result.points, args.pitch)
    speed = None if units_per_frame is None else units_per_frame * mm_per_unit / 10e-6
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
        plot_job(args.png, result, title=f"{args.job}: {len(marked)} marked points, "
                                         f"{args.pulses_per_point} pulse(s) each at "
                                         f"{args.prr:g} kHz")
    summary = {
        "segments": len(job), "frames": len(result.frames), "points": len(result.points),
        "marked_points": len(marked), "pulses_per_marked_point": counts,
        "expected_pulses_per_point": args.pulses_per_point,
        "line_speed_mm_s": None if speed is None else round(speed, 2),
        "expected_line_speed_mm_s": round(args.pitch * mm_per_unit * args.prr * 1e3
                                          / args.pulses_per_point, 2),
        "sim_seconds": round(seconds, 2), "csv": args.csv, "points_csv": args.points_csv,
        "png": args.png, "vcd": args.vcd,
    }
    if args.json:
        print(json.dumps(summary, indent=2))
        return 0
    print(f"{len(job)} segments: {len(result.frames)} frames, {len(result.points)} points, "
          f"{len(marked)} marked, simulated in {seconds:.1f} s")
    print(f"pulses per marked point: {', '.join(map(str, counts)) or '-'} "
          f"(asked {args.pulses_per_point})")
    if speed is not None:
        print(f"marking speed {speed:.1f} mm/s on a {args.lens_field:g} mm field "
              f"(pitch × PRR / N = {summary['expected_line_speed_mm_s']:.1f} mm/s)")
    for what in ("csv", "points_csv", "png", "vcd"):
        if summary[what]:
            print(f"  {what.replace('_', ' ')}: {summary[what]}")
    return 0 if counts in ([args.pulses_per_point], []) else 1


def _backend(args):
    """``--backend``; a waveform (``--vcd``) is written by the Python one only."""
    if args.vcd:
        if args.backend == "compiled":
            fail("--vcd needs --backend python (the compiled backend writes no waveform)")
        return "python"
    return args.backend


def _netlist_settings(args):
    """``(settings, clocks per XY2 bit)`` of the build whose netlist ``--netlist`` names: its
    register resets (the default ones: ``galvoscan build`` takes none) and its spiral's
    interpolator, built or not; options that would change the design are refused."""
    # Here: sim.compiled takes 2.8 s to import; `galvoscan --help` need not wait.
    from ..sim.compiled import CompileError
    from ..sim.compiled.netlist import build_record
    for option in ("dwell", "interp", "correction", "vcd"):
        if getattr(args, option) is not None:
            fail(f"--{option} is the build's with --netlist (the netlist is simulated as it "
                 f"was built)")
    if args.backend == "python":
        fail("--netlist runs on the compiled backend (Amaranth simulates designs, not netlists)")
    try:
        record = build_record(args.netlist) or {}
    except CompileError as error:
        fail(error)
    settings = ScanSettings(spiral_interp=1 if record.get("interpolation") else 0)
    clock = float(record.get("clock_mhz", 12)) * 1e6
    return settings, round(clock / (float(record.get("bit_rate_mhz", 2)) * 1e6))


class _FrameBar:
    """The progress bar of a simulation, opened at its first frame, so that a compile before
    it (which says so in its own lines) neither sits under a bar at 0 % nor counts in its
    rate; ``started`` is when that was, the simulation's time being counted from there."""

    def __init__(self, total=None):
        self.total = total
        self.started = None
        self._bar = None

    def update(self, frames):
        if self._bar is None:
            self.started = time.monotonic()
            self._bar = tqdm(total=self.total, unit="frame", desc="simulating", disable=None,
                             file=sys.stderr)
        self._bar.update(frames)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        if self._bar is not None:
            self._bar.close()


def _say(line):
    print(f"galvoscan: {line}", file=sys.stderr, flush=True)


def _sim_spiral(args):
    # Here: sim takes 2.9 s to import; `galvoscan --help` need not wait.
    from ..sim.plots import plot_path
    from ..sim.spiral import SIM_CLOCKS_PER_BIT, replay_spiral, write_csv

    if args.job:
        fail("--job is for --mode vector")
    if args.points is None:
        fail("the spiral needs --points N (8064 is the whole pattern)")
    if args.interp is None and not args.netlist:
        # What the default bitstream does: it has no interpolator, so it holds each point.
        args.interp = "off"
    table = table_from(args)
    settings = settings_from(args, table)
    correction = _correction(args)
    clocks_per_bit = SIM_CLOCKS_PER_BIT
    if args.netlist:
        settings, clocks_per_bit = _netlist_settings(args)
    # The first frames after power-up park the mirrors at the centre; then each point is held
    # for `dwell` frames.
    frames = PARK_FRAMES + args.points * settings.dwell
    start = time.monotonic()
    with _FrameBar(total=frames) as bar:
        received = replay_spiral(frames=frames, table=table, settings=settings, vcd=args.vcd,
                                 progress=bar.update, correction=correction,
                                 backend=_backend(args), say=_say, netlist=args.netlist)
    seconds = time.monotonic() - (bar.started or start)
    cycles = frames * 20 * clocks_per_bit

    if args.csv:
        write_csv(args.csv, received)
    if args.png:
        sampling = (f"Gaussian sampling, σ = {table.sigma:g}" if table.sampling == "gaussian"
                    else "uniform sampling")
        plot_path(args.png, received[PARK_FRAMES:], title=(
            f"{args.points} spiral points, {sampling}, "
            f"{INTERPOLATIONS[settings.spiral_interp]} between points\n"
            f"(decoded from the simulated XY2-100 wires)"))
    summary = {
        "points": args.points, "dwell_frames": settings.dwell,
        "interpolation": INTERPOLATIONS[settings.spiral_interp], "frames": len(received),
        "table_points": table.points, "x_range": list(settings.x_range),
        "y_range": list(settings.y_range),
        "scan_time_s": len(received) * 10e-6, "sim_seconds": round(seconds, 2),
        "sim_cycles_per_s": round(cycles / seconds),
        "csv": args.csv, "png": args.png, "vcd": args.vcd,
    }
    if args.json:
        print(json.dumps(summary, indent=2))
        return 0
    print(f"{len(received)} frames decoded from the XY2-100 wires "
          f"({args.points} points × {settings.dwell} frames + {PARK_FRAMES} park frames, "
          f"{INTERPOLATIONS[settings.spiral_interp]} between points, "
          f"{summary['scan_time_s'] * 1e3:.2f} ms of scanning) in {seconds:.1f} s "
          f"({summary['sim_cycles_per_s']:,} system clocks/s)")
    for what in ("csv", "png", "vcd"):
        if summary[what]:
            print(f"  {what}: {summary[what]}")
    return 0


#: Vector-mode options given no value: the register's reset where there is one.
VECTOR_DEFAULTS = {"prr": 60.0, "lens_field": 110.0}


def _cmd_sim(args):
    vector_only = ("prr", "pulses_per_point", "pitch", "jump_delay", "lens_field", "points_csv")
    if args.mode == "vector":
        if args.netlist:
            fail("--netlist replays the spiral (the build's default mode); a vector job runs on "
                 "a netlist through galvoscan board --sim --netlist")
        if args.interp is not None:
            fail("--interp is for the spiral")
        if not args.job:
            fail("--mode vector needs --job FILE")
        for name in vector_only:
            if getattr(args, name) is None and name != "points_csv":
                setattr(args, name, VECTOR_DEFAULTS.get(name) or BY_NAME[name].reset)
        return _compiled_or_one_line(_sim_vector, args)
    given = [name for name in vector_only if getattr(args, name) is not None]
    if given:
        fail(f"--{given[0].replace('_', '-')} is for --mode vector")
    return _compiled_or_one_line(_sim_spiral, args)


def _compiled_or_one_line(command, args):
    # Here: sim.compiled takes 2.8 s to import; `galvoscan --help` need not wait.
    from ..sim.compiled import CompileError
    try:
        return command(args)
    except CompileError as error:
        if args.netlist:
            failed(f"the netlist cannot be simulated: {error}")
        failed(f"the compiled simulator cannot be built: {error} (--backend python runs "
               f"Amaranth's)")


def add_parsers(commands):

    rom = commands.add_parser("rom", help="print the two spiral angle tables",
                              description="Print the X and Y spiral tables as the ROMs hold "
                                          "them: signed offsets from the field centre.")
    rom.add_argument("--csv", action="store_true", help="comma-separated: address,x,y")
    add_table_options(rom)
    rom.set_defaults(run=_cmd_rom)

    sim = commands.add_parser(
        "sim", help="replay the spiral, or a vector job, through the system top in simulation",
        description="Simulate the system top from power-up, decode the XY2-100 wires like a "
                    "scan head and report the frames. The full precessing pattern is 8064 "
                    "points (lcm(128, 126)). With --mode vector, a job file (one 'jump X Y' "
                    "or 'mark X Y' a line, galvo units) is sent through the SPI pins and the "
                    "laser pulses on every point are counted on the DB25 pins. Output folders "
                    "are made before the simulation starts.")
    sim.add_argument("--mode", choices=["spiral", "vector"], default="spiral",
                     help="what to run (default: %(default)s)")
    sim.add_argument("--points", type=int_in(1, 1_000_000, "points"), default=None,
                     help="spiral points to replay (8064 = the whole pattern)")
    dwell = BY_NAME["dwell"]
    sim.add_argument("--dwell", type=register_int("dwell"), default=None,
                     help=f"10 µs frames each spiral point is held, {dwell.low} … {dwell.high} "
                          f"(default: the register's {dwell.reset})")
    interp = BY_NAME["spiral_interp"]
    sim.add_argument("--interp", choices=INTERPOLATIONS, default=None,
                     help=f"between spiral points: off (hold each point, then jump) or linear "
                          f"(every frame moves part of the way to the next). Default: off, "
                          f"what the default bitstream does (it has no interpolator); a build "
                          f"with --interpolation, or --preset cleaner, starts "
                          f"{INTERPOLATIONS[interp.reset]}")
    sim.add_argument("--correction", metavar="FILE",
                     help="distortion correction table (.json, .ctb, .cor) the top starts with "
                          "(default: the identity); the wires carry corrected positions")
    sim.add_argument("--vcd", type=output_file, metavar="FILE",
                     help="write a waveform (large for long runs)")
    sim.add_argument("--csv", type=output_file, metavar="FILE",
                     help="write one row per frame: frame,x,y (vector: and pulses)")
    sim.add_argument("--png", type=image_file, metavar="FILE",
                     help="plot the path (.png, .svg, .pdf, …)")
    sim.add_argument("--json", action="store_true", help="print the summary as JSON")
    add_backend_option(sim)
    sim.add_argument("--netlist", metavar="BUILD_DIR",
                     help="simulate the synthesized netlist of the build in BUILD_DIR (what "
                          "galvoscan build left there, iCEBreaker or ULX3S), gate by gate "
                          "with the FPGA's cell models: the bitstream's own logic (the "
                          "spiral; compiled backend)")
    vector = sim.add_argument_group("vector mode")
    vector.add_argument("--job", metavar="FILE", help="the job: 'jump X Y' / 'mark X Y' lines")
    prr = BY_NAME["laser_prr"]       # in 100 Hz steps
    vector.add_argument("--prr", type=prr_khz(), metavar="KHZ",
                        help=f"laser pulse rate, {prr.low / 10:g} … {prr.high / 10:g} kHz "
                             f"(default: {VECTOR_DEFAULTS['prr']:g}, the speeds of Wan et "
                             f"al.'s table)")
    for name, what in (("pulses_per_point", "pulses on every marked point"),
                       ("pitch", "galvo units between marked points"),
                       ("jump_delay", "laser-off wait after a jump, µs (whole 10 µs frames)")):
        reg = BY_NAME[name]
        vector.add_argument(f"--{name.replace('_', '-')}", type=register_int(name),
                            metavar="N", help=f"{what}, {reg.low} … {reg.high} (default: the "
                                              f"register's {reg.reset})")
    vector.add_argument("--lens-field", type=number_in("lens field", 1, 2000), metavar="MM",
                        help=f"field across 65536 units, for the speed in mm/s (default: "
                             f"{VECTOR_DEFAULTS['lens_field']:g})")
    vector.add_argument("--points-csv", type=output_file, metavar="FILE",
                        help="write one row per point: x,y,pulses,frames")
    add_table_options(sim)
    sim.set_defaults(run=_cmd_sim)
