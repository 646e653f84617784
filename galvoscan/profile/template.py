"""The commented machine profile template: :func:`profile_text`, the file ``galvoscan machine
init`` writes (every key with its default, unit, range and purpose).

The ranges and their units are read from the key table
(:data:`galvoscan.profile.keys.SECTIONS`, the declarations of :mod:`galvoscan.settings.machine`)
and the defaults from :func:`galvoscan.profile.machine.default_profile` (the declarations'
too), so the template cannot disagree with what is checked.
"""

from ..link.client import frame_seconds
from .keys import FRAME_US, POWER_REGISTER_MAX, SECTIONS, _toml_num
from ..settings.sky import NPOST_SHARE, NPREV_SHARE
from .machine import _LASER_ON_HIGH_US, DEFAULT_PROFILE_NAME, default_profile


def _key(section, name):
    return next(k for k in SECTIONS[section] if k.name == name)


def _span(section, name):
    """A key's range and unit, as its key table has them: ``1 … 2_000 mm``."""
    key = _key(section, name)
    unit = f" {key.unit}" if key.unit else ""
    return f"{_toml_num(key.low)} … {_toml_num(key.high)}{unit}"


def profile_text():
    """The commented profile ``galvoscan machine init`` writes: the defaults, every key
    explained (unit, range, purpose)."""
    d = default_profile()
    # A jump and its mark: two frames on the line (the streamer's reads of the queue, one a
    # batch of 128, aside).
    link_us = round(2 * frame_seconds(d.link.baud) * 1e6)
    s = _span
    n = _toml_num
    return f"""\
# galvoscan machine profile
#
# What a marking or cleaning job needs to know about this machine that the board's
# registers do not hold: the lens's field, the laser, how long the mirrors take to
# settle, and the job settings to use when the command line gives none.
# `galvoscan mark` and `galvoscan clean` read ./{DEFAULT_PROFILE_NAME} (or the file given
# with --machine FILE); `galvoscan machine show` prints what this file resolves to.
#
# Every key may be left out: the value written here is its default. A key galvoscan
# does not know is an error, not ignored, so that a typo cannot pass unnoticed.
# Units are in the key names: _mm, _w (watts), _khz, _us (microseconds), _s (seconds).
#
# Edit first: [link] port, [field] size_mm and [laser] max_power_w.

[field]
# Side of the square marking field, in mm: the field of the f-theta lens, which the
# whole galvo range (positions 0 … 65535 on each axis) spans. Take it from the lens's
# data sheet (110 for the common F160 lens); a wrong value scales every job.
# {s("field", "size_mm")}.
size_mm = {n(d.field.size_mm)}
# Distortion correction table for this lens: a galvoscan .json (`galvoscan correct`),
# a SCANLAB .ctb or a JCZ (EzCad) .cor file. A relative path is relative to the folder
# of this file. Left out, the board's identity table is used: no correction.
# correction = "f160.cor"
# The focus shifter on XY2-100's Z channel (SCANLAB's varioSCAN; a ULX3S bitstream drives
# it on GP2): its galvo units a mm of focus shift, from its data sheet or a focus test.
# `mark --z MM` (and a layer's z) shifts the focus by MM; Z 0 is the shifter's middle.
# 0: no focus shifter, and --z is refused. {s("field", "z_units_per_mm")}.
z_units_per_mm = {n(d.field.z_units_per_mm)}

[link]
# Serial port of the board: on Linux usually the second of its two /dev/ttyUSB ports,
# on Windows a COM port. Left out, give --port on the command line. Set port or spi,
# not both.
# port = "/dev/ttyUSB1"
# Serial rate in baud, as the bitstream was built. {s("link", "baud")}.
baud = {n(d.link.baud)}
# Instead of port: the pyftdi URL of an FTDI SPI adapter wired to the board.
# spi = "ftdi://ftdi:2232h/1"
# Seconds to wait for the board to answer before giving up. {s("link", "timeout_s")}.
timeout_s = {n(d.link.timeout_s)}

[laser]
# Average power of the laser at 100 % (laser_power register {POWER_REGISTER_MAX}), in W: its
# rating. Jobs set power in %; it is shown in W from this. {s("laser", "max_power_w")}.
max_power_w = {n(d.laser.max_power_w)}
# Pulse repetition rates the laser accepts, in kHz: [lowest, highest]. The board makes
# {s("laser", "prr_khz")}; narrow it to your laser's data sheet (a job asking for a
# rate outside it is refused).
prr_khz = [{n(d.laser.prr_khz[0])}, {n(d.laser.prr_khz[1])}]
# Spot diameter at focus, in mm (the lens data sheet, or measure the mark of single
# pulses): what line spacings and previews are drawn from. {s("laser", "spot_mm")}.
spot_mm = {n(d.laser.spot_mm)}
# true if the machine has a guide (red pointer) laser wired to the board's guide output
# (laser_guide), to frame a job before marking; false if not. The guide laser's pin on
# the DB25 differs between lasers: see the wiring table (docs/hardware/wiring.md).
guide = {"true" if d.laser.guide else "false"}

[galvo]
# The wait after a jump, laser off, for the mirrors to settle before marking resumes,
# in µs, grows with the jump's length as in SCANLAB's RTC (its variable jump delay: the
# jump delay of set_scanner_delays, and MinJumpDelay and JumpLengthLimit of
# set_delay_mode): a jump of jump_length_limit_mm or longer waits jump_delay_us, a
# shorter one min_jump_delay_us and the difference in proportion to its length. The
# board counts {FRAME_US} µs frames: each wait is rounded up to a whole frame. A photo's
# thousands of short gaps between dark cells so no longer each wait as long as a jump
# across the field.
# The defaults: a 10 mm head's, as `galvoscan analyze` models it (the JD1403 galvo of
# Wan et al. 2018: a 1 % step settles in 0.3 ms, a 10 % step in 0.7 ms), where a 0.2 mm
# jump comes within 10 µm of its end in about 200 µs and a 5 mm one in about 515 µs;
# and the link: at {d.link.baud:,} baud it takes {link_us} µs to bring a jump and its mark, so
# short jumps waiting less would let a photo empty the board's queue. Measure your
# head's with a test mark and set these from it.
# Wait after a jump of jump_length_limit_mm or longer. {s("galvo", "jump_delay_us")}.
jump_delay_us = {n(d.galvo.jump_delay_us)}
# Wait after the shortest jump (length 0): at most jump_delay_us (left out, and more
# than a jump_delay_us given: jump_delay_us, every jump waiting that).
# {s("galvo", "min_jump_delay_us")}.
min_jump_delay_us = {n(d.galvo.min_jump_delay_us)}
# The jump length from which every jump waits jump_delay_us, in mm; 0: every jump
# waits jump_delay_us, whatever its length. {s("galvo", "jump_length_limit_mm")}.
jump_length_limit_mm = {n(d.galvo.jump_length_limit_mm)}
# Fastest marking or cleaning speed a job may ask for, in mm/s: faster is refused. Take
# it from the scan head's data sheet. {s("galvo", "max_speed_mm_s")}.
max_speed_mm_s = {n(d.galvo.max_speed_mm_s)}
# The laser and scanner delays of SCANLAB's RTC (EzCad's start, end and corner TC): the
# mirrors lag the set point by their tracking error (about 100-200 µs on a 10 mm head), so
# without them a line starts and ends with a burnt dot and corners over-dose. Tune them with
# a test mark (docs/design/modes.md, "Laser and scanner delays"). The laser delays are placed to the
# board's clock; mark and polygon delays are rounded up to {FRAME_US} µs frames.
# Laser on this long after a mark's first point; negative: that much before.
# {s("galvo", "laser_on_delay_us")}.
laser_on_delay_us = {n(d.galvo.laser_on_delay_us)}
# Laser stays on this long after a mark's last point. {s("galvo", "laser_off_delay_us")}.
laser_off_delay_us = {n(d.galvo.laser_off_delay_us)}
# Mirrors hold a mark's end this long, laser off, before the next jump; keep it above
# laser_off_delay_us (RTC's rule). {s("galvo", "mark_delay_us")}.
mark_delay_us = {n(d.galvo.mark_delay_us)}
# Mirrors hold each corner between two marks this long, laser on.
# {s("galvo", "polygon_delay_us")}.
polygon_delay_us = {n(d.galvo.polygon_delay_us)}
# true: scale each corner's polygon delay by (1 - cos φ), φ the turn at the corner (RTC's
# variable polygon delay: none straight on, the full delay at a right angle, twice it at a
# reversal, at most 1270 µs); false: the full delay at every corner.
polygon_scaled = {"true" if d.galvo.polygon_scaled else "false"}
# How far in time the mirrors lag their set point on a line at constant speed (their
# tracking error; a critically damped servo's 2/ωn, some 80 µs on a 10 mm head): a photo's
# pixel lines are sent this far ahead, so each pixel lands where it belongs in both
# directions, and run in and out at speed over three times it. Tune it with a test mark
# of a photo: the two directions' edges then meet. {s("galvo", "tracking_delay_us")}.
tracking_delay_us = {n(d.galvo.tracking_delay_us)}
# true: the scan head answers on its XY2-100 STATUS line and the laser obeys it: Temp OK or
# Power OK low, or no answer, keeps the laser off, stops a job and latches the head fault
# (a bitstream built with --head-status; `galvoscan status` shows the head's bits).
# false: for a head without the line, which would read as missing.
head_check = {"true" if d.galvo.head_check else "false"}

[defaults]
# Job settings used when the command line does not give them.
# Marking speed, in mm/s: at most [galvo] max_speed_mm_s. {s("defaults", "speed_mm_s")}.
speed_mm_s = {n(d.defaults.speed_mm_s)}
# Laser power, in % of max_power_w. Low on purpose: raise it per job, after a test
# mark, rather than here. {s("defaults", "power_percent")}.
power_percent = {n(d.defaults.power_percent)}
# Pulse repetition rate, in kHz: within [laser] prr_khz.
prr_khz = {n(d.defaults.prr_khz)}
# Times each job is marked, one pass over the other. {s("defaults", "passes")}.
passes = {n(d.defaults.passes)}

[wobble]
# A small ellipse laid over every marked line, to widen a weld or cleaning track (needs
# a bitstream built with the wobble stage). `galvoscan mark --wobble` overrides these.
# Amplitude across the line, to each side, in µm: the track grows by twice this.
# 0 here and in along_um: no wobble. {s("wobble", "across_um")} (the board holds at
# most 4095 galvo units: 6.9 mm on a 110 mm field).
across_um = {n(d.wobble.across_um)}
# Amplitude along the line, forwards and back, in µm; equal to across_um: a circle.
# {s("wobble", "along_um")}.
along_um = {n(d.wobble.along_um)}
# Turns of the figure a second, in Hz: with the line speed v, the figure repeats every
# v / freq_hz along the line. {s("wobble", "freq_hz")}.
freq_hz = {n(d.wobble.freq_hz)}

[fly]
# Marking on the fly (`galvoscan mark --fly X`, a bitstream with the fly: the ULX3S's): a
# belt carries the part through the field, an encoder on the belt tells the board how far,
# and every point follows it. The encoder's A and B go to the board's ENCODER input of
# that axis (docs/hardware/wiring.md).
# The encoder's counts a mm of belt, every edge of A and B counted (4 a line period),
# counting up as the belt runs (else swap A and B). Left out: no encoder (`mark
# --encoder`, or `--fly-speed` for the board's simulated one). {s("fly", "counts_per_mm")}.
# counts_per_mm = 100
# Which way the belt carries the part along the axis: "+" towards +X (or +Y), "-"
# towards -X.
direction = "{d.fly.direction}"
# The belt's top speed, in mm/s: a job on the fly is refused if the part would leave the
# field at it before the job is done. Left out: `mark --belt-speed`.
# {s("fly", "belt_speed_mm_s")}.
# belt_speed_mm_s = 200
# The board's system clock, in MHz, as its bitstream was built: the simulated encoder
# (`mark --fly-speed`) counts in its clocks. {s("fly", "board_clock_mhz")}.
board_clock_mhz = {n(d.fly.board_clock_mhz)}

[sky]
# SkyWriting (SCANLAB RTC's; `galvoscan mark --sky 1`, a bitstream with pixel lines: the
# ULX3S's, or build --preset engraver): the mirrors run through each mark's ends at the
# mark's speed, laser off, and the laser switches Timelag after the set point crosses
# them, so the dose is even up to the ends. docs/user/skywriting.md.
# The mode jobs take when they do not give --sky: 0 off; 1 every mark run in and out;
# 2 also every corner taken apart into run-out, jump and run-in; 3 the corners sharper
# than limit only. {s("sky", "mode")}.
mode = {d.sky.mode}
# Timelag, in µs: the head's tracking error. Left out: [galvo] tracking_delay_us.
# {s("sky", "timelag_us")}.
# timelag_us = 80
# LaserOnShift, in µs: laser-on moved this much later (negative: earlier); Timelag + it
# must be 0 … {_LASER_ON_HIGH_US} µs. {s("sky", "laser_on_shift_us")}.
laser_on_shift_us = {n(d.sky.laser_on_shift_us)}
# Nprev and Npost, in µs: the run-in before and the run-out after each mark, whole
# points at its speed. Left out: {NPREV_SHARE:g} and {NPOST_SHARE:g} × Timelag. {s("sky", "nprev_us")}.
# nprev_us = 12
# npost_us = 8
# Mode 3: a corner is taken apart where cos φ is below this (φ the turn: 1 straight on,
# 0 a right angle, -1 a reversal); the others keep the polygon delay. {s("sky", "limit")}.
limit = {n(d.sky.limit)}
"""
