"""A cleaning job: a rectangle in mm filled by the spiral or the raster, at a speed, for a
number of passes, a time or a dose, made into register values and checked before anything is
sent.

Speeds: the spiral's dwell is the smallest that keeps each axis at or below the speed (the
analysis' :func:`~galvoscan.analysis.patterns.spiral_dwell_for_speed`); the raster's step is
the speed times the 10 µs frame, its line spacing half the spot. The dose is the mean areal
dose, energy over area: ``power × time / area`` (J/cm²), which is what the analysis' dose map
averages to over the area.
"""

import math
from dataclasses import dataclass, field

from ..analysis.galvo import FRAME_PERIOD
from ..analysis.patterns import ScanHead, spiral_amplitude, spiral_dwell_for_speed, spiral_frames
from ..gateware.host.regmap import BY_NAME, Mode
from ..gateware.points import FIELD_CENTRE
from ..gateware.sources.spiral_table import SpiralTable
from ..geometry.field import PlanError


__all__ = ["AreaJob", "plan_area_job", "PATTERNS"]


PATTERNS = ("spiral", "raster")


@dataclass
class AreaJob:
    """A planned cleaning job.

    Attributes
    ----------
    registers : dict
        Every register the job sets (mode, pattern, laser), in the order to write them.
    pass_s : float
        Time of one whole pattern.
    seconds : float
        The job's time (passes × pass_s, or the duration asked).
    passes : float
    dose_j_cm2 : float
        Mean areal dose of the whole job.
    speed_mm_s : float
        The pattern's speed as built (spiral: the fastest axis's commanded speed).
    bounds_mm : tuple
        ``(xmin, ymin, xmax, ymax)`` in field mm.
    notes : list of str
        What the plan says (the speed made, when more than 2 % from the one asked).
    """
    pattern: str
    registers: dict
    pass_s: float
    seconds: float
    passes: float
    dose_j_cm2: float
    speed_mm_s: float
    bounds_mm: tuple
    power_w: float
    notes: list = field(default_factory=list)


def _units(head, mm):
    return int(round(float(head.units(mm))))


