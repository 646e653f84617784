"""``galvoscan board --sim``: a board without hardware, its serial port on a pseudo-terminal."""

import time

from .args import add_backend_option, baud, fail, failed, simulated_board


__all__ = ["add_parsers"]


def _cmd_board(args):
    from ..build import simulated_bitstream
    from ..sim.board import PTYServer
    try:
        config, contents = simulated_bitstream(args.board, preset=args.preset, baud=args.baud)
    except ValueError as error:
        fail(error)
    if args.netlist:
        if args.backend == "python":
            fail("--netlist runs on the compiled backend (Amaranth simulates designs, not "
                 "netlists)")
        board = simulated_board(args, netlist=args.netlist)
    else:
        board = simulated_board(args, config=config, **contents)
    speed = board.speed()
    timeout = board.answer_timeout_s()
    server = PTYServer(board, real_time=not args.free_run)
    what = f"the netlist in {args.netlist}, gate by gate" if args.netlist else \
        f"{board.backend} backend"
    print(f"simulated board ({board.clk_freq / 1e6:g} MHz, {board.baud:,} baud, {what}) on "
          f"{server.port}", flush=True)
    if board.config is not None:
        what = ("the ULX3S bitstream (build --board ulx3s)" if args.board == "ulx3s" else
                f"the {args.preset} bitstream (build --preset {args.preset})")
        print(f"  {what}: {board.config.summary()}", flush=True)
    if speed >= 1 and not args.free_run:
        print("  it runs faster than real time and waits for the host's clock: a client "
              "sees a real board's timing (answers, the watchdog, clean --duration); "
              "Ctrl-C stops it", flush=True)
    else:
        print(f"  it runs at {_fraction(speed)} of real time: give clients --timeout "
              f"{timeout:.0f} or more (it says how far it falls behind); Ctrl-C stops it",
              flush=True)
    print(f"  e.g. galvoscan read status --port {server.port} --baud {board.baud} "
          f"--timeout {timeout:.0f}", flush=True)
    started = time.monotonic()
    board_started = board.now
    try:
        server.serve_forever(report=lambda lag: print(
            f"  {lag:,.1f} s behind the host's clock "
            f"({_fraction((board.now - board_started) / max(time.monotonic() - started, 1e-9))}"
            f" of real time)", flush=True))
    except KeyboardInterrupt:
        pass
    finally:
        server.stop()
    if server.error is not None:
        failed(f"the simulated board stopped: {server.error}")
    wall = time.monotonic() - started
    print(f"stopped after {board.now * 1e3:.1f} ms of board time in {wall:.0f} s "
          f"({_fraction((board.now - board_started) / max(wall, 1e-9))} of real time): "
          f"{len(board.frames)} XY2-100 frames, {len(board.pulses)} laser pulses")
    return 0


def _fraction(speed):
    """A speed as a person reads it: 1/12 of real time, or 1/2400."""
    return "real time" if speed >= 1 else f"1/{1 / speed:,.0f}"


def add_parsers(commands):
    from ..build import SIMULATED_BOARDS
    from ..gateware.clocking import DEFAULT_BAUD
    board = commands.add_parser(
        "board", help="serve a simulated board on a pseudo-terminal",
        description="Serve a simulated iCEBreaker bitstream (by default the default build: "
                    "every mode, correction, laser controller; or a --preset's) on a "
                    "pseudo-terminal, so that send, read, mark and clean run against it with "
                    "--port. It runs until Ctrl-C.")
    board.add_argument("--sim", action="store_true", required=True,
                       help="simulate the board (the only kind this command serves)")
    board.add_argument("--board", choices=SIMULATED_BOARDS, default="icebreaker",
                       help="whose bitstream: the iCEBreaker's (default) or the ULX3S's, "
                            "with every feature")
    board.add_argument("--baud", type=baud, default=None,
                       help=f"the simulated bitstream's serial rate (default: the board's: "
                            f"{DEFAULT_BAUD:g}, the ULX3S's 3e6)")
    # (Checked when it runs: the presets are build configurations, which the parser does not
    # load.)
    board.add_argument("--preset", default="default",
                       help="the bitstream simulated: that of build --preset PRESET "
                            "(default: %(default)s, what build builds when told nothing)")
    add_backend_option(board)
    board.add_argument("--netlist", metavar="BUILD_DIR",
                       help="serve the synthesized netlist of the build in BUILD_DIR (what "
                            "galvoscan build left there), gate by gate: the bitstream's own "
                            "logic, at the build's clock and baud")
    board.add_argument("--free-run", action="store_true",
                       help="run as fast as the simulator can, ahead of the host's clock "
                            "(by default a board faster than real time waits for it)")
    board.set_defaults(run=_cmd_board)
