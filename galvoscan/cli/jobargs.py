"""What ``mark`` and ``clean`` share: job parameters in user units, the link to a board (a real
one, or the simulated one with ``--sim``), and running a job safely to its end."""

import argparse
import contextlib
import sys

from tqdm import tqdm

from ..api import load_lens_table
from ..build import SIMULATED_BOARDS, simulated_bitstream
from ..platforms.ulx3s import ULX3S_BAUD, ULX3S_CLOCK_HZ
from ..link.client import ClientError, HostClient, SerialTransport
from ..outputs.stream import JobAborted, JobInterrupted, JobRefused
from ..plan.vector_job import frame_segments
from ..sim.board import PTYServer
from ..settings.laser import POWER, PRR, SPEED, TIMEOUT
from .args import (add_backend_option, add_setting, baud, fail, failed, open_transport,
                   simulated_board)


__all__ = ["add_job_options", "add_job_link_options", "job_settings_values", "board_link",
           "has_link", "link_baud", "pair_mm", "load_lens_table", "stopped_in_one_line", "frame_job",
           "progress_bar"]


def pair_mm(what):
    """``X,Y`` in mm."""
    def parse(text):
        parts = text.replace(" ", "").split(",")
        try:
            x, y = (float(p) for p in parts)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{what} must be X,Y in mm (e.g. 10,-5), not "
                                             f"{text!r}")
        if not all(abs(v) <= 1000 for v in (x, y)):
            raise argparse.ArgumentTypeError(f"{what} must be within ±1000 mm, not {text}")
        return x, y
    return parse


def add_job_options(parser):
    """``--speed``, ``--power``, ``--prr``, ``--passes`` (defaults from the machine profile)."""
    job = parser.add_argument_group("laser and speed (defaults: the machine profile's)")
    for setting in (SPEED, POWER, PRR):
        add_setting(job, setting)
    return job


def job_settings_values(args, profile):
    """``(speed_mm_s, power_percent, prr_khz)``: the command line's, else the profile's."""
    defaults = profile.defaults
    return (args.speed if args.speed is not None else defaults.speed_mm_s,
            args.power if args.power is not None else defaults.power_percent,
            args.prr if args.prr is not None else defaults.prr_khz)


def add_job_link_options(parser):
    link = parser.add_argument_group("board (one of; none: plan, preview and estimate only)")
    where = link.add_mutually_exclusive_group()
    where.add_argument("--port", help="serial port of the board (default: the profile's)")
    where.add_argument("--spi", metavar="URL", help="pyftdi URL of an FTDI SPI adapter")
    where.add_argument("--sim", action="store_true",
                       help="run on the simulated board (see --backend for its speed)")
    link.add_argument("--baud", type=baud, default=None,
                      help="serial rate of the bitstream (default: the profile's)")
    add_setting(link, TIMEOUT, default_text="the profile's; with --sim, from the simulator's "
                                             "measured speed")
    link.add_argument("--board", choices=SIMULATED_BOARDS, default=None,
                      help="with --sim: whose bitstream the simulated board runs: the "
                           "iCEBreaker's default build (default; with the wobble stage for a "
                           "wobbled job, the engraver's for a photo's pixel lines) or the "
                           f"ULX3S's, every feature at {ULX3S_CLOCK_HZ / 1e6:g} MHz "
                           f"and {ULX3S_BAUD / 1e6:g} Mbaud")
    add_backend_option(link, default=None)


def link_baud(args, profile):
    """The serial rate of the job's link: ``--baud``, else a simulated ULX3S's own, else the
    profile's."""
    if args.baud:
        return args.baud
    return ULX3S_BAUD if args.sim and args.board == "ulx3s" else profile.link.baud


def has_link(args, profile):
    return bool(args.sim or args.port or args.spi or profile.link.port or profile.link.spi)


