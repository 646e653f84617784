"""SkyWriting's settings (SCANLAB RTC5/6's names), each declared once: the mode, Timelag,
LaserOnShift, Nprev, Npost and Limit.

SkyWriting runs the mirrors through a mark's ends at the mark's own speed: a run-in of
``nprev_us`` before its first point and a run-out of ``npost_us`` after its last, laser off
(mode 1); modes 2 and 3 also take corners between two marks apart into run-out, jump and
run-in (mode 2 at every corner that turns, mode 3 only where cos φ < ``sky_limit``, φ the
turn). The laser switches ``timelag_us`` (the head's tracking error) after the set point
crosses a mark's ends, laser-on moved by ``laser_on_shift_us``; the laser and polygon delays
are not used while it is on. Times are in µs here (RTC counts Nprev and Npost in 10 µs ticks;
galvoscan turns them into whole points at the mark's speed, at least as long as asked).

``mark``'s ``--sky``, ``--timelag``, ``--laser-on-shift``, ``--nprev``, ``--npost`` and
``--sky-limit`` are made from these (:mod:`galvoscan.cli.job_options`), a job file's
``[job]`` keys and a layer's keys read with them, and the machine profile's ``[sky]`` holds
the machine's own (:mod:`.machine`).
"""

from ..gateware.host.regmap import BY_NAME
from .schema import Setting


__all__ = ["MODE_DEFAULT", "SHIFT_DEFAULT", "LIMIT_DEFAULT", "SKY", "TIMELAG", "LASER_ON_SHIFT", "NPREV", "NPOST", "SKY_LIMIT", "SKY_SETTINGS",
           "NPREV_SHARE", "NPOST_SHARE", "RUN_MAX_US"]


#: The machine profile's ``[sky]`` defaults: SkyWriting off, no shift, mode 3's Limit (a
#: corner turning more than 60° taken apart: galvoscan's choice).
MODE_DEFAULT = 0
SHIFT_DEFAULT = 0.0
LIMIT_DEFAULT = 0.5
#: RTC's defaults for Nprev and Npost: these shares of Timelag.
NPREV_SHARE = 0.15
NPOST_SHARE = 0.1
#: The longest run-in or run-out, µs (10 ms: ten times the longest Timelag).
RUN_MAX_US = 10_000
#: Timelag becomes ``laser_off_delay`` and Timelag + LaserOnShift ``laser_on_delay``: the
#: registers' ranges bound them.
_ON, _OFF = BY_NAME["laser_on_delay"], BY_NAME["laser_off_delay"]

_PROFILE = "the profile's [sky]"

SKY = Setting("sky_mode", "integer", "", 0, 3, what="--sky", flag="--sky", key="sky",
              metavar="MODE", default_said=f"{_PROFILE} mode, {MODE_DEFAULT}",
              help="SkyWriting (RTC's modes): 0 off; 1 every mark run in and out at its own "
                   "speed with the laser off, the laser switched Timelag after the mirrors' "
                   "set point crosses its ends; 2 also every corner between two marks taken "
                   "apart into run-out, jump and run-in; 3 only the corners sharper than "
                   "--sky-limit. Needs a bitstream with pixel lines (the ULX3S's, build "
                   "--preset engraver)")
TIMELAG = Setting("timelag_us", "number", "µs", 0, _OFF.high, what="timelag",
                  flag="--timelag", key="timelag", metavar="US",
                  default_said=f"{_PROFILE} timelag_us, else [galvo] tracking_delay_us",
                  help="SkyWriting's Timelag: how far the mirrors lag their set point (the "
                       "head's tracking error); the laser switches this long after the set "
                       "point crosses a mark's ends")
LASER_ON_SHIFT = Setting("laser_on_shift_us", "number", "µs", -_ON.high, _ON.high,
                         what="laser-on shift", flag="--laser-on-shift", key="laser_on_shift",
                         metavar="US",
                         default_said=f"{_PROFILE} laser_on_shift_us, {SHIFT_DEFAULT:g}",
                         help="SkyWriting's LaserOnShift: laser-on moved by this (negative: "
                              "earlier); Timelag + it must be from 0 to "
                              f"{_ON.high} µs")
NPREV = Setting("nprev_us", "number", "µs", 0, RUN_MAX_US, what="nprev", flag="--nprev",
                key="nprev", metavar="US",
                default_said=f"{_PROFILE} nprev_us, else {NPREV_SHARE:g} × Timelag",
                help="SkyWriting's Nprev: the run-in before each mark, at its speed, laser "
                     "off (whole points, at least this long)")
NPOST = Setting("npost_us", "number", "µs", 0, RUN_MAX_US, what="npost", flag="--npost",
                key="npost", metavar="US",
                default_said=f"{_PROFILE} npost_us, else {NPOST_SHARE:g} × Timelag",
                help="SkyWriting's Npost: the run-out after each mark, at its speed, laser off "
                     "(whole points, at least this long)")
SKY_LIMIT = Setting("sky_limit", "number", "", -1, 1, what="sky limit", flag="--sky-limit",
                    key="sky_limit", metavar="COS",
                    default_said=f"{_PROFILE} limit, {LIMIT_DEFAULT:g}",
                    help="SkyWriting mode 3's Limit: a corner is taken apart where cos φ is "
                         "below it (φ the turn: 1 straight on, 0 a right angle, -1 a "
                         "reversal); the others keep the polygon delay")

#: Every SkyWriting setting, in ``--help``'s order.
SKY_SETTINGS = (SKY, TIMELAG, LASER_ON_SHIFT, NPREV, NPOST, SKY_LIMIT)
