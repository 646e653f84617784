"""``galvoscan board --sim``: a board without hardware, its serial port on a pseudo-terminal."""

import sys
import time

from .args import baud


__all__ = ["add_parsers"]


def _cmd_board(args):
    from ..sim.board import SIM_TIMEOUT_S, PTYServer, SimulatedBoard
    board = SimulatedBoard(baud=args.baud)
    server = PTYServer(board)
    print(f"simulated board (12 MHz, {args.baud:,} baud) on {server.port}", flush=True)
    print(f"  e.g. galvoscan read status --port {server.port} --baud {args.baud} "
          f"--timeout {SIM_TIMEOUT_S:g}", flush=True)
    print("  it runs about 1000x slower than a real board: give clients a long --timeout; "
          "Ctrl-C stops it", flush=True)
    started = time.monotonic()
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
    print(f"stopped after {board.now * 1e3:.1f} ms of board time "
          f"({time.monotonic() - started:.0f} s): {len(board.frames)} XY2-100 frames, "
          f"{len(board.pulses)} laser pulses")
    return 0


def add_parsers(commands):
    from ..gateware.clocking import DEFAULT_BAUD
    board = commands.add_parser(
        "board", help="serve a simulated board on a pseudo-terminal",
        description="Serve the simulated system top (the default iCEBreaker build: every "
                    "mode, correction, laser controller) on a pseudo-terminal, so that send, "
                    "read, mark and clean run against it with --port. It runs until Ctrl-C.")
    board.add_argument("--sim", action="store_true", required=True,
                       help="simulate the board (the only kind this command serves)")
    board.add_argument("--baud", type=baud, default=DEFAULT_BAUD,
                       help="the simulated bitstream's serial rate (default: %(default)s)")
    board.set_defaults(run=_cmd_board)
