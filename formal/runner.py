"""Run a spec harness through SymbiYosys: an unbounded proof (k-induction) and a cover."""

from dataclasses import dataclass, field
from pathlib import Path
import re
import subprocess
import time

from amaranth.back import rtlil
from amaranth.hdl import ClockSignal

from ..toolchain import tool, tool_env


__all__ = ["ProofResult", "run_sby"]


_SBY_TEMPLATE = """\
[tasks]
prove
cover
bmc

[options]
prove: mode prove
prove: depth {depth}
cover: mode cover
cover: depth {cover_depth}
cover: skip {cover_skip}
bmc: mode bmc
bmc: depth {cover_depth}
bmc: skip {cover_skip}
multiclock off

[engines]
prove: smtbmc z3
cover: smtbmc --nopresat{search_options} z3{search_solver_options}
bmc: smtbmc --nopresat{search_options} z3{search_solver_options}

[script]
read_rtlil {name}.il
prep -top {name}

[files]
{name}.il
"""


@dataclass
class ProofResult:
    """Outcome of one SymbiYosys task."""
    name: str
    task: str           # "prove" or "cover"
    status: str         # "PASS", "FAIL", "ERROR", "UNKNOWN", …
    seconds: float
    workdir: Path
    #: Assertions that failed, or covers that were not reached, as sby reported them.
    failed: list = field(default_factory=list)

    @property
    def passed(self):
        return self.status == "PASS"


#: smtbmc's options for a search solved afresh at each step (``fresh_solver``): the state as
#: plain bit-vectors, unrolled, and a new solver for each query (``--noincr``), so that z3 takes
#: each query as one bit-vector problem, which it bit-blasts whole, rather than extending an
#: incremental solver that does not.
_FRESH_SOLVER = (" --stbv --unroll", " -- --noincr")


def run_sby(harness, name, workdir, *, depth, cover_depth, cover_skip=0,
            tasks=("prove", "cover"), timeout=1800, fresh_solver=False):
    """Prove ``harness`` (an elaboratable with Assert/Cover) and reach its covers.

    ``cover_skip`` clocks are not searched for covers: a cover that needs a whole command frame
    cannot be reached sooner, and proving that step by step is what takes a solver long.

    ``tasks`` may also name ``"bmc"``: a bounded check to ``cover_depth`` (skipping
    ``cover_skip`` clocks), which fails with a counterexample trace where an assertion can be
    broken that soon; the broken designs' tests use it.

    The covers and bounded checks run without smtbmc's ``--presat``: it checks on every step
    that the assumptions can hold, and the harnesses assume nothing (all their inputs are
    free or fixed), so it only doubled the solver calls, each as dear as a cover or assertion
    query.

    ``fresh_solver`` solves each cover and bounded-check query with a new solver (see
    :data:`_FRESH_SOLVER`): some five times faster where the queries are few and come after a
    long skipped prefix (the player's whole image header), far slower where they are many
    (a search from the first clock re-solves every clock before it at each step).

    Files go to ``workdir/name``; YoWASP tools cannot see absolute paths outside their working
    folder, so they run with it as ``cwd`` and relative paths. Returns the
    :class:`ProofResult` of each of ``tasks``.
    """
    folder = Path(workdir) / name
    folder.mkdir(parents=True, exist_ok=True)
    (folder / f"{name}.il").write_text(rtlil.convert(harness, name=name, platform="formal", ports=[ClockSignal("sync")]))
    (folder / f"{name}.sby").write_text(
        _SBY_TEMPLATE.format(name=name, depth=depth, cover_depth=cover_depth,
                             cover_skip=cover_skip,
                             search_options=_FRESH_SOLVER[0] if fresh_solver else "",
                             search_solver_options=_FRESH_SOLVER[1] if fresh_solver else ""))

    results = []
    for task in tasks:
        start = time.monotonic()
        proc = subprocess.run(
            [tool("yowasp-sby"), "-f", f"{name}.sby", task],
            cwd=folder, env=tool_env(proofs=True), timeout=timeout,
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        seconds = time.monotonic() - start
        (folder / f"{task}.log").write_text(proc.stdout)
        status_file = folder / f"{name}_{task}" / "status"
        status = status_file.read_text().split()[0] if status_file.exists() else "ERROR"
        failed = sorted(set(
            re.findall(r"(?:Assert failed in|Unreached cover statement at|"
                       r"failed assertion|cover \S+ not reached)[^\n]*", proc.stdout)))
        results.append(ProofResult(name, task, status, seconds, folder, failed))
    return results
