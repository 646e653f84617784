"""Marking on the fly, planned: a belt carries the part through the field while it is marked,
and the board moves every point by the encoder's count × a scale (RTC's ``set_fly_x/y``).

:class:`Fly` is what a job asks for (the axis, a real encoder's counts a mm or the board's
simulated encoder's speed, the direction, a real belt's top speed); :func:`plan_fly` makes it
the board's registers for a planned job and checks that the part stays in the field until
the job is done, in one line with the figures if not (:class:`FlyPlan`).

The registers (gateware/host/register_list.py): ``fly_scale_x``/``_hi`` (or ``_y``), the scale
in galvo units a count, signed Q8.16; ``fly_sim_period``, the simulated encoder's clocks a
count; ``fly_ctrl``, the simulated bit of the axis, written with the fly off as the job is set
up. The job streamer zeroes the count (``fly_clear``) and turns the fly on as the job starts
(:class:`~galvoscan.outputs.stream.JobStreamer`), and off (``fly_return``) however it ends.

Time in the field: the drawing's edge ahead of the belt (its bounds) has the field's edge
``room`` mm ahead of it as the job starts, which the belt covers in ``room / speed``; the job
takes the planner's estimate, and each layer after the first arms the laser again, waiting
out the MO lead (the bitstreams': 5 ms). A job that would take longer is refused: a point
carried past the field's edge would be held there unmarked.
"""

import math
from dataclasses import dataclass, replace

from ..gateware.build_config import BuildConfig
from ..gateware.fields import FlyControl, pack
from ..gateware.fly.scale import SCALE_BITS, SCALE_FRACTION
from ..geometry.field import PlanError
from ..settings.fly import (BELT_SPEED, ENCODER, FLY, FLY_DIRECTION, FLY_SPEED,
                            SIM_COUNTS_PER_MM)


__all__ = ["Fly", "FlyPlan", "check_fly", "plan_fly", "SIM_COUNTS_PER_MM", "FLY_ON"]


#: ``fly_ctrl`` with the fly on (its other bits: the simulated encoder's).
FLY_ON = pack(FlyControl, on=1)
#: The largest ``fly_sim_period`` (a 16-bit register) and the smallest the encoder steps at.
_PERIOD_RANGE = (2, 0xFFFF)
#: The time each layer after the first waits before it marks: the MO lead of the bitstreams.
_REARM_S = BuildConfig.mo_lead


@dataclass(frozen=True)
class Fly:
    """Marking on the fly: the belt carries the part along ``axis`` (``"X"`` or ``"Y"``) of
    the field, towards ``direction`` (``"+"`` or ``"-"``; None: the profile's ``[fly]``).

    A real encoder on the board's ENCODER input of that axis: ``counts_per_mm`` (None: the
    profile's), and ``belt_speed_mm_s``, the belt's top speed, to check the time in the
    field (None: the profile's). Or the board's simulated encoder, a belt at ``speed_mm_s``
    (:data:`SIM_COUNTS_PER_MM` counts a mm). Every value is checked against its setting
    (:mod:`galvoscan.settings.fly`) here."""
    axis: str
    counts_per_mm: float = None
    speed_mm_s: float = None
    belt_speed_mm_s: float = None
    direction: str = None

    def __post_init__(self):
        FLY.check(self.axis)
        for setting, value in ((ENCODER, self.counts_per_mm), (FLY_SPEED, self.speed_mm_s),
                               (BELT_SPEED, self.belt_speed_mm_s),
                               (FLY_DIRECTION, self.direction)):
            if value is not None:
                setting.check(value)
        if self.speed_mm_s is not None and self.counts_per_mm is not None:
            raise PlanError(f"{FLY_SPEED.flag} runs the board's simulated encoder, "
                            f"{ENCODER.flag} names a real one: give one of them")
        if self.speed_mm_s is not None and self.belt_speed_mm_s is not None:
            raise PlanError(f"{BELT_SPEED.flag} is a real belt's, under {ENCODER.flag}; the "
                            f"simulated encoder's belt runs at {FLY_SPEED.flag}")


