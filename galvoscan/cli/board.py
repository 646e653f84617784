"""``galvoscan board --sim``: a board without hardware, its serial port on a pseudo-terminal."""

import sys
import time

from ..gateware.clocking import DEFAULT_BAUD
from .args import add_backend_option, baud, fail, simulated_board


__all__ = ["add_parsers"]


def _cmd_board(args):
    # Here: sim.board takes 2.7 s to import; `galvoscan --help` need not wait.
    from ..sim.board import PTYServer
    if args.netlist:
        if args.backend == "python":
            fail("--netlist runs on the compiled backend (Amaranth simulates designs, not "
                 "netlists)")
        board = simulated_board(args, netlist=args.netlist)
    else:
        board = simulated_board(args, baud=args.baud)
    speed = board.speed()
    timeout = board.answer_timeout_s()
    server = PTYServer(board)
    what = f"the netlist in {args.netlist}, gate by gate" if args.netlist else \
        f"{board.backend} backend"
    print(f"simulated board ({board.clk_freq / 1e6:g} MHz, {board.baud:,} baud, {what}) on "
          f"{server.port}", flush=True)
    print(f"  it runs at {_fraction(speed)} of real time: give clients --timeout "
          f"{timeout:.0f} or more; Ctrl-C stops it", flush=True)
    print(f"  e.g. galvoscan read status --port {server.port} --baud {board.baud} "
          f"--timeout {timeout:.0f}", flush=True)
    started = time.monotonic()
    board_started = board.now
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        server.stop()
    if server.error is not None:
        print(f"galvoscan: error: the simulated board stopped: {server.error}",
              file=sys.stderr)
        return 1
    wall = time.monotonic() - started
    print(f"stopped after {board.now * 1e3:.1f} ms of board time in {wall:.0f} s "
          f"({_fraction((board.now - board_started) / max(wall, 1e-9))} of real time): "
          f"{len(board.frames)} XY2-100 frames, {len(board.pulses)} laser pulses")
    return 0


def _fraction(speed):
    """A speed as a person reads it: 1/12 of real time, or 1/2400."""
    return "real time" if speed >= 1 else f"1/{1 / speed:,.0f}"


def add_parsers(commands):
    board = commands.add_parser(
        "board", help="serve a simulated board on a pseudo-terminal",
        description="Serve the simulated system top (the default iCEBreaker build: every "
                    "mode, correction, laser controller) on a pseudo-terminal, so that send, "
                    "read, mark and clean run against it with --port. It runs until Ctrl-C.")
    board.add_argument("--sim", action="store_true", required=True,
                       help="simulate the board (the only kind this command serves)")
    board.add_argument("--baud", type=baud, default=DEFAULT_BAUD,
                       help="the simulated bitstream's serial rate (default: %(default)s)")
    add_backend_option(board)
    board.add_argument("--netlist", metavar="BUILD_DIR",
                       help="serve the synthesized netlist of the build in BUILD_DIR (what "
                            "galvoscan build left there), gate by gate: the bitstream's own "
                            "logic, at the build's clock and baud")
    board.set_defaults(run=_cmd_board)
