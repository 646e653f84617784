"""SkyWriting (SCANLAB RTC5/6, modes 1 to 3), planned on the host.

The mirrors lag their set point by the head's tracking error, Timelag. Without help a mark's
ends are where the mirrors accelerate and brake: the laser delays trade a burnt dot against a
missing end, and the polygon delay holds each corner with the laser on. SkyWriting instead
runs the set point through a mark's ends at the mark's own speed:

* **mode 1**: before each mark (a jump's polyline) a run-in of ``nprev_us``, after it a run-out
  of ``npost_us``, both on the mark's line and at its speed with the laser off (the run-in
  ends a pitch before the mark's start, which the mark then steps onto, lit);
* **mode 2**: also every corner between two marks that turns is taken apart: run-out along the
  mark that ends there, jump, run-in along the one that leaves it (up to the corner, which the
  mark that ends there has lit: lit twice it would get twice the dose);
* **mode 3**: only the corners whose cos φ is below ``limit`` (φ the turn); the others keep
  the polygon delay (scaled by (1 - cos φ), a hold the host sends with each corner).

The run-ins and run-outs are pixel lines without pixel words (:mod:`galvoscan.geometry.
segments`): the board steps them as it steps a mark, the same pitch and pulses a point, with
the laser off; so SkyWriting needs a bitstream with pixel lines. Their lengths are whole
points, at least as long as asked. The board's laser delays then place the laser's edges: it
switches on ``timelag_us + laser_on_shift_us`` after a mark's first point reaches the head and
off ``timelag_us`` after its last, when the lagging mirrors cross the drawing's ends; the
polygon delay is 0 (mode 3: the kept corners' holds), and the mark delay at least what lets
the laser go off before the jump after a run-out.
"""

import math
from dataclasses import dataclass, replace

from ..gateware.host.regmap import BY_NAME, FRAME_US
from ..gateware.points import FIELD_CENTRE
from ..geometry.field import PlanError
from ..geometry.segments import JUMP, LINE, MARK, PIXELS, has_pixel_lines
from ..settings.schema import SettingError
from ..settings.sky import (LASER_ON_SHIFT, LIMIT_DEFAULT, NPOST, NPOST_SHARE, NPREV,
                            NPREV_SHARE, SKY, SKY_LIMIT, TIMELAG)


__all__ = ["Sky", "SkyPlan", "job_sky", "layer_sky", "sky_segments", "sky_registers",
           "run_points", "OFF"]


_ON, _OFF = BY_NAME["laser_on_delay"], BY_NAME["laser_off_delay"]
_FIELD_MAX = BY_NAME["vec_x"].high
#: A corner "turns" in mode 2 where cos φ is below this (straight on: nothing to take apart).
_STRAIGHT = 1 - 1e-9
#: What the mark delay adds to the run-out, µs, before the laser may be taken as off: a point
#: may be handed on up to a frame early, and the edge comes a clock after its frame.
_OFF_MARGIN_US = 2 * FRAME_US


@dataclass(frozen=True)
class Sky:
    """SkyWriting as a job or a layer marks with it, every value checked against its setting
    (:mod:`galvoscan.settings.sky`): ``mode`` 0 (off) … 3, ``timelag_us``,
    ``laser_on_shift_us`` (signed), ``nprev_us`` and ``npost_us`` (None: RTC's 0.15 and 0.1 ×
    Timelag) and ``limit`` (mode 3's cos φ). A :class:`PlanError` (one line) for a value out
    of range, or a laser-on (Timelag + LaserOnShift) the board's register cannot hold."""
    mode: int = 0
    timelag_us: float = 0.0
    laser_on_shift_us: float = 0.0
    nprev_us: float = None
    npost_us: float = None
    limit: float = LIMIT_DEFAULT

    def __post_init__(self):
        # Off, only the mode must be one: a profile's tracking delay may be longer than any
        # Timelag the board takes, and a job that does not skywrite must not be refused for it.
        for setting, value in ((SKY, self.mode), (TIMELAG, self.timelag_us),
                               (LASER_ON_SHIFT, self.laser_on_shift_us),
                               (NPREV, self.nprev_us), (NPOST, self.npost_us),
                               (SKY_LIMIT, self.limit)):
            if value is None and setting in (NPREV, NPOST) or \
                    setting is not SKY and self.mode == 0:
                continue
            try:
                setting.check(value)
            except SettingError as error:
                raise PlanError(f"SkyWriting: {error}") from None
        on = self.timelag_us + self.laser_on_shift_us
        if self.mode and not 0 <= on <= _ON.high:
            raise PlanError(f"SkyWriting: Timelag {self.timelag_us:g} µs + laser-on shift "
                            f"{self.laser_on_shift_us:+g} µs is {on:g} µs: laser-on must come "
                            f"0 … {_ON.high} µs after the set point reaches a mark's start "
                            + ("(a shift nearer 0, or a longer Timelag)" if on < 0 else
                               "(a shift nearer 0, or a shorter Timelag)"))

    @property
    def on(self):
        return self.mode > 0

    @property
    def run_in_us(self):
        """Nprev, µs: given, else 0.15 × Timelag."""
        return self.nprev_us if self.nprev_us is not None else NPREV_SHARE * self.timelag_us

    @property
    def run_out_us(self):
        """Npost, µs: given, else 0.1 × Timelag."""
        return self.npost_us if self.npost_us is not None else NPOST_SHARE * self.timelag_us

    @property
    def laser_on_delay(self):
        """The ``laser_on_delay`` register, whole µs: Timelag + LaserOnShift."""
        return math.floor(self.timelag_us + self.laser_on_shift_us + 0.5)

    @property
    def laser_off_delay(self):
        """The ``laser_off_delay`` register, whole µs: Timelag."""
        return math.floor(self.timelag_us + 0.5)

    def splits(self, cos_phi):
        """Whether a corner turning by φ (its cos) is taken apart into run-out, jump and
        run-in."""
        if self.mode == 2:
            return cos_phi < _STRAIGHT
        if self.mode == 3:
            return cos_phi < self.limit
        return False

    def said(self):
        """``SkyWriting mode 1 (Timelag 80 µs, …)``, as the plan says it."""
        words = f"Timelag {self.timelag_us:g} µs"
        if self.laser_on_shift_us:
            words += f", laser-on shift {self.laser_on_shift_us:+g} µs"
        words += f", Nprev {self.run_in_us:g} µs, Npost {self.run_out_us:g} µs"
        if self.mode == 3:
            words += f", limit cos φ < {self.limit:g}"
        return f"SkyWriting mode {self.mode} ({words})"