def plan_area_job(*, area_mm, centre_mm, pattern, speed_mm_s, power_percent, prr_khz, profile,
                  passes=None, duration_s=None, dose_j_cm2=None):
    """Plan a cleaning job; exactly one of ``passes``, ``duration_s``, ``dose_j_cm2``.
    Raises :class:`~galvoscan.geometry.field.PlanError` (one line) for what cannot run."""
    if sum(v is not None for v in (passes, duration_s, dose_j_cm2)) != 1:
        raise PlanError("give one of --passes, --duration and --dose")
    if pattern not in PATTERNS:
        raise PlanError(f"pattern must be spiral or raster, not {pattern!r}")
    width, height = area_mm
    cx, cy = centre_mm
    half = profile.field.size_mm / 2
    bounds = (cx - width / 2, cy - height / 2, cx + width / 2, cy + height / 2)
    if min(bounds) < -half or max(bounds) > half:
        raise PlanError(f"the area spans X {bounds[0]:g}…{bounds[2]:g} mm, Y {bounds[1]:g}…"
                        f"{bounds[3]:g} mm; the field is {-half:g}…{half:g} mm")
    if speed_mm_s > profile.galvo.max_speed_mm_s:
        raise PlanError(f"{speed_mm_s:g} mm/s is faster than the machine's "
                        f"{profile.galvo.max_speed_mm_s:g} mm/s ([galvo] max_speed_mm_s)")
    prr = profile.prr_register(prr_khz)
    power = profile.power_register(power_percent)
    power_w = profile.power_w(power_percent)
    head = ScanHead(profile.field.size_mm)
    registers = {"run": 0}
    if pattern == "spiral":
        table = SpiralTable()
        amp = (spiral_amplitude(width, head), spiral_amplitude(height, head))
        dwell = spiral_dwell_for_speed(table, amp=amp, speed_m_s=speed_mm_s / 1e3, head=head)
        if dwell > BY_NAME["dwell"].high:
            raise PlanError(f"{speed_mm_s:g} mm/s is too slow for the spiral on this area")
        frames = spiral_frames(table, dwell=dwell, amp=amp,
                               centre=(FIELD_CENTRE + _units(head, cx), FIELD_CENTRE + _units(head, cy)))
        # Each point is held ``dwell`` frames: the axis speed is the largest step from point to
        # point over that time (taken between the points, not between frames: an interpolating
        # build spreads a step over its dwell, which is the same speed, not a dwell-th of it).
        points = spiral_frames(table, dwell=1, amp=amp, interpolation="off")
        steps = [max(abs(b - a) for a, b in zip(axis, axis[1:])) for axis in (points.x, points.y)]
        built_speed = float(head.mm(max(steps))) / (dwell * FRAME_PERIOD)
        fastest = built_speed * dwell           # a point a frame
        if speed_mm_s > fastest * 1.02:
            raise PlanError(f"{speed_mm_s:g} mm/s is out of reach for the spiral over "
                            f"{width:g} x {height:g} mm: {fastest:.0f} mm/s at most (a point "
                            f"a 10 µs frame); a slower speed, a larger area, or the raster")
        between = (f"the spiral makes over {width:g} x {height:g} mm ({fastest:.0f} mm/s over "
                   f"a whole number of 10 µs frames a point: {fastest / (dwell - 1):.0f} or "
                   f"{built_speed:.0f})" if dwell > 1 else "")
        made = f"cleaned at {built_speed:.0f} mm/s"
        nearest = "the faster not over it"
        registers.update(mode=Mode.SPIRAL.value, dwell=dwell, amp_x=amp[0], amp_y=amp[1],
                         center_x=FIELD_CENTRE + _units(head, cx),
                         center_y=FIELD_CENTRE + _units(head, cy))
        pass_frames = len(frames.x)
    else:
        step = _units(head, speed_mm_s * FRAME_PERIOD)
        spacing = max(1, _units(head, profile.laser.spot_mm / 2))
        if step < 1:
            raise PlanError(f"{speed_mm_s:g} mm/s is under one galvo unit a frame: too slow "
                            f"for the raster")
        if step > BY_NAME["ras_step"].high:
            raise PlanError(f"{speed_mm_s:g} mm/s is over {BY_NAME['ras_step'].high} galvo "
                            f"units a frame: too fast for the raster")
        corner = (FIELD_CENTRE + _units(head, bounds[0]), FIELD_CENTRE + _units(head, bounds[1]))
        size = (_units(head, width), _units(head, height))
        # Lines one spacing apart, each ``ceil(width / step)`` frames and its end point.
        pass_frames = (size[1] // spacing + 1) * (math.ceil(size[0] / step) + 1)
        built_speed = float(head.mm(step)) / FRAME_PERIOD
        between = (f"the raster makes (whole galvo units a 10 µs frame, "
                   f"{float(head.mm(1)) / FRAME_PERIOD:.1f} mm/s each)")
        made = f"cleaned at the nearest, {built_speed:.1f} mm/s"
        nearest = ""
        registers.update(mode=Mode.RASTER.value, ras_x=corner[0], ras_y=corner[1],
                         ras_w=size[0], ras_h=size[1], ras_spacing=spacing, ras_step=step,
                         ras_flags=0, ras_turn_gate=0)
    registers.update(laser_prr=prr, laser_power=power)
    pass_s = pass_frames * FRAME_PERIOD
    area_cm2 = width * height / 100
    pass_dose = power_w * pass_s / area_cm2
    if passes is not None:
        seconds = passes * pass_s
    elif duration_s is not None:
        seconds = duration_s
    else:
        seconds = dose_j_cm2 * area_cm2 / power_w if power_w > 0 else math.inf
        if not math.isfinite(seconds):
            raise PlanError("a dose needs power above 0 %")
    # As mark does (geometry.speed.choose_pitch): a speed out of reach is refused above, one
    # within reach but more than 2 % from any the pattern makes is said, with the one made.
    error = (built_speed - speed_mm_s) / speed_mm_s
    notes = [f"{speed_mm_s:g} mm/s falls between the speeds {between}: {made} "
             f"({error:+.1%}{', ' + nearest if nearest else ''})"] if abs(error) > 0.02 else []
    return AreaJob(pattern=pattern, registers=registers, pass_s=pass_s, seconds=seconds,
                   passes=seconds / pass_s, dose_j_cm2=pass_dose * seconds / pass_s,
                   speed_mm_s=built_speed, bounds_mm=bounds, power_w=power_w, notes=notes)
