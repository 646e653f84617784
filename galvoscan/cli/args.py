"""What the command groups share: argument types, one-line errors, the spiral table options,
output paths and the host link.

Every check here runs while the command line is parsed, so a wrong argument is one line and a
non-zero exit before any simulation, build or byte to a board.
"""

import argparse
import math
import os
from pathlib import Path

from ..settings.laser import BAUD, LINK_TIMEOUT_S, PASSES, POWER, PRR, SPEED, TIMEOUT
from ..settings.schema import SettingError, number_text as _number


__all__ = ["CLIError", "REFUSED", "FAILED", "fail", "failed", "int_in", "number_in",
           "register_int", "sigma", "field_mm",
           "table_points", "output_file", "image_file", "output_dir", "read_text",
           "add_table_options", "table_from", "settings_from", "INTERPOLATIONS", "baud", "add_baud_option",
           "add_link_options", "open_transport", "open_link", "add_backend_option",
           "check_backend_needs_sim", "simulated_board", "prr_khz", "setting_type", "setting_keywords", "add_setting", "speed_mm_s",
           "power_percent", "passes"]


#: Exit statuses. A refusal (the command line, a file or a setting it names, found wrong
#: before any work: nothing built, sent or written) is 2, as argparse's own refusals are, so
#: that a script tells "I asked wrongly" from "the work failed" (a board, a link, a tool):
#: 1. Both are said alike, ``galvoscan COMMAND: error: …``, in one line.
REFUSED, FAILED = 2, 1


class CLIError(SystemExit):
    """A one-line error and its exit status (:data:`REFUSED` or :data:`FAILED`):
    :func:`galvoscan.cli.main` says it on stderr as ``galvoscan COMMAND: error: …`` (its
    ``prog``, the command's, set there), as argparse says its own."""

    prog = "galvoscan"

    def __init__(self, message, status=REFUSED):
        super().__init__(status)
        self.message = str(message)

    def __str__(self):
        return f"{self.prog}: error: {self.message}"


def fail(message):
    """Refuse, before any work: one line, exit status 2."""
    raise CLIError(message, REFUSED)


def failed(message):
    """The work failed (a board, a link, a tool, after it began): one line, exit status 1."""
    raise CLIError(message, FAILED)


# --- numbers -------------------------------------------------------------------------------------

def int_in(low, high, what):
    """An integer (decimal, 0x… or 0b…) from ``low`` to ``high``."""
    def parse(text):
        try:
            value = int(text, 0)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{what} must be an integer, not {text!r}")
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"{what} must be from {low} to {high}, not {value}")
        return value
    return parse


def number_in(what, low, high):
    """A finite number from ``low`` to ``high`` (``1e6`` and the like accepted)."""
    def parse(text):
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{what} must be a number, not {text!r}")
        if not math.isfinite(value) or not low <= value <= high:
            raise argparse.ArgumentTypeError(f"{what} must be from {_number(low)} to "
                                             f"{_number(high)}, not {text}")
        return value
    return parse


def setting_type(setting):
    """An argparse type reading ``setting`` (a :class:`~galvoscan.settings.schema.Setting`):
    its range checked, its refusal its own one line."""
    def parse(text):
        try:
            return setting.parse(text)
        except SettingError as error:
            raise argparse.ArgumentTypeError(str(error)) from None
    parse.__name__ = setting.what
    return parse


def setting_keywords(setting, *, default=None, default_text=None):
    """``add_argument``'s keywords for ``setting``: its type (a choice: its words), placeholder,
    default and help (the unit, the range and the default said); a repeated setting's values
    gathered in a list. ``default``: the command's own, in place of the setting's;
    ``default_text``: where a default left as None comes from."""
    default = setting.default if default is None else default
    help = setting.described(default, default_text).replace("%", "%%")
    if setting.kind == "choice":
        return dict(choices=list(setting.choices), default=default, help=help)
    keywords = dict(type=setting_type(setting), metavar=setting.metavar, help=help)
    if setting.repeated:
        return dict(keywords, action="append")
    return dict(keywords, default=default)


def add_setting(group, setting, **how):
    """``setting``'s option (its flag, :func:`setting_keywords`) in ``group``."""
    return group.add_argument(setting.flag, **setting_keywords(setting, **how))


def prr_khz():
    """``--prr`` of the board's laser, kHz: the ``laser_prr`` register's range (100 Hz
    steps)."""
    return setting_type(PRR)


#: A job's marking speed (mm/s), power (% of the laser's maximum) and passes: the types of
#: ``mark``'s options and of a layer's settings alike.
speed_mm_s = setting_type(SPEED)
power_percent = setting_type(POWER)
passes = setting_type(PASSES)


def register_int(name, what=None):
    """An integer in the writable range of register ``name``, as the register map declares it."""
    from ..gateware.host.regmap import BY_NAME
    reg = BY_NAME[name]
    return int_in(reg.low, reg.high, what or name.replace("_", " "))


def sigma(text):
    """Width of the Gaussian sampling, in half-swings."""
    return number_in("sigma", 0.05, 100)(text)