def job_sky(profile, *, mode=None, timelag_us=None, laser_on_shift_us=None, nprev_us=None,
            npost_us=None, limit=None):
    """A job's :class:`Sky`: each value given, else the profile's ``[sky]`` (its Timelag,
    else ``[galvo] tracking_delay_us``)."""
    section = profile.sky
    given = [setting.flag for setting, value in ((TIMELAG, timelag_us),
                                                 (LASER_ON_SHIFT, laser_on_shift_us),
                                                 (NPREV, nprev_us), (NPOST, npost_us),
                                                 (SKY_LIMIT, limit)) if value is not None]
    if given and (mode if mode is not None else section.mode) == 0:
        # (As the fly's options without --fly: a setting that would do nothing is refused,
        # not ignored.)
        raise PlanError(f"{given[0]} is SkyWriting's: give --sky 1, 2 or 3 too (the "
                        f"profile's [sky] mode is {section.mode})")
    timelag = timelag_us if timelag_us is not None else (
        section.timelag_us if section.timelag_us is not None
        else profile.galvo.tracking_delay_us)
    return Sky(mode=mode if mode is not None else section.mode, timelag_us=timelag,
               laser_on_shift_us=laser_on_shift_us if laser_on_shift_us is not None
               else section.laser_on_shift_us,
               nprev_us=nprev_us if nprev_us is not None else section.nprev_us,
               npost_us=npost_us if npost_us is not None else section.npost_us,
               limit=limit if limit is not None else section.limit)


#: A layer's fields and the :class:`Sky` fields they set.
LAYER_FIELDS = {"sky_mode": "mode", "timelag_us": "timelag_us",
                "laser_on_shift_us": "laser_on_shift_us", "nprev_us": "nprev_us",
                "npost_us": "npost_us", "sky_limit": "limit"}


def layer_sky(layer, base):
    """``base`` (a :class:`Sky`, or None: off) with a layer's own SkyWriting values in it."""
    given = {field: getattr(layer, name) for name, field in LAYER_FIELDS.items()
             if getattr(layer, name, None) is not None}
    if not given:
        return base
    return replace(base if base is not None else Sky(), **given)


def run_points(us, dwell_us):
    """Whole points a run of ``us`` takes at a point every ``dwell_us``: at least as long."""
    return max(0, math.ceil(us / dwell_us - 1e-9)) if us > 0 else 0


@dataclass(frozen=True)
class SkyPlan:
    """What SkyWriting made of a job's segments: the ``segments``, the points of each run-in
    and run-out, and how many run-ins, run-outs and corners taken apart there are."""
    segments: list
    in_points: int
    out_points: int
    run_ins: int
    run_outs: int
    corners: int


def _unit(dx, dy):
    length = math.hypot(dx, dy)
    return (dx / length, dy / length) if length else None


def _point(at, direction, units, where):
    """``at`` moved ``units`` along ``direction`` (galvo units, rounded); one line if it
    leaves the galvo range."""
    x = round(at[0] + direction[0] * units)
    y = round(at[1] + direction[1] * units)
    if not (0 <= x <= _FIELD_MAX and 0 <= y <= _FIELD_MAX):
        raise PlanError(f"SkyWriting: the {where} at galvo ({at[0]}, {at[1]}) reaches past "
                        f"the field's edge: move the job towards the centre, or shorten "
                        f"{'--nprev' if where == 'run-in' else '--npost'}")
    return x, y


