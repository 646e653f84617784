"""The C++ compiler the compiled backend builds with: the system's where there is one, else Zig's
``zig c++`` from the ``ziglang`` wheel (a galvoscan dependency), so that a machine with nothing
but Python still gets it.

A system compiler is a program of the system's, found on PATH: ``$CXX`` first, then Clang
(``clang++``, else the newest versioned ``clang++-N``), then ``g++`` and ``c++``. Clang first,
because it is the faster here on CXXRTL's one large function, and what is compiled is mostly
that: on the tests' 8 MHz top (0.3 MB of C++) clang++ 14 took 3.6 to 5.5 s at -O2 where g++ 12
took 9.5, the models simulating as fast (0.77 and 0.84 s for the same 24,000 frames); on the
default build's netlist (5 MB) Clang -O1 compiled in 42 to 48 s and then ran 1.2 ms of the board
in 0.3 s, where g++ -Og took 43 s and ran it in 18 s (and Clang -O0 15 s, running it in 34 s;
g++ -O1 8 min 45 s over the 10 MB of Yosys' own LUT model). ``ziglang`` is found beside the running
interpreter, as a module of its environment, never on PATH.
"""

import importlib.util
import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass


__all__ = ["Compiler", "CompilerError", "find_compiler"]


class CompilerError(RuntimeError):
    """No C++ compiler could be found or run."""


@dataclass(frozen=True)
class Compiler:
    """A C++ compiler: the command that runs it, and what it says it is.

    ``identity`` (its ``--version`` line) is part of a compiled model's cache key: a model
    built by another compiler is never taken for this one's.
    """
    command: tuple
    identity: str
    #: True for ``zig c++``, whose first run builds its libc++ (minutes, once).
    zig: bool = False

    @property
    def clang(self):
        """Clang's front end (``zig c++`` is Clang too)."""
        return self.zig or "clang" in self.identity.lower()

    @property
    def light_optimisation(self):
        """The flag for a design too large to optimise fully (a netlist's C++): -O1 for Clang,
        -Og for g++, whose -O1 takes minutes over it (the module's figures)."""
        return "-O1" if self.clang else "-Og"

    @property
    def name(self):
        return "zig c++" if self.zig else os.path.basename(self.command[0])


def _identity(command):
    try:
        run = subprocess.run([*command, "--version"], capture_output=True, text=True,
                             timeout=60, check=False)
    except (OSError, subprocess.SubprocessError):
        return None
    if run.returncode != 0:
        return None
    lines = (run.stdout or run.stderr).strip().splitlines()
    return lines[0] if lines else None


def _versioned_clangs():
    """``clang++-N`` on PATH (Debian's and Ubuntu's names), the newest first."""
    found = {}
    for folder in os.environ.get("PATH", "").split(os.pathsep):
        try:
            with os.scandir(folder or ".") as entries:
                for entry in entries:
                    match = re.fullmatch(r"clang\+\+-(\d+)", entry.name)
                    if match and os.access(entry.path, os.X_OK):
                        found.setdefault(int(match[1]), entry.name)
        except OSError:
            continue
    return [found[version] for version in sorted(found, reverse=True)]


def _system_compilers():
    names = []
    if os.environ.get("CXX"):
        names.append(os.environ["CXX"])
    names += ["clang++", *_versioned_clangs(), "g++", "c++"]
    for name in names:
        path = shutil.which(name)
        if path:
            yield path


def _zig():
    if importlib.util.find_spec("ziglang") is None:
        return None
    command = (sys.executable, "-m", "ziglang", "c++")
    run = None
    try:
        run = subprocess.run([sys.executable, "-m", "ziglang", "version"], capture_output=True,
                             text=True, timeout=120, check=False)
    except (OSError, subprocess.SubprocessError):
        return None
    if run.returncode != 0 or not run.stdout.strip():
        return None
    return Compiler(command, f"zig {run.stdout.strip()}", zig=True)


def find_compiler(prefer=None):
    """The compiler to build with.

    Parameters
    ----------
    prefer : str, optional
        ``"system"`` or ``"zig"``: that kind only. Default: the system's (``$CXX``, Clang,
        g++, c++, in that order), else zig.

    Raises
    ------
    CompilerError
        With the reason in one line.
    """
    if prefer not in (None, "system", "zig"):
        raise ValueError(f"prefer must be 'system' or 'zig', not {prefer!r}")
    if prefer in (None, "system"):
        for path in _system_compilers():
            identity = _identity((path,))
            if identity:
                return Compiler((path,), identity)
        if prefer == "system":
            raise CompilerError("no C++ compiler on PATH (g++, c++, clang++ or $CXX)")
    compiler = _zig()
    if compiler is None:
        raise CompilerError("no C++ compiler: none on PATH (g++, c++, clang++) and the "
                            "ziglang package is not installed beside this Python")
    return compiler
