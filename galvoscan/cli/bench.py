"""``galvoscan bench``: resources, Fmax, frame rate, link speed, simulator and proof times."""

import json
from pathlib import Path
import sys

from .args import add_backend_option, fail, output_file, read_text


__all__ = ["add_parsers"]


def _cmd_bench(args):
    # Here: bench takes 2.0 s to import; `galvoscan --help` need not wait.
    from ..bench import README_END, README_START, run_bench, table, write_readme
    full = not args.quick

    def progress(text):
        print(f"bench: {text}", file=sys.stderr, flush=True)

    if args.readme:
        # Checked before the run, not after six minutes of it.
        if args.quick:
            fail("--readme takes a full run's figures: leave out --quick")
        text = read_text(args.readme, "README")
        if README_START not in text or README_END not in text:
            fail(f"{args.readme} has no benchmark section to rewrite (the lines "
                 f"{README_START!r} … {README_END!r})")
    if args.suite is not None and not (Path(args.suite) / "tests").is_dir():
        fail(f"--suite {args.suite}: not a galvoscan checkout (it has no tests folder)")
    result = run_bench(builds=full, proofs=full, replay=full, suite=args.suite,
                       backend=args.backend, progress=progress)
    if args.record:
        Path(args.record).write_text(json.dumps(result, indent=2) + "\n")
    if args.readme:
        try:
            write_readme(args.readme, result)
        except (OSError, ValueError) as error:
            fail(error)
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        machine = result["machine"]
        print(f"galvoscan bench, {result['date']}, {machine['system']}, {machine['cpus']} "
              f"cores, Python {machine['python']}\n")
        print(table(result))
    return 0


def add_parsers(commands):
    bench = commands.add_parser(
        "bench", help="measure resources, Fmax, frame rate, link speed, simulator and proofs",
        description="One run (10 to 20 minutes on 2 cores) that builds each board "
                    "configuration, runs every proof, and simulates the PHY, the host link and "
                    "the full spiral; prints a table (README 'Benchmarks').")
    bench.add_argument("--json", action="store_true",
                       help="print the figures as JSON (frames_per_s, idle_clocks, boards: "
                            "luts, brams, fmax_mhz, …)")
    bench.add_argument("--quick", action="store_true",
                       help="simulations only: no builds, proofs or full replay (seconds)")
    bench.add_argument("--record", type=output_file, metavar="FILE",
                       help="also write the figures as JSON to FILE (the README's are in "
                            "docs/bench.json)")
    bench.add_argument("--suite", metavar="CHECKOUT",
                       help="also run and time the test suite of this galvoscan checkout (the "
                            "README's test command, after everything else)")
    bench.add_argument("--readme", metavar="FILE",
                       help="rewrite the benchmark section of this README with the figures")
    add_backend_option(bench, default="python",
                       what="the simulator of the host-link stream and the full-spiral replay "
                            "(the backends' own row measures both, in the same run)")
    bench.set_defaults(run=_cmd_bench)