def _run_length(points, pitch_units):
    """A run of ``points`` points as a length a little short of as many pitches, so that the
    board steps exactly that many (its DDA's last step lands on the end)."""
    return points * pitch_units - min(1.0, pitch_units / 4)


def sky_segments(segments, sky, *, pitch_units, dwell_us, start=(FIELD_CENTRE, FIELD_CENTRE)):
    """``segments`` (``(op, x, y)``, galvo units, from ``start``) with SkyWriting's run-ins,
    run-outs and (modes 2 and 3) corners taken apart: a :class:`SkyPlan`. ``pitch_units``:
    the marks' pitch; ``dwell_us``: the time a point is held (pulses per point / PRR)."""
    if not sky.on:
        return SkyPlan(list(segments), 0, 0, 0, 0, 0)
    if has_pixel_lines(segments):
        raise PlanError("SkyWriting runs vector marks in and out; a photo's pixel lines have "
                        "their own run-in: give the photo a layer of its own with sky = 0")
    n_in = run_points(sky.run_in_us, dwell_us)
    n_out = run_points(sky.run_out_us, dwell_us)
    len_in, len_out = _run_length(n_in, pitch_units), _run_length(n_out, pitch_units)
    out = []
    counts = {"in": 0, "out": 0, "corners": 0}
    here = tuple(start)

    def run_in(first, direction, lit):
        """A jump to the run-in's start (the jump before the mark moved there) and the
        run-in: up to the point a pitch before ``first`` when ``first`` is to be ``lit`` (the
        mark then steps onto it; a run-in to ``first`` itself leaves that point dark, the
        board marking a mark's start point only after the laser was off), else up to
        ``first`` (a corner taken apart: the mark that ends there has marked it)."""
        if not n_in:
            if not (out and out[-1][0] == JUMP and out[-1][1:] == first):
                out.append((JUMP, *first))
            return
        before = _point(first, direction, -pitch_units, "run-in") if lit else first
        begin = _point(before, direction, -len_in, "run-in")
        if out and out[-1][0] == JUMP and out[-1][1:] == first:
            out[-1] = (JUMP, *begin)
        else:
            out.append((JUMP, *begin))
        out.append((LINE, *before))
        counts["in"] += 1

    def run_out(last, direction):
        if n_out:
            out.append((LINE, *_point(last, direction, len_out, "run-out")))
            counts["out"] += 1

    k, n = 0, len(segments)
    while k < n:
        op, x, y = segments[k]
        if op != MARK:
            out.append((op, x, y))
            if op != PIXELS:
                here = (x, y)
            k += 1
            continue
        end = k
        while end < n and segments[end][0] == MARK:
            end += 1
        marks = segments[k:end]
        k = end
        # The polyline's pieces: split at the corners the mode takes apart.
        pieces, piece = [], []
        position, last_direction, first_direction = here, None, None
        for mark in marks:
            direction = _unit(mark[1] - position[0], mark[2] - position[1])
            if direction is not None and last_direction is not None:
                cos_phi = direction[0] * last_direction[0] + direction[1] * last_direction[1]
                if sky.splits(cos_phi):
                    pieces.append((piece, first_direction, last_direction))
                    piece, first_direction = [], None
                    counts["corners"] += 1
            if direction is not None:
                last_direction = direction
                if first_direction is None:
                    first_direction = direction
            piece.append(mark)
            position = mark[1:]
        pieces.append((piece, first_direction, last_direction))
        position = here
        for number, (piece, first_direction, last_direction) in enumerate(pieces):
            if first_direction is None:             # dots only: nothing to run through
                out.extend(piece)
                position = piece[-1][1:]
                continue
            run_in(tuple(position), first_direction, lit=number == 0)
            out.extend(piece)
            position = piece[-1][1:]
            run_out(tuple(position), last_direction)
        here = tuple(marks[-1][1:])
    return SkyPlan(out, n_in, n_out, counts["in"], counts["out"], counts["corners"])


def sky_registers(sky, registers, *, dwell_us, out_points):
    """``registers`` (a job's, its delays set) as SkyWriting marks them: the laser delays
    Timelag (+ LaserOnShift), the polygon delay 0 (mode 3: kept, a hold the host sends for
    each corner it keeps), corners held as the host says, and the mark delay at least what
    lets the laser go off (Timelag after a mark's end) before the jump after its run-out.
    Returns the notes to say."""
    notes = []
    registers["laser_on_delay"] = sky.laser_on_delay
    registers["laser_off_delay"] = sky.laser_off_delay
    if sky.mode != 3:
        registers["polygon_delay"] = 0
    registers["polygon_scaled"] = 1
    slack = sky.timelag_us + _OFF_MARGIN_US - out_points * dwell_us
    needed = math.ceil(slack / FRAME_US - 1e-9) * FRAME_US if slack > 0 else 0
    if registers.get("mark_delay", 0) < needed:
        notes.append(f"SkyWriting: mark delay {needed} µs (was {registers.get('mark_delay', 0)}"
                     f" µs), so that the laser, off Timelag after a mark's end, is off before "
                     f"the jump after its run-out")
        registers["mark_delay"] = needed
    return notes
