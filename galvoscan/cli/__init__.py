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
import difflib
import sys
from importlib.metadata import PackageNotFoundError, version

from .args import FAILED, REFUSED, CLIError
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
    listed), not argparse's usage block; subcommands' parsers are of this class too.

    An option a command does not know is refused by that command's parser (argparse leaves
    it to the top one, whose help does not list it), with the nearest of its options."""

    def error(self, message):
        self.exit(REFUSED, f"{self.prog}: error: {message} (`{self.prog} --help` lists the "
                           f"options)\n")

    def parse_known_args(self, args=None, namespace=None):
        namespace, extras = super().parse_known_args(args, namespace)
        if extras and not self._subparsers:         # a command's own parser: its options
            self.error(f"unrecognized arguments: {' '.join(extras)}{self._nearest(extras)}")
        return namespace, extras

    def _nearest(self, extras):
        """`` (did you mean --speed?)`` for the first unknown option like one of ours."""
        for word in extras:
            if word.startswith("--"):
                near = difflib.get_close_matches(word.split("=")[0], [
                    flag for flag in self._option_string_actions if flag.startswith("--")],
                    n=1)
                if near:
                    return f" (did you mean {near[0]}?)"
        return ""


def _name_commands(parser):
    """Each command's parser gives its name (``galvoscan mark``) to the arguments it parses:
    the prefix of the errors said while it runs."""
    parser.set_defaults(prog=parser.prog)
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in set(action.choices.values()):
                _name_commands(sub)


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
    _name_commands(top)
    return top


def main(argv=None):
    """Run the command ``argv`` gives (None: the process's). Every error is one line,
    ``galvoscan COMMAND: error: …``, with exit status 2 when the command was refused before
    any work (argparse's refusals and :func:`.args.fail`'s) and 1 when the work failed
    (:func:`.args.failed`, a file that could not be written after all)."""
    args = None
    try:
        args = parser().parse_args(argv)
        return args.run(args) or 0
    except CLIError as error:
        error.prog = getattr(args, "prog", error.prog)      # (None: refused while parsed)
        print(error, file=sys.stderr)
        raise
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
        print(f"{getattr(args, 'prog', 'galvoscan')}: error:{where} {error.strerror or error}",
              file=sys.stderr)
        return FAILED
