"""``galvoscan prove``: every SymbiYosys proof and its cover."""

import json
import sys

from .args import fail, output_dir


__all__ = ["add_parsers"]


def _cmd_prove(args):
    from ..formal.proofs import PROOFS
    from ..toolchain import ToolchainError

    unknown = set(args.only or ()) - {proof.name for proof in PROOFS}
    if unknown:
        fail(f"unknown proof(s) {', '.join(sorted(unknown))}; "
             f"known: {', '.join(p.name for p in PROOFS)}")
    selected = [proof for proof in PROOFS if not args.only or proof.name in args.only]
    rows = []
    try:
        for proof in selected:
            print(f"proving {proof.name} (depth {proof.depth}) …", file=sys.stderr, flush=True)
            for result in proof.run(args.workdir):
                rows.append(result)
                print(f"  {result.task:5s} {result.status} in {result.seconds:.1f} s",
                      file=sys.stderr, flush=True)
    except ToolchainError as error:          # z3 or the YoWASP tools missing
        fail(error)
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


def add_parsers(commands):
    prove = commands.add_parser(
        "prove", help="run all SymbiYosys proofs and their covers",
        description="Run every proof (k-induction, unbounded) and its cover; print a table. "
                    "Exits non-zero if any fails.")
    prove.add_argument("--workdir", type=output_dir, default="build/formal", metavar="DIR",
                       help="where SymbiYosys works (default: %(default)s)")
    prove.add_argument("--only", nargs="+", metavar="NAME", help="run only these proofs")
    prove.add_argument("--json", action="store_true", help="print the results as JSON")
    prove.set_defaults(run=_cmd_prove)