def field_mm(text):
    """``WIDTHxHEIGHT`` in mm (``50x20``, ``50×20``)."""
    parts = text.lower().replace("×", "x").split("x")
    try:
        width, height = (float(p) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"field must be WIDTHxHEIGHT in mm (e.g. 50x20), "
                                         f"not {text!r}")
    if not all(math.isfinite(v) and 0.5 <= v <= 2000 for v in (width, height)):
        raise argparse.ArgumentTypeError(f"field sides must be from 0.5 to 2000 mm, not {text}")
    return width, height


# --- files ---------------------------------------------------------------------------------------

def _writable_folder(folder, what):
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise argparse.ArgumentTypeError(f"cannot make the folder {str(folder)!r} for {what}: "
                                         f"{error.strerror or error}")
    if not os.access(folder, os.W_OK):
        raise argparse.ArgumentTypeError(f"cannot write into {str(folder)!r} (permission)")


def table_points(text):
    """Samples per period of the spiral table: a multiple of 4 in the table's bounds."""
    from ..gateware.sources.spiral_table import MAX_POINTS, MIN_POINTS
    value = int_in(MIN_POINTS, MAX_POINTS, "table points")(text)
    if value % 4:
        raise argparse.ArgumentTypeError(f"table points must be a multiple of 4, not {value}")
    return value


def output_file(text):
    """A file to write: its folder is made and the file tried now (or refused now), not after
    a long run."""
    path = Path(text)
    try:
        if path.is_dir():
            raise argparse.ArgumentTypeError(f"{text!r} is a folder, not a file")
        _writable_folder(path.parent, text)
        existed = path.exists()
        with open(path, "a"):
            pass
    except OSError as error:                # a name too long, a folder that is not one, …
        raise argparse.ArgumentTypeError(f"cannot write {text!r}: {error.strerror or error}")
    if not existed:
        path.unlink()                 # nothing is left behind if the run stops early
    return text


def image_file(text):
    """A picture to write, in a format the plots can be saved as (by its suffix)."""
    import matplotlib
    matplotlib.use("Agg")
    from matplotlib.figure import Figure
    formats = Figure().canvas.get_supported_filetypes()
    suffix = Path(text).suffix.lower().lstrip(".")
    if suffix not in formats:
        raise argparse.ArgumentTypeError(
            f"{text!r}: a picture's name ends in one of .{', .'.join(sorted(formats))} "
            f"(.png is usual)")
    return output_file(text)


def output_dir(text):
    """A folder to write into, made now if missing."""
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is a file, not a folder")
    _writable_folder(path, "the output")
    return text


def read_text(path, what="file"):
    """The UTF-8 text of ``path`` (a byte-order mark, as Windows editors write, is dropped),
    or a one-line error naming it."""
    try:
        data = Path(path).read_bytes()
    except OSError as error:
        fail(f"cannot read the {what} {path}: {error.strerror or error}")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        line = data[:error.start].count(b"\n") + 1
        fail(f"{path}, line {line}: the {what} is not UTF-8 text (save it as UTF-8)")


def read_bytes(path, what="file"):
    """The bytes of ``path``, or a one-line error naming it."""
    try:
        return Path(path).read_bytes()
    except OSError as error:
        fail(f"cannot read the {what} {path}: {error.strerror or error}")


# --- spiral tables -------------------------------------------------------------------------------

def add_table_options(parser):
    from ..gateware.sources.spiral_table import (DEFAULT_POINTS, DEFAULT_SIGMA, MAX_POINTS,
                                                 MIN_POINTS, SAMPLINGS)
    group = parser.add_argument_group("spiral tables")
    group.add_argument("--sampling", choices=SAMPLINGS, default="gaussian",
                       help="how one sine period is sampled (default: %(default)s)")
    group.add_argument("--sigma", type=sigma, default=DEFAULT_SIGMA,
                       help="width of the Gaussian sampling in half-swings "
                            "(default: %(default)s)")
    group.add_argument("--table-points", type=table_points, default=DEFAULT_POINTS, metavar="N",
                       help=f"samples per sine period, a multiple of 4 from {MIN_POINTS} to "
                            f"{MAX_POINTS} (default: %(default)s, as in the paper)")


def table_from(args):
    from ..gateware.sources.spiral_table import SpiralTable
    try:
        return SpiralTable(points=args.table_points, sampling=args.sampling, sigma=args.sigma)
    except ValueError as error:
        fail(error)


#: Settings of the ``spiral_interp`` register, by value: what ``--interp`` takes.
INTERPOLATIONS = ("off", "linear")


def settings_from(args, table, **overrides):
    """The scan settings a build or simulation starts with, for ``table``'s size: the resets
    its register map gives (the paper's ranges, X over the whole table, Y one short at each
    end), the dwell if given."""
    from ..gateware.host.regmap import register_map
    from ..gateware.top import ScanSettings
    regmap = register_map(table_points=table.points)
    settings = dict(x_range=(regmap["x_first"].reset, regmap["x_last"].reset),
                    y_range=(regmap["y_first"].reset, regmap["y_last"].reset))
    if getattr(args, "dwell", None) is not None:
        settings["dwell"] = args.dwell
    if getattr(args, "interp", None) is not None:
        settings["spiral_interp"] = INTERPOLATIONS.index(args.interp)
    settings.update(overrides)
    try:
        return ScanSettings(**settings)
    except ValueError as error:
        fail(error)


