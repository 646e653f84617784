"""Marking on the fly's settings, each declared once: the axis the belt carries the part along,
the encoder (a real one's counts a mm, or the board's simulated one's belt speed), the belt's
direction on the field and its top speed, and the board's clock (the simulated encoder counts
in its clocks).

``mark``'s ``--fly``, ``--encoder``, ``--fly-speed``, ``--fly-direction`` and
``--belt-speed`` are made from these (:mod:`galvoscan.cli.job_options`), a job file's
``[job]`` keys read with them, and the machine profile's ``[fly]`` holds the machine's own
(the encoder, the direction, the belt's speed, the clock: :mod:`.machine`).
"""

from ..platforms.ulx3s import ULX3S_CLOCK_HZ
from .schema import Setting


__all__ = ["FLY", "ENCODER", "FLY_SPEED", "FLY_DIRECTION", "BELT_SPEED", "BOARD_CLOCK",
           "SIM_COUNTS_PER_MM", "AXES", "DIRECTIONS"]


#: The axes of the field a belt may carry the part along.
AXES = ("X", "Y")
#: Which way along it: towards + or towards −.
DIRECTIONS = ("+", "-")

#: The board's simulated encoder, as galvoscan runs it: 1,000 counts a mm (a µm a count). Its
#: count period (``fly_sim_period``, whole clocks) is the board's clock over speed × this,
#: rounded: 100, 250 or 500 mm/s are made exactly at 24, 12 and 8 MHz, another speed to the
#: nearest whole clock (the plan says the speed it runs at), and from 1 to 4,000 mm/s the
#: period stays within 2 … 65,535 clocks on any clock from 8 MHz to 65 MHz.
SIM_COUNTS_PER_MM = 1000

_PROFILE = "the profile's [fly]"

FLY = Setting("fly", "choice", what="fly", flag="--fly", key="fly", choices=AXES,
              help="mark on the fly: a belt carries the part along this axis of the field while "
                   "it is marked, and every point follows it (the encoder's count × a scale, "
                   "added on the board before the correction); needs --encoder or --fly-speed "
                   "and a bitstream with the fly (the ULX3S's)")
ENCODER = Setting("encoder_counts_per_mm", "number", "counts/mm", 1, 10_000, what="encoder",
                  flag="--encoder", key="encoder", metavar="COUNTS_PER_MM",
                  default_said=f"{_PROFILE} counts_per_mm",
                  help="the belt's encoder, on the board's ENCODER input of --fly's axis: its "
                       "counts a mm of belt (every edge of A and B, 4 an increment), counting "
                       "up as the belt runs (else swap A and B); its direction on the field is "
                       "--fly-direction's")
FLY_SPEED = Setting("fly_speed_mm_s", "number", "mm/s", 1, 4000, what="fly speed",
                    flag="--fly-speed", key="fly_speed", metavar="MM_S",
                    help=f"instead of --encoder: the board's simulated encoder "
                         f"({SIM_COUNTS_PER_MM:,} counts/mm, for trials without a belt), a belt "
                         f"at this speed")
FLY_DIRECTION = Setting("fly_direction", "choice", what="fly direction",
                        flag="--fly-direction", key="fly_direction", choices=DIRECTIONS,
                        default_said=f"{_PROFILE} direction",
                        help=f"which way the belt carries the part along --fly's axis: + "
                             f"towards +X (or +Y), - towards -X (default: {_PROFILE} "
                             f"direction, +)")
BELT_SPEED = Setting("belt_speed_mm_s", "number", "mm/s", 0.1, 10_000, what="belt speed",
                     flag="--belt-speed", key="belt_speed", metavar="MM_S",
                     default_said=f"{_PROFILE} belt_speed_mm_s",
                     help="with --encoder: the belt's top speed, to check that the part stays "
                          "in the field until the job is done (with --sim, the simulated "
                          "board's belt runs at it)")
BOARD_CLOCK = Setting("board_clock_mhz", "number", "MHz", 1, 275,
                      default=ULX3S_CLOCK_HZ / 1e6,
                      help="the board's system clock, as its bitstream was built (the ULX3S's "
                           "24 MHz): the simulated encoder counts in its clocks")