@contextlib.contextmanager
def board_link(args, profile, *, wobble=False, pixel_lines=False, belt=None, sensor=None):
    """``(client, simulated_board or None)`` for the job's board, opened; closed after
    (``wobble``: a simulated board is built with the wobble stage; ``pixel_lines``: a
    simulated iCEBreaker runs the engraver's bitstream, which has them; ``belt``: ``(mm_s,
    counts_per_mm, axis)``, the simulated board's belt runs so under its encoder from the
    start, as a real one would under a board; one line, nothing sent, for one its encoder
    cannot count; ``sensor``: :meth:`~galvoscan.sim.board.SimulatedBoard.parts_arrive`'s
    keywords, the simulated line's part sensor, set before the first byte)."""
    if args.sim:
        # (The ULX3S's bitstream at its own rate unless told another: the profile's baud is
        # the real machine's link.)
        baud_rate = link_baud(args, profile)
        if args.board == "ulx3s":
            config, contents = simulated_bitstream("ulx3s", baud=baud_rate)
            board = simulated_board(args, config=config, **contents)
        elif pixel_lines and not wobble:
            config, contents = simulated_bitstream("icebreaker", preset="engraver",
                                                   baud=baud_rate)
            board = simulated_board(args, config=config, **contents)
        else:
            board = simulated_board(args, baud=baud_rate, **({"wobble": True} if wobble else {}))
        if belt is not None:
            mm_s, counts_per_mm, axis = belt
            try:
                board.belt_moves(mm_s, counts_per_mm, axis=axis)
            except ValueError as error:
                fail(f"the simulated board's belt: {error}")
        if sensor is not None:
            board.parts_arrive(**sensor)
        timeout = args.timeout or board.answer_timeout_s()
        server = PTYServer(board).start()
        try:
            with SerialTransport(server.port, baud=baud_rate, timeout=timeout) as transport:
                yield HostClient(transport), board
        finally:
            server.stop()
            if server.error is not None:
                failed(f"the simulated board stopped: {server.error}")
        return
    baud_rate = link_baud(args, profile)
    transport = open_transport(port=args.port or (None if args.spi else profile.link.port),
                               spi=args.spi or (None if args.port else profile.link.spi),
                               baud=baud_rate, timeout=args.timeout or profile.link.timeout_s)
    with transport:
        yield HostClient(transport), None


@contextlib.contextmanager
def stopped_in_one_line(*, on_complete=None):
    """A job the board stopped, or a link that failed, as one line and a non-zero exit (the
    streamer has already sent arm = 0). ``on_complete()``: called first when the job was
    marked to its end before it stopped (a part that is done: its serial number is taken);
    it returns words to add to the line."""
    try:
        yield
    except JobInterrupted as error:
        more = on_complete() if error.complete and on_complete is not None else ""
        raise JobInterrupted(f"{error}{more}") from error
    except JobRefused as error:
        failed(f"job refused: {error}")
    except JobAborted as error:
        more = on_complete() if error.complete and on_complete is not None else ""
        failed(f"job stopped, laser disarmed: {error}{more}")
    except (ClientError, OSError) as error:
        failed(f"job stopped, laser disarm sent: the link failed: {error}")


def frame_job(streamer, profile, outline_mm, times, registers, *, timeout_s, say, what):
    """Trace ``outline_mm`` (a closed outline) ``times`` times in vector mode with the guide
    laser on and the laser never armed (``registers``: the vector settings to walk it with)."""
    if not profile.laser.guide:
        fail("the machine profile says there is no guide laser ([laser] guide)")
    segments = frame_segments(outline_mm, profile.field.size_mm, times)
    streamer.run_vector(segments, dict(registers, guide=1, laser_power=0), armed=False,
                        timeout_s=timeout_s)
    say(f"framed the {what}'s outline {times} time(s) with the guide laser; the laser stayed "
        f"off")


def progress_bar(total, unit, *, disable=None):
    """A tqdm bar on stderr (off when stderr is not a terminal, unless asked)."""
    return tqdm(total=total, unit=unit, file=sys.stderr, leave=False,
                disable=(not sys.stderr.isatty()) if disable is None else disable)