@dataclass(frozen=True)
class FlyPlan:
    """A job's fly, as the board runs it and as long as the part stays in the field.

    Attributes
    ----------
    axis : str
        ``"X"`` or ``"Y"``.
    direction : str
        ``"+"`` or ``"-"``.
    simulated : bool
        The board's simulated encoder (else a real one on the axis's ENCODER input).
    counts_per_mm : float
    speed_mm_s : float
        The belt's speed: the simulated encoder's as it runs at ``clock_hz`` (its period
        whole clocks), or a real belt's top speed.
    asked_mm_s : float
        The simulated belt's speed as asked (a real belt's: ``speed_mm_s``).
    scale : int
        Galvo units a count, 2^-16 units (signed: the direction).
    sim_period : int
        The simulated encoder's clocks a count (0: a real encoder).
    clock_hz : float
        The board's clock the period is counted in.
    room_mm : float
        How far the part may move before the drawing's edge ahead reaches the field's.
    lead_mm : float
        That edge of the drawing, field mm along the axis.
    edge_mm : float
        The field's edge it moves towards.
    job_s : float
        How long the job takes: the planner's estimate, and the MO lead of each layer after
        the first.
    """
    axis: str
    direction: str
    simulated: bool
    counts_per_mm: float
    speed_mm_s: float
    asked_mm_s: float
    scale: int
    sim_period: int
    clock_hz: float
    room_mm: float
    lead_mm: float
    edge_mm: float
    job_s: float

    @property
    def in_field_s(self):
        """Seconds until the part leaves the field (its edge ahead reaches the field's)."""
        return self.room_mm / self.speed_mm_s

    @property
    def scale_units(self):
        """The scale, galvo units a count."""
        return self.scale / (1 << SCALE_FRACTION)

    def check(self):
        """Refuse (:class:`PlanError`, one line with the figures) a job that takes longer than
        the part stays in the field."""
        if self.in_field_s < self.job_s:
            raise PlanError(
                f"the part leaves the field after {self.in_field_s:.3f} s at "
                f"{self.speed_mm_s:g} mm/s (its edge ahead at {self.lead_mm:+.2f} mm, the "
                f"field's at {self.edge_mm:+g} mm, moving {self.direction}{self.axis}); the "
                f"job takes {self.job_s:.3f} s: place it upstream (towards "
                f"{'-' if self.direction == '+' else '+'}{self.axis}, --offset), mark less, or "
                f"run the belt slower")
        return self

    def at_clock(self, clock_hz):
        """The plan on a board whose clock is ``clock_hz`` (a simulated board's own), checked
        again: the simulated encoder's period is in its clocks."""
        if not self.simulated or clock_hz == self.clock_hz:
            return self
        period, speed = _sim_period(self.asked_mm_s, clock_hz)
        return replace(self, clock_hz=clock_hz, sim_period=period, speed_mm_s=speed).check()

    def registers(self):
        """The fly registers a job is set up with: the scale on its axis (0 on the other),
        the simulated encoder's period, ``fly_ctrl`` with the fly off (the streamer turns it
        on as the job starts)."""
        axis = self.axis.lower()
        other = "y" if axis == "x" else "x"
        control = pack(FlyControl, **({f"{axis}_simulated": 1} if self.simulated else {}))
        return {"fly_ctrl": control,
                f"fly_scale_{axis}": self.scale & 0xFFFF,
                f"fly_scale_{axis}_hi": self.scale >> 16,
                f"fly_scale_{other}": 0, f"fly_scale_{other}_hi": 0,
                "fly_sim_period": self.sim_period}

    def source(self):
        """The encoder, in words."""
        if self.simulated:
            return (f"the board's simulated encoder, {self.counts_per_mm:g} counts/mm, a count "
                    f"every {self.sim_period} clocks at {self.clock_hz / 1e6:g} MHz")
        return (f"the encoder on ENCODER {self.axis}, {self.counts_per_mm:g} counts/mm, the "
                f"belt at most {self.speed_mm_s:g} mm/s")

    def line(self):
        """What the plan says of it."""
        speed = f"{self.speed_mm_s:.6g}" + (f" (asked {self.asked_mm_s:g})"
                                            if self.speed_mm_s != self.asked_mm_s else "")
        return (f"on the fly: the part moves {self.direction}{self.axis} at {speed} mm/s "
                f"({self.source()}; {self.scale_units:.6g} galvo units a count): it leaves "
                f"the field after {self.in_field_s:.3f} s, the job takes {self.job_s:.3f} s")

    def record(self):
        """The ``--estimate --json`` record of it, in the units the line says."""
        return {"axis": self.axis, "direction": self.direction,
                "encoder": "simulated" if self.simulated else f"ENCODER {self.axis}",
                "counts_per_mm": self.counts_per_mm,
                "speed_mm_s": round(self.speed_mm_s, 6), "asked_speed_mm_s": self.asked_mm_s,
                "scale_units_per_count": round(self.scale_units, 8), "scale_q16": self.scale,
                "sim_period_clocks": self.sim_period or None,
                "clock_mhz": self.clock_hz / 1e6 if self.simulated else None,
                "leading_edge_mm": round(self.lead_mm, 4), "field_edge_mm": self.edge_mm,
                "in_field_s": round(self.in_field_s, 6), "job_s": round(self.job_s, 6)}


