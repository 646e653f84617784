"""What the RTC delays do to a marked line and a corner, through the galvo model.

A vector job as the board runs it (Wan et al.'s points, each held for N pulses; the delays as
docs/design/modes.md gives them), frame by frame, goes through :class:`~.galvo.GalvoModel`; the
pulses fall where the mirror really is. The dose is taken along the marked path, at spot scale:
a line's start and end and the corner between two lines against the dose mid-line.

The job: a jump to the start, a mark of ``length_mm`` along X, a right-angle turn, a mark of
``length_mm`` along Y, a jump away. The laser is on from ``laser_on_delay`` after the first point
comes in force to ``laser_off_delay`` after the last point's pulses; the corner is held
``polygon_delay`` (laser on), the end ``mark_delay`` (laser off).
"""

import math

import numpy as np

from .figures import _pyplot
from .galvo import FRAME_PERIOD, FULL_RANGE, GalvoModel


__all__ = ["DelaySettings", "corner_job_dose", "delay_study", "NONE"]


class DelaySettings:
    """The delays, µs: ``on`` (laser-on), ``off`` (laser-off), ``mark``, ``polygon``."""

    def __init__(self, on=0.0, off=0.0, mark=0.0, polygon=0.0):
        self.on, self.off, self.mark, self.polygon = on, off, mark, polygon

    def as_dict(self):
        return {"laser_on_delay_us": self.on, "laser_off_delay_us": self.off,
                "mark_delay_us": self.mark, "polygon_delay_us": self.polygon}

    def __repr__(self):
        return f"DelaySettings(on={self.on:g}, off={self.off:g}, mark={self.mark:g}, " \
               f"polygon={self.polygon:g})"


#: No delays: the laser switches with the points.
NONE = DelaySettings()


def _frames(settings, *, length_mm, field_mm, pitch_mm, frames_per_point, lead_frames=30):
    """Commanded X, Y (galvo units) per frame, and the laser-on interval (s)."""
    units = FULL_RANGE / field_mm
    steps = int(math.ceil(length_mm / pitch_mm))
    along = np.minimum(np.arange(1, steps + 1) * pitch_mm, length_mm)
    start = np.array([-length_mm / 2, -length_mm / 2])
    first = [start + (s, 0.0) for s in along]
    corner = first[-1]
    second = [corner + (0.0, s) for s in along]
    xs, ys = [], []

    def hold(point, n):
        xs.extend([point[0] * units] * n)
        ys.extend([point[1] * units] * n)

    hold(start, lead_frames)                       # the jump's end, settled
    t_first = len(xs) * FRAME_PERIOD
    hold(start, frames_per_point)                  # the mark's start point, marked
    for point in first:
        hold(point, frames_per_point)
    hold(corner, int(math.ceil(settings.polygon / 10 - 1e-9)))
    for point in second:
        hold(point, frames_per_point)
    t_last = len(xs) * FRAME_PERIOD
    end = second[-1]
    hold(end, int(math.ceil(settings.mark / 10 - 1e-9)) + 60)
    laser = (t_first + settings.on * 1e-6, t_last + settings.off * 1e-6)
    return np.array(xs), np.array(ys), laser, (start, corner, end)


def corner_job_dose(settings, *, galvo=None, length_mm=3.0, field_mm=110.0, speed_mm_s=1000.0,
                    prr_hz=100e3, spot_mm=0.05, sample_mm=0.005):
    """Dose along the L-shaped job's path, relative to the dose mid-line.

    Returns a dict: ``s_mm`` (distance along the path from the start), ``dose`` (relative),
    ``start``, ``corner``, ``end`` (peak relative dose within a spot of each), and the pulses'
    positions (mm) for a figure."""
    galvo = GalvoModel.from_step_times() if galvo is None else galvo
    frames_per_point = max(1, int(round(1 / prr_hz / FRAME_PERIOD)))
    pitch_mm = speed_mm_s * frames_per_point * FRAME_PERIOD
    xs, ys, (t_on, t_off), (start, corner, end) = _frames(
        settings, length_mm=length_mm, field_mm=field_mm, pitch_mm=pitch_mm,
        frames_per_point=frames_per_point)
    substeps = 10
    path = galvo.follow(xs, ys, substeps=substeps)
    t = (np.arange(int(len(xs) * FRAME_PERIOD * prr_hz)) + 0.5) / prr_hz
    t = t[(t >= t_on) & (t < t_off)]
    px, py = path.at(t)
    units = FULL_RANGE / field_mm
    px, py = px / units, py / units
    # The path as drawn, sampled, and the dose at each sample: Gaussian spots, 1/e² radius.
    s = np.arange(-0.3, 2 * length_mm + 0.3, sample_mm)
    on_first = s <= length_mm
    sx = np.where(on_first, start[0] + s, corner[0])
    sy = np.where(on_first, start[1], corner[1] + (s - length_mm))
    w = spot_mm / 2
    dose = np.zeros_like(s)
    for k in range(0, len(px), 256):
        dx = sx[:, None] - px[None, k:k + 256]
        dy = sy[:, None] - py[None, k:k + 256]
        dose += np.exp(-2 * (dx ** 2 + dy ** 2) / w ** 2).sum(axis=1)
    middle = (s > 0.3 * length_mm) & (s < 0.7 * length_mm)
    dose = dose / np.median(dose[middle])

    def peak(low, high):
        near = (s >= low) & (s <= high)
        return float(dose[near].max())

    # Where the marked line begins and ends: the dose crosses half the mid-line's (a uniformly
    # marked line's ends get half), as distances past the set start and end points.
    marked = np.nonzero(dose >= 0.5)[0]
    return {"s_mm": s, "dose": dose,
            "start": peak(-0.3, 0.5), "corner": peak(length_mm - 0.3, length_mm + 0.3),
            "end": peak(2 * length_mm - 0.5, 2 * length_mm + 0.3),
            "start_shift_mm": float(s[marked[0]]) if len(marked) else math.inf,
            "end_shift_mm": float(s[marked[-1]] - 2 * length_mm) if len(marked) else -math.inf,
            "pulses_mm": (px, py), "settings": settings}


