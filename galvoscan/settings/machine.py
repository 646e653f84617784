"""The machine's own settings, and every key of the machine profile, each declared once.

The profile (:mod:`galvoscan.profile`) holds what a job needs to know about the machine that
the board's registers do not: the lens's field, the link, the laser, how long the mirrors
take to settle, and the job settings to use when the command line gives none. :data:`PROFILE`
is each of its sections and their keys (:class:`~.schema.ProfileKey`), in the order the
template writes them: the keys that are a job's or a run's settings hold :mod:`.laser`'s, the
others the settings declared here. The profile checks a file's values by these, its template
says their ranges from them, and the docs' table of them is generated from them
(:func:`~.schema.profile_table`).

The delays are the board's registers (``jump_delay``, ``laser_on_delay``, …): their ranges
are read from the register map, and the same settings are a layer's delay keys
(:data:`DELAYS`), whole µs there, any number of µs in the profile (rounded when written).
"""

from ..gateware.clocking import DEFAULT_BAUD
from ..gateware.host.regmap import BY_NAME, FRAME_US
from .laser import BAUD, LINK_TIMEOUT_S, PASSES, POWER, PRR, SPEED, TIMEOUT, WOBBLE, \
    WOBBLE_ALONG, WOBBLE_HZ
from .fly import BELT_SPEED, BOARD_CLOCK, ENCODER, FLY_DIRECTION
from .sky import (LASER_ON_SHIFT, LIMIT_DEFAULT, MODE_DEFAULT, NPOST, NPREV, SHIFT_DEFAULT, SKY,
                  SKY_LIMIT, TIMELAG)
from .schema import ProfileKey, Setting


__all__ = ["SIZE", "CORRECTION", "Z_UNITS", "PORT", "SPI", "MAX_POWER", "SPOT", "GUIDE", "JUMP_DELAY",
           "MIN_JUMP_DELAY", "JUMP_LENGTH_LIMIT", "MAX_SPEED", "TRACKING_DELAY", "LASER_ON_DELAY", "LASER_OFF_DELAY", "MARK_DELAY",
           "POLYGON_DELAY", "POLYGON_SCALED", "DELAYS", "LASER_DELAYS", "PROFILE"]


SIZE = Setting("size_mm", "number", "mm", 1, 2000, default=110.0,
               help="side of the square marking field: the f-theta lens's, which galvo "
                    "positions 0 … 65535 span")
CORRECTION = Setting("correction", "path",
                     help="the lens's distortion correction table (a galvoscan .json, a "
                          "SCANLAB .ctb or a JCZ .cor), relative to the profile's folder; "
                          "none: no correction")
Z_UNITS = Setting("z_units_per_mm", "number", "units/mm", 0, 65_535, default=0.0,
                  help="the focus shifter on XY2-100's Z channel (SCANLAB's varioSCAN, a "
                       "ULX3S bitstream's GP2): its galvo units a mm of focus shift, from its "
                       "data sheet or a focus test; Z 0 mm is its middle, 32768; 0: none "
                       "(--z refused)")
PORT = Setting("port", "text", help="serial port of the board; none: --port on the command "
                                    "line")
SPI = Setting("spi", "text", help="instead of port: the pyftdi URL of an FTDI SPI adapter "
                                  "wired to the board")
MAX_POWER = Setting("max_power_w", "number", "W", 0.1, 10_000, default=20.0,
                    help="average power of the laser at 100 % (its rating)")
SPOT = Setting("spot_mm", "number", "mm", 0.001, 10, default=0.05,
               help="spot diameter at focus: what line spacings and previews are drawn from")
GUIDE = Setting("guide", "bool", default=True,
                help="a guide (red pointer) laser is wired to the board's guide output")
JUMP_LENGTH_LIMIT = Setting("jump_length_limit_mm", "number", "mm", 0, 3000, default=5.0,
                            help="jumps this long or longer wait jump_delay_us, shorter ones "
                                 "from min_jump_delay_us up in proportion to their length "
                                 "(RTC's variable jump delay); 0: every jump waits "
                                 "jump_delay_us")