def _sim_period(speed_mm_s, clock_hz):
    """``(period, speed)``: the simulated encoder's clocks a count nearest ``speed_mm_s`` and
    the speed that makes; one line if the register cannot hold it."""
    exact = clock_hz / (speed_mm_s * SIM_COUNTS_PER_MM)
    period = round(exact)
    low, high = _PERIOD_RANGE
    if not low <= period <= high:
        raise PlanError(f"{FLY_SPEED.flag} {speed_mm_s:g} mm/s is a count every {exact:.4g} "
                        f"clocks at {clock_hz / 1e6:g} MHz: the simulated encoder counts every "
                        f"{low} to {high:,} clocks ({clock_hz / (high * SIM_COUNTS_PER_MM):.3g} "
                        f"… {clock_hz / (low * SIM_COUNTS_PER_MM):.4g} mm/s)")
    return period, clock_hz / (period * SIM_COUNTS_PER_MM)


def _belt(fly, profile, clock_hz):
    """What ``fly`` runs with on ``profile``'s machine, whatever the job: a :class:`FlyPlan`'s
    fields but the job's (its time in the field), or one line."""
    section = profile.fly
    direction = fly.direction or section.direction
    clock_hz = clock_hz or section.board_clock_mhz * 1e6
    simulated = fly.speed_mm_s is not None
    if simulated:
        counts = SIM_COUNTS_PER_MM
        period, speed = _sim_period(fly.speed_mm_s, clock_hz)
        asked = fly.speed_mm_s
    else:
        counts = fly.counts_per_mm or section.counts_per_mm
        if counts is None:
            raise PlanError(f"{FLY.flag} {fly.axis} needs an encoder: {ENCODER.flag} "
                            f"COUNTS_PER_MM (the belt's, on the board's ENCODER {fly.axis} "
                            f"input; or [fly] counts_per_mm in the profile) or "
                            f"{FLY_SPEED.flag} MM_S (the board's simulated encoder)")
        speed = asked = fly.belt_speed_mm_s or section.belt_speed_mm_s
        if speed is None:
            raise PlanError(f"{FLY.flag} with a real encoder needs the belt's top speed, "
                            f"{BELT_SPEED.flag} MM_S (or [fly] belt_speed_mm_s in the "
                            f"profile), to check that the part stays in the field until the "
                            f"job is done")
        period = 0
    units_per_mm = profile.units_per_mm
    per_count = units_per_mm / counts
    scale = round(per_count * (1 << SCALE_FRACTION)) * (1 if direction == "+" else -1)
    top = 1 << (SCALE_BITS - 1)
    if not -top <= scale < top:
        least = units_per_mm * (1 << SCALE_FRACTION) / (top - 0.5)
        raise PlanError(f"{ENCODER.flag} {counts:g} counts/mm is {per_count:.4g} galvo units a "
                        f"count on this {profile.field.size_mm:g} mm field: the board's fly "
                        f"scale holds less than {top >> SCALE_FRACTION} (an encoder of at "
                        f"least {math.ceil(least * 100) / 100:g} counts/mm)")
    return dict(axis=fly.axis, direction=direction, simulated=simulated,
                counts_per_mm=float(counts), speed_mm_s=speed, asked_mm_s=asked, scale=scale,
                sim_period=period, clock_hz=clock_hz)


def check_fly(fly, profile):
    """Refuse (one line, :class:`PlanError`) a ``fly`` that cannot run on ``profile``'s
    machine whatever the job: no encoder, a real one's belt speed not given, a scale or a
    simulated speed the board cannot hold. (Before a job is planned: :func:`plan_fly` checks
    it again, with the job.)"""
    _belt(fly, profile, None)


def plan_fly(fly, vector_job, profile, *, clock_hz=None):
    """``fly`` (a :class:`Fly`) for ``vector_job`` on ``profile``'s machine (its field, and its
    ``[fly]`` for what ``fly`` leaves out), the simulated encoder counting in ``clock_hz``
    (None: the profile's ``[fly] board_clock_mhz``): a :class:`FlyPlan`, checked. A
    :class:`PlanError` (one line) for an encoder the board's scale cannot hold, a belt speed
    not given, or a part that leaves the field before the job is done."""
    belt = _belt(fly, profile, clock_hz)
    direction = belt["direction"]
    axis = 0 if fly.axis == "X" else 1
    half = profile.field.size_mm / 2
    bounds = vector_job.bounds_mm
    lead = bounds[2 + axis] if direction == "+" else bounds[axis]
    edge = half if direction == "+" else -half
    layers = len(vector_job.layers) if vector_job.layers else 1
    return FlyPlan(**belt, room_mm=max(0.0, edge - lead if direction == "+" else lead - edge),
                   lead_mm=lead, edge_mm=edge,
                   job_s=vector_job.estimate_s + (layers - 1) * _REARM_S).check()
