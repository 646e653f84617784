"""The simulated board compiled to native code: the system top through Yosys' CXXRTL and a C++
compiler, with the board of ``board.cc`` around it (host UART, machine inputs, scan head and
laser recorders), some hundreds of times faster than Amaranth's simulator and giving the same
records (:class:`galvoscan.sim.board.SimulatedBoard` with ``backend="compiled"``).

* :func:`compiled_model` — a top's model, built once per design and cached;
* :class:`CompiledEngine` — the engine a :class:`~galvoscan.sim.board.SimulatedBoard` runs on;
* :func:`find_compiler` — the system's C++ compiler, else ``zig c++`` from the ziglang wheel.
"""

from .compiler import Compiler, CompilerError, find_compiler
from .engine import CompiledEngine
from .model import CompileError, CompiledModel, cache_dir, compiled_model


__all__ = ["CompileError", "CompiledEngine", "CompiledModel", "Compiler", "CompilerError",
           "cache_dir", "compiled_model", "find_compiler"]
