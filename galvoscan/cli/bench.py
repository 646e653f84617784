"""``galvoscan bench``: resources, Fmax, frame rate, link speed, simulator and proof times."""

import json
from pathlib import Path
import sys

from .args import add_backend_option, fail, failed, output_file, read_text


__all__ = ["add_parsers"]


def _cmd_bench(args):
    from ..bench import DOCS_END, DOCS_START, run_bench, table, write_docs
    full = not args.quick

    def progress(text):
        print(f"bench: {text}", file=sys.stderr, flush=True)

    if args.docs:
        # Checked before the run, not after six minutes of it.
        if args.quick:
            fail("--docs takes a full run's figures: leave out --quick")
        text = read_text(args.docs, "benchmarks page")
        if DOCS_START not in text or DOCS_END not in text:
            fail(f"{args.docs} has no benchmark table to rewrite (the lines "
                 f"{DOCS_START!r} … {DOCS_END!r})")
    if args.suite is not None and not (Path(args.suite) / "tests").is_dir():
        fail(f"--suite {args.suite}: not a galvoscan checkout (it has no tests folder)")
    result = run_bench(builds=full, proofs=full, replay=full, suite=args.suite,
                       backend=args.backend, progress=progress)
    if args.record:
        Path(args.record).write_text(json.dumps(result, indent=2) + "\n")
    if args.docs:
        try:
            write_docs(args.docs, result)
        except (OSError, ValueError) as error:  # (after the run: the work failed)
            failed(error)
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
                    "the full spiral; prints a table (docs/reference/benchmarks.md).")
    bench.add_argument("--json", action="store_true",
                       help="print the figures as JSON (frames_per_s, idle_clocks, boards: "
                            "luts, brams, fmax_mhz, …)")
    bench.add_argument("--quick", action="store_true",
                       help="simulations only: no builds, proofs or full replay (seconds)")
    bench.add_argument("--record", type=output_file, metavar="FILE",
                       help="also write the figures as JSON to FILE (the docs' are in "
                            "docs/bench.json)")
    bench.add_argument("--suite", metavar="CHECKOUT",
                       help="also run and time the test suite of this galvoscan checkout (the "
                            "README's test command, after everything else)")
    bench.add_argument("--docs", metavar="PAGE",
                       help="rewrite the benchmark table of this page with the figures "
                            "(docs/reference/benchmarks.md)")
    add_backend_option(bench, default="python",
                       what="the simulator of the host-link stream and the full-spiral replay "
                            "(the backends' own row measures both, in the same run)")
    bench.set_defaults(run=_cmd_bench)