# --- host link -----------------------------------------------------------------------------------

def baud(text):
    """A UART rate in baud (``1e6``, ``3000000``)."""
    value = setting_type(BAUD)(text)
    if value != int(value):
        raise argparse.ArgumentTypeError(f"baud must be a whole number, not {text}")
    return int(value)


def add_baud_option(parser, *, clock_option="--clock", board_default=None):
    """``--baud`` of a build: the rate the bitstream's serial port runs at (``clock_option``:
    the command's option for the system clock; ``board_default``: a sentence on boards whose
    default differs, and then the option's default is None, the board's)."""
    from ..gateware.clocking import DEFAULT_BAUD, FTDI_BAUDS
    parser.add_argument("--baud", type=baud, default=None if board_default else DEFAULT_BAUD,
                        metavar="BAUD",
                        help=f"host serial port rate (default: {_number(DEFAULT_BAUD)}"
                             f"{f'; {board_default}' if board_default else ''}; the "
                             f"FTDI chips make {', '.join(map(_number, FTDI_BAUDS))} exactly; "
                             f"3e6 needs {clock_option} 24e6 or more)")


def add_link_options(parser):
    from ..gateware.clocking import DEFAULT_BAUD
    link = parser.add_argument_group("link (one of)")
    where = link.add_mutually_exclusive_group(required=True)
    where.add_argument("--port", help="serial port of the board (e.g. /dev/ttyUSB1, COM4)")
    where.add_argument("--spi", metavar="URL", help="pyftdi URL of an FTDI SPI adapter "
                                                    "(e.g. ftdi://ftdi:2232h/1)")
    link.add_argument("--baud", type=baud, default=DEFAULT_BAUD,
                      help="serial rate of the bitstream (default: %(default)s)")
    add_setting(link, TIMEOUT, default=LINK_TIMEOUT_S)
    link.add_argument("--sck", type=number_in("SPI clock", 1e3, 30e6), default=1e6,
                      metavar="HZ", help="SPI clock, at most the board clock / 12 "
                                         "(default: 1e6)")


def open_transport(*, port=None, spi=None, baud=None, timeout=LINK_TIMEOUT_S, sck=1e6):
    """A serial (``port``) or FTDI SPI (``spi``) transport, opened; one line if it cannot be."""
    from ..link.client import ClientError, FTDISPITransport, SerialTransport
    from ..gateware.clocking import DEFAULT_BAUD
    try:
        if spi:
            return FTDISPITransport(spi, frequency=sck)
        return SerialTransport(port, baud=baud or DEFAULT_BAUD, timeout=timeout)
    except ClientError as error:
        failed(error)
    except Exception as error:   # serial.SerialException and the like: say what failed
        failed(f"cannot open {spi or port}: {error}")


def open_link(args):
    """The transport the link options name, opened; one line if it cannot be."""
    return open_transport(port=args.port, spi=args.spi, baud=args.baud, timeout=args.timeout,
                          sck=args.sck)


# --- the simulated board ---------------------------------------------------------------------------

def add_backend_option(parser, *, default="auto", what="the simulator"):
    """``--backend``: which simulator runs the simulated board. ``default=None``: auto, and a
    command can tell whether it was given (see :func:`check_backend_needs_sim`)."""
    from ..sim.board import BACKENDS
    parser.add_argument("--backend", choices=BACKENDS, default=default,
                        help=f"{what}: compiled (the design as native code, built once "
                             f"per design and cached; some 200 times faster: the benchmarks), python (Amaranth's, "
                             f"the reference) or auto, the compiled one where a C++ compiler "
                             f"can build it (default: {default or 'auto'})")


def check_backend_needs_sim(args):
    """A job's ``--backend`` without ``--sim`` chooses nothing: one line, before any work."""
    if getattr(args, "backend", None) is not None and not getattr(args, "sim", False):
        fail(f"--backend {args.backend} chooses the simulated board's simulator: it needs "
             f"--sim")
    if getattr(args, "board", None) is not None and not getattr(args, "sim", False):
        fail(f"--board {args.board} chooses the simulated board's bitstream: it needs --sim "
             f"(a real board's is read off it)")


def simulated_board(args, **kwargs):
    """The :class:`~galvoscan.sim.board.SimulatedBoard` ``--backend`` asks for (a compile's
    progress and a fallback's reason on stderr); one line if the compiled one cannot be had."""
    import sys
    from ..sim.compiled import CompileError
    from ..sim.board import SimulatedBoard

    def say(line):
        print(f"galvoscan: {line}", file=sys.stderr, flush=True)
    try:
        return SimulatedBoard(backend=getattr(args, "backend", None) or "auto", say=say,
                              **kwargs)
    except CompileError as error:
        if kwargs.get("netlist"):
            failed(f"the netlist cannot be simulated: {error}")
        failed(f"the compiled simulator cannot be built: {error} (--backend python runs "
               f"Amaranth's)")
