"""The settings a job is marked at and a run talks to its board with, each declared once:
marking speed, laser power, pulse repetition rate, passes, pulses per point, wobble, chord
tolerance and the link's answer timeout and rate.

``mark``, ``clean``, ``store`` and ``test-grid`` build their options from these, a job file's
``[job]`` and a layer's keys read with them, and the machine profile's ``[defaults]``,
``[wobble]``, ``[laser] prr_khz`` and ``[link] baud`` and ``timeout_s`` hold them
(:mod:`.machine`). Ranges a register fixes (the PRR, pulses per point, the wobble's
frequency) are read from the register map, so that no setting can ask for what the board
cannot hold.
"""

from ..gateware.clocking import DEFAULT_BAUD
from ..gateware.host.regmap import BY_NAME
from ..gateware.limits import WOBBLE_MAX_HZ
from .schema import Setting, number_text


__all__ = ["SPEED", "POWER", "PRR", "PASSES", "PULSES", "WOBBLE", "WOBBLE_ALONG", "WOBBLE_HZ",
           "TOLERANCE", "Z", "TIMEOUT", "LINK_TIMEOUT_S", "BAUD", "PRESS_TIMEOUT", "ALL",
           "JOB_SETTINGS", "PRR_STEPS_PER_KHZ"]


_PRR_REGISTER = BY_NAME["laser_prr"]
#: Steps of ``laser_prr`` per kHz (its unit is 100 Hz).
PRR_STEPS_PER_KHZ = 10
assert _PRR_REGISTER.unit == "100 Hz", "laser_prr's unit changed: update PRR_STEPS_PER_KHZ"

_DEFAULTS = "the profile's [defaults]"
_WOBBLE = "the profile's [wobble]"

SPEED = Setting("speed_mm_s", "number", "mm/s", 0.1, 100_000, what="speed", flag="--speed",
                key="speed", metavar="MM_S", help="marking speed",
                default_said=_DEFAULTS)
POWER = Setting("power_percent", "number", "%", 0, 100, what="power", flag="--power",
                key="power", metavar="PERCENT", help="laser power, of the laser's maximum",
                default_said=_DEFAULTS)
PRR = Setting("prr_khz", "number", "kHz", _PRR_REGISTER.low / PRR_STEPS_PER_KHZ,
              _PRR_REGISTER.high / PRR_STEPS_PER_KHZ, what="PRR (kHz)", flag="--prr",
              key="prr", metavar="KHZ", default_said=_DEFAULTS,
              help="pulse repetition rate (the board's range; the profile's laser may allow "
                   "less)")
PASSES = Setting("passes", "integer", "", 1, 1000, what="passes", flag="--passes",
                 key="passes", metavar="N", help="times the job is marked",
                 default_said=_DEFAULTS)
_PULSES_REGISTER = BY_NAME["pulses_per_point"]
#: A layer's ``pulses``: the pitch follows the speed, not the other way round.
PULSES = Setting("pulses_per_point", "integer", "", _PULSES_REGISTER.low,
                 _PULSES_REGISTER.high, what="pulses per point", key="pulses",
                 flag="--pulses-per-point", metavar="N",
                 help="laser pulses a point (the pitch then follows the speed)")
WOBBLE = Setting("wobble_um", "number", "µm", 0, 10_000, what="wobble", flag="--wobble",
                 key="wobble", metavar="UM", default_said=_WOBBLE,
                 help="wobble amplitude across the line (to each side); a circle unless "
                      "--wobble-along; 0: no wobble")
WOBBLE_ALONG = Setting("wobble_along_um", "number", "µm", 0, 10_000, what="wobble-along",
                       flag="--wobble-along", key="wobble_along", metavar="UM",
                       default_said=_WOBBLE,
                       help="wobble amplitude along the line (an ellipse)")
WOBBLE_HZ = Setting("wobble_hz", "number", "Hz", BY_NAME["wob_freq"].low, WOBBLE_MAX_HZ,
                    what="wobble-hz", flag="--wobble-hz", key="wobble_hz", metavar="HZ",
                    default_said=_WOBBLE,
                    help="turns of the wobble's figure a second")
Z = Setting("z_mm", "number", "mm", -100, 100, what="Z", flag="--z", key="z", metavar="MM",
            help="focus shift on XY2-100's Z channel (a focus shifter, [field] z_units_per_mm "
                 "in the profile; a bitstream with the Z channel, the ULX3S's): + away from "
                 "the lens; default 0, the shifter's middle: a job that gives no Z is marked "
                 "there, whatever the job before it left)")
TOLERANCE = Setting("tolerance_mm", "number", "mm", 0.0005, 1, default=0.01,
                    what="tolerance", flag="--tolerance", key="tolerance", metavar="MM",
                    help="curves as chords at most this far off")
#: The link's answer timeout when neither the command line nor a profile gives one, s.
LINK_TIMEOUT_S = 0.5
#: Up to 600 s: the answer timeout ``board --sim`` advises for its slowest backend
#: (:meth:`galvoscan.sim.board.SimulatedBoard.answer_timeout_s` is held to this range).
TIMEOUT = Setting("timeout_s", "number", "s", 0.01, 600, what="timeout", flag="--timeout",
                  metavar="S", help="seconds to wait for the board's answer",
                  default_said=f"{number_text(LINK_TIMEOUT_S)} (read, send, …); a job's: the "
                               f"profile's [link], with --sim the simulator's measured speed")

#: The host link's serial rate: a number as a person writes it (``1e6``), whole. ``build``'s
#: ``--baud`` (the bitstream's), the link options' and the profile's ``[link] baud``.
BAUD = Setting("baud", "number", "baud", 300, 12e6, what="baud", flag="--baud", metavar="BAUD",
               help="serial rate of the bitstream",
               default_said=f"{number_text(DEFAULT_BAUD)} (build, read, send, …); a job's: the "
                            f"profile's [link]")
#: ``standalone --timeout``: not the link's answer timeout but the most of the simulated
#: board's own time a press of its start input may take (whole seconds).
PRESS_TIMEOUT = Setting("press_timeout_s", "integer", "s", 1, 3600, default=600,
                        what="timeout", flag="--timeout", metavar="S",
                        help="the most of the board's own time a press may take")

#: A job's own settings, which a layer may change: by the key a job file and a layer use.
JOB_SETTINGS = {s.key: s for s in (SPEED, POWER, PRR, PASSES, WOBBLE, WOBBLE_ALONG,
                                   WOBBLE_HZ, Z)}

#: The settings docs/reference/settings.md lists, in its order (``standalone``'s press timeout is that
#: command's own).
ALL = (SPEED, POWER, PRR, PASSES, TOLERANCE, WOBBLE, WOBBLE_ALONG, WOBBLE_HZ, Z, TIMEOUT,
       BAUD)