#: The ends' and the corner's peak dose may exceed the mid-line's by this share.
TOLERANCE = 0.2


def delay_study(*, galvo=None, **job):
    """The job without delays, and with the delays that keep the line's ends and its corner
    within :data:`TOLERANCE` of the mid-line dose and the line's ends nearest their set points
    (a search over laser-on and laser-off delays in 10 µs steps, mark delay = laser-off delay
    + 50 µs as the RTC asks, then polygon delays from 0). Returns ``(without, chosen)``."""
    galvo = GalvoModel.from_step_times() if galvo is None else galvo
    without = corner_job_dose(NONE, galvo=galvo, **job)
    best = None
    for on in range(0, 301, 10):
        trial = corner_job_dose(DelaySettings(on=on), galvo=galvo, **job)
        if trial["start"] <= 1 + TOLERANCE:
            best_on = on
            break
    else:
        best_on = 300
    for off in range(0, 301, 10):
        trial = corner_job_dose(DelaySettings(on=best_on, off=off, mark=off + 50), galvo=galvo,
                                **job)
        if trial["end"] > 1 + TOLERANCE:
            break
        best = trial
    best = best or trial
    chosen = best
    for polygon in range(10, 201, 10):
        trial = corner_job_dose(DelaySettings(best_on, best["settings"].off,
                                              best["settings"].mark, polygon), galvo=galvo, **job)
        if trial["corner"] > 1 + TOLERANCE:
            break
        chosen = trial
    return without, chosen


def plot_delays(path, without, chosen):
    """Dose along the L-shaped job without and with the delays, and where the pulses fell at
    the line's start and at the corner."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.4), dpi=110,
                             gridspec_kw={"width_ratios": [2.2, 1, 1]})
    ax = axes[0]
    length = (without["s_mm"][-1] - 0.3) / 2
    for result, label, colour in ((without, "no delays", "tab:red"),
                                  (chosen, _label(chosen["settings"]), "tab:blue")):
        ax.plot(result["s_mm"], result["dose"], color=colour, linewidth=0.9, label=label)
    ax.axhspan(1 - TOLERANCE, 1 + TOLERANCE, color="0.9")
    for at in (0, length, 2 * length):
        ax.axvline(at, color="0.5", linewidth=0.5, linestyle=":")
    ax.set_xlabel("along the path, mm (start, corner, end dotted)")
    ax.set_ylabel("dose / mid-line dose")
    ax.legend(fontsize=7, loc="upper center")
    for ax, (cx, cy), title in ((axes[1], (-length / 2, -length / 2), "start"),
                                (axes[2], (length / 2, -length / 2), "corner")):
        for result, colour, marker in ((without, "tab:red", "o"), (chosen, "tab:blue", ".")):
            px, py = result["pulses_mm"]
            near = (np.abs(px - cx) < 0.25) & (np.abs(py - cy) < 0.25)
            ax.plot(px[near], py[near], marker, color=colour, markersize=3, alpha=0.6)
        ax.set_xlim(cx - 0.25, cx + 0.25)
        ax.set_ylim(cy - 0.25, cy + 0.25)
        ax.set_aspect("equal")
        ax.set_title(f"pulses at the {title}", fontsize=9)
        ax.set_xlabel("mm")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def _label(settings):
    return (f"laser on {settings.on:g} µs, off {settings.off:g} µs, mark {settings.mark:g} µs, "
            f"polygon {settings.polygon:g} µs")


def delay_report(without, chosen):
    """Rows of plain numbers for the table and ``--json``."""
    rows = []
    for name, result in (("no delays", without), ("with delays", chosen)):
        rows.append({"run": name, **result["settings"].as_dict(),
                     "start_peak": round(result["start"], 3),
                     "corner_peak": round(result["corner"], 3),
                     "end_peak": round(result["end"], 3),
                     "start_shift_um": round(result["start_shift_mm"] * 1000, 1),
                     "end_shift_um": round(result["end_shift_mm"] * 1000, 1)})
    return rows