MAX_SPEED = Setting("max_speed_mm_s", "number", "mm/s", 1, 100_000, default=10_000.0,
                    help="fastest marking speed a job may ask for (the scan head's)")
TRACKING_DELAY = Setting("tracking_delay_us", "number", "µs", 0, 2000, default=80.0,
                         help="how far in time the mirrors lag their set point on a line at "
                              "constant speed (their tracking error): a pixel line is sent "
                              "this far ahead of the pixels, and run in and out over three "
                              "times it")
HEAD_CHECK = Setting("head_check", "bool", default=False,
                     help="the scan head answers on its XY2-100 STATUS line and the laser "
                          "obeys it: Temp OK or Power OK low, or no answer, keeps the laser "
                          "off and stops a job (a bitstream built with --head-status); off "
                          "for a head without the line, which would read as missing")
POLYGON_SCALED = Setting("polygon_scaled", "bool", default=True,
                         help="each corner's polygon delay scaled by (1 - cos φ), φ the turn "
                              "at the corner (RTC's variable polygon delay)")


def _delay(register, help):
    """The delay register ``register`` as a setting: whole µs in its range."""
    found = BY_NAME[register]
    assert found.unit.startswith("µs"), f"{register}'s unit changed: update its setting"
    return Setting(register, "integer", "µs", found.low, found.high,
                   what=register.replace("_", " "), key=register, help=help)


JUMP_DELAY = _delay("jump_delay", f"laser-off wait after every jump, for the mirrors to settle "
                                  f"(rounded up to whole {FRAME_US} µs frames)")
#: The jump delay of the shortest jump (RTC's MinJumpDelay): not a register of its own, but
#: what the host works a jump's delay out from, so the register's range.
MIN_JUMP_DELAY = Setting("min_jump_delay_us", "number", "µs", JUMP_DELAY.low, JUMP_DELAY.high,
                         default=240.0,
                         help="laser-off wait after a jump of length 0, at most jump_delay_us "
                              "(left out: jump_delay_us if that is less): a jump shorter than "
                              "jump_length_limit_mm waits in proportion between the two")
LASER_ON_DELAY = _delay("laser_on_delay", "the laser switches on this long after a mark's "
                                          "first point (negative: before)")
LASER_OFF_DELAY = _delay("laser_off_delay", "the laser stays on this long after a mark's last "
                                            "point")
MARK_DELAY = _delay("mark_delay", "the mirrors hold a mark's end this long, laser off, before "
                                  "the next jump")
POLYGON_DELAY = _delay("polygon_delay", "the mirrors hold each corner between two marks this "
                                        "long, laser on")

#: The delays a layer may set: the jump delay and :data:`LASER_DELAYS`.
DELAYS = (JUMP_DELAY, LASER_ON_DELAY, LASER_OFF_DELAY, MARK_DELAY, POLYGON_DELAY)
#: The laser and scanner delays (SCANLAB's RTC's), written as they are before every job.
LASER_DELAYS = DELAYS[1:]


def _keys(section, *keys):
    """``[section]``'s keys: ``(name, setting, keywords of its ProfileKey)``."""
    return tuple(ProfileKey(section, name, setting, **how) for name, setting, how in keys)


