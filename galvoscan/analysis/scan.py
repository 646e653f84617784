"""One analysis run: frames → mirror path → pulses → dose map, motion and revisit figures."""

import math

import numpy as np

from .dose import dose_map, pulses_along, revisit_intervals, revisit_metrics
from .galvo import FRAME_PERIOD
from .patterns import Frames


__all__ = ["Analysis", "analyse"]


class Analysis:
    """What one run found.

    Attributes
    ----------
    metrics : dict
        Plain numbers (JSON-ready); names carry their units.
    frames, path, pulses, dose, intervals
        The intermediate results, for figures.
    """

    def __repr__(self):
        return f"Analysis({self.metrics!r})"


def analyse(frames, *, head, laser, galvo, region, periodic=True, warmup_s=2e-3, cell_mm=None,
            target_dose_j_cm2=None, pass_gap_s=100e-6, revisit_radius_mm=0.1, substeps=10):
    """Analyse one run of ``frames``.

    Parameters
    ----------
    frames : Frames
    head : ScanHead
    laser : Laser
    galvo : GalvoModel
    region : Region
        The field the pattern is meant to dose (metrics are taken over it).
    periodic : bool
        The pattern repeats (the spiral): the mirror starts as it would on a repetition, by
        running the last ``warmup_s`` of the pattern first. Otherwise it starts at rest on the
        first frame.
    target_dose_j_cm2 : float, optional
        Dose to reach by repeating the pattern; adds the time it takes on average
        (``time_to_mean_dose_s``), on every 1 mm block (``time_to_dose_1mm_s``) and at spot
        scale on 99 % of the field (``time_to_dose_s``; infinite if the pattern never gets
        there).
    """
    warm = min(len(frames), int(round(warmup_s / FRAME_PERIOD))) if periodic else 0
    if warm:
        run = Frames(np.concatenate((frames.x[-warm:], frames.x)),
                     np.concatenate((frames.y[-warm:], frames.y)),
                     laser=np.concatenate((frames.laser[-warm:], frames.laser)))
    else:
        run = frames
    path = galvo.follow(run.x, run.y, substeps=substeps)
    t_start = warm * FRAME_PERIOD
    pulses = pulses_along(path, run, laser, head, t0=t_start)
    pulses.t = pulses.t - t_start
    dose = dose_map(pulses, laser, region, cell_mm=cell_mm)
    intervals = revisit_intervals(pulses, region, radius_mm=revisit_radius_mm,
                                   period=frames.duration, pass_gap=pass_gap_s)

    skip = warm * substeps
    vx, vy = path.velocity()
    ax, ay = path.acceleration()
    mm_per_unit = float(head.mm(1))
    speed = np.hypot(vx[skip:], vy[skip:])
    metrics = {
        "frames": len(frames),
        "duration_s": frames.duration,
        "pulses": len(pulses),
        "mean_speed_m_s": float(np.mean(speed) * mm_per_unit / 1e3),
        "peak_speed_m_s": float(np.max(speed) * mm_per_unit / 1e3),
        "peak_over_mean": float(np.max(speed) / np.mean(speed)) if np.mean(speed) > 0 else None,
        "peak_accel_km_s2": float(max(np.max(np.abs(ax[skip:])), np.max(np.abs(ay[skip:])))
                                  * mm_per_unit / 1e6),
    }
    metrics.update(dose.metrics())
    metrics.update(revisit_metrics(intervals))
    if target_dose_j_cm2 is not None:
        # Repeating the pattern until the target is reached: on average (energy-limited), on
        # every 1 mm block, and at spot scale on 99 % of the field.
        metrics["target_dose_j_cm2"] = target_dose_j_cm2
        for key, dose_per_pass in (("time_to_mean_dose_s", metrics["dose_mean_j_cm2"]),
                                   ("time_to_dose_1mm_s", float(dose.blocks(1.0).min())),
                                   ("time_to_dose_s", metrics["dose_p1_j_cm2"])):
            # Less than a thousandth of the target per pass counts as never.
            metrics[key] = (target_dose_j_cm2 / dose_per_pass * frames.duration
                            if dose_per_pass > 1e-3 * target_dose_j_cm2 else math.inf)
    result = Analysis()
    result.metrics, result.frames, result.path = metrics, frames, path
    result.pulses, result.dose, result.intervals, result.warmup_s = pulses, dose, intervals, t_start
    return result
