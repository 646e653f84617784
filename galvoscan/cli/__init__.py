"""``galvoscan``: build, simulate, prove and export the scan head controller, and talk to a board.

One module per command group, each adding its own parsers (``add_parsers(commands)``):
:mod:`.sim` (``rom``, ``sim``), :mod:`.build` (``build``, ``export``), :mod:`.prove`,
:mod:`.link` (``regs``, ``encode``, ``send``, ``read``), :mod:`.analyze`, :mod:`.correct`,
:mod:`.bench`, :mod:`.machine` (``machine init``, ``machine show``), :mod:`.mark`,
:mod:`.clean`, :mod:`.testgrid` (``test-grid``), :mod:`.standalone` (``store``, ``flash``,
``standalone``), :mod:`.board`
(``board --sim``); :mod:`.args` and :mod:`.jobargs` hold what
they share.
"""

import argparse
import sys
from importlib.metadata import PackageNotFoundError, version

from . import (analyze, bench, board, build, clean, correct, link, machine, mark, prove, sim,
               standalone, testgrid)


__all__ = ["main", "parser"]


#: The command groups, in the order ``--help`` lists them.
GROUPS = (machine, mark, testgrid, clean, standalone, board, link, sim, build, prove, analyze,
          correct, bench)


def _version():
    try:
        return version("galvoscan")
    except PackageNotFoundError:                 # run from a source tree, not installed
        return "unknown (not installed)"


class _OneLineParser(argparse.ArgumentParser):
    """An argument parser whose errors are one line (what was wrong, and where the options are
    listed), not argparse's usage block; subcommands' parsers are of this class too."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (`{self.prog} --help` lists the "
                     f"options)\n")


def parser():
    """The whole command line."""
    top = _OneLineParser(
        prog="galvoscan",
        description="Open FPGA gateware that drives a laser scan head over XY2-100: "
                    "precessing Gaussian spiral fill, vector marking, raster fill and field "
                    "correction, simulated end to end and proved.")
    top.add_argument("--version", action="version", version=f"galvoscan {_version()}",
                     help="print the installed version and exit")
    commands = top.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for group in GROUPS:
        group.add_parsers(commands)
    return top


def main(argv=None):
    args = parser().parse_args(argv)
    try:
        return args.run(args) or 0
    except BrokenPipeError:
        # Output piped into `head` and the like: stop quietly.
        sys.stderr.close()
        return 0
    except KeyboardInterrupt as error:
        # A job says how far it got (JobInterrupted); anything else stops where it is.
        print(f"galvoscan: stopped (Ctrl-C){f': {error}' if str(error) else ''}",
              file=sys.stderr)
        return 130
    except OSError as error:
        # A file that could not be written or read after all (a full disk, a lost device):
        # one line, not a traceback. Paths are checked when parsed, so this is the exception.
        where = f" {error.filename}" if error.filename else ""
        print(f"galvoscan: error:{where} {error.strerror or error}", file=sys.stderr)
        return 1