#: Every section of the machine profile and its keys, in the template's order.
PROFILE = {
    "field": _keys("field", ("size_mm", SIZE, {}), ("correction", CORRECTION, {}),
                   ("z_units_per_mm", Z_UNITS, {})),
    "link": _keys("link", ("port", PORT, {}),
                  ("baud", BAUD, dict(default=DEFAULT_BAUD, kind="integer",
                                      help="serial rate in baud, as the bitstream was built")),
                  ("spi", SPI, {}),
                  ("timeout_s", TIMEOUT, dict(default=LINK_TIMEOUT_S))),
    "laser": _keys("laser", ("max_power_w", MAX_POWER, {}),
                   ("prr_khz", PRR, dict(default=PRR.range, kind="pair",
                                         help="the pulse repetition rates the laser accepts "
                                              "(the board's range, narrowed to the laser's)")),
                   ("spot_mm", SPOT, {}), ("guide", GUIDE, {})),
    # The delays' defaults are what `galvoscan analyze --delays` finds for Wan et al.'s JD1403
    # galvo at 1 m/s (galvoscan.profile.machine.GalvoSection).
    # The jump delays are RTC's variable jump delay (JumpDelay, MinJumpDelay and
    # JumpLengthLimit): their defaults, and where they come from, are the template's comment.
    "galvo": _keys("galvo", ("jump_delay_us", JUMP_DELAY, dict(
                       default=500.0, kind="number",
                       help=f"laser-off wait after a jump of jump_length_limit_mm or longer, "
                            f"for the mirrors to settle (rounded up to whole {FRAME_US} µs "
                            f"frames)")),
                   ("min_jump_delay_us", MIN_JUMP_DELAY, {}),
                   ("jump_length_limit_mm", JUMP_LENGTH_LIMIT, {}),
                   ("max_speed_mm_s", MAX_SPEED, {}),
                   ("laser_on_delay_us", LASER_ON_DELAY, dict(default=100.0, kind="number")),
                   ("laser_off_delay_us", LASER_OFF_DELAY, dict(default=50.0, kind="number")),
                   ("mark_delay_us", MARK_DELAY, dict(default=100.0, kind="number")),
                   ("polygon_delay_us", POLYGON_DELAY, dict(default=0.0, kind="number")),
                   ("polygon_scaled", POLYGON_SCALED, {}),
                   ("tracking_delay_us", TRACKING_DELAY, {}),
                   ("head_check", HEAD_CHECK, {})),
    "defaults": _keys("defaults", ("speed_mm_s", SPEED, dict(default=1000.0)),
                      ("power_percent", POWER, dict(default=10.0)),
                      ("prr_khz", PRR, dict(default=50.0, help="pulse repetition rate, within "
                                                               "[laser] prr_khz")),
                      ("passes", PASSES, dict(default=1))),
    "wobble": _keys("wobble",
                    ("across_um", WOBBLE, dict(default=0.0, help=(
                        "wobble amplitude across the line (to each side); 0 here and in "
                        "along_um: no wobble"))),
                    ("along_um", WOBBLE_ALONG, dict(default=0.0)),
                    ("freq_hz", WOBBLE_HZ, dict(default=1000.0))),
    # Marking on the fly: the machine's belt and the board's clock (`mark --fly`).
    "fly": _keys("fly",
                 ("counts_per_mm", ENCODER, dict(help=(
                     "the belt's encoder: counts a mm of belt (every edge of A and B), counting "
                     "up as the belt runs; none: no encoder (mark --fly then needs --encoder "
                     "or --fly-speed)"))),
                 ("direction", FLY_DIRECTION, dict(default="+", help=(
                     "which way the belt carries the part along mark --fly's axis: + towards "
                     "+X (or +Y), - towards -X"))),
                 ("belt_speed_mm_s", BELT_SPEED, dict(help=(
                     "the belt's top speed: a job on the fly is refused if the part would "
                     "leave the field at it before the job is done"))),
                 ("board_clock_mhz", BOARD_CLOCK, {})),
    # SkyWriting (`mark --sky`): the machine's own Timelag and runs, and the mode jobs take.
    "sky": _keys("sky",
                 ("mode", SKY, dict(default=MODE_DEFAULT, help=(
                     "SkyWriting's mode for jobs that do not give --sky: 0 off; 1 every mark "
                     "run in and out at its speed, laser off; 2 also every corner taken "
                     "apart; 3 the corners sharper than limit"))),
                 ("timelag_us", TIMELAG, dict(help=(
                     "SkyWriting's Timelag, the head's tracking error; none: [galvo] "
                     "tracking_delay_us"))),
                 ("laser_on_shift_us", LASER_ON_SHIFT, dict(default=SHIFT_DEFAULT)),
                 ("nprev_us", NPREV, dict(help=(
                     "SkyWriting's run-in before each mark; none: 0.15 × Timelag"))),
                 ("npost_us", NPOST, dict(help=(
                     "SkyWriting's run-out after each mark; none: 0.1 × Timelag"))),
                 ("limit", SKY_LIMIT, dict(default=LIMIT_DEFAULT))),
}
