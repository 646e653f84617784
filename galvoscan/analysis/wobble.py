"""Wobble on a marked line, through the galvo model: how wide the track gets and how evenly it is
dosed across and along it (``galvoscan analyze --wobble``).

A straight line is marked as vector mode marks it: points one pitch apart, each held for one
laser pulse, the laser on for the whole line. The wobble figure is laid over every frame as the
gateware lays it (an ellipse, ``along · sin θ`` along the line and ``across · cos θ`` across
it, ``θ = 2π f t``, t from the line's start), the frames run through the galvo model, the
pulses land where the mirror really is, and the dose map gives:

``width_mm``
    Width of the track: between the outermost places where the dose, averaged along the line's
    middle, reaches half its own peak (for a plain line the full width at half maximum, 1.18 ×
    the spot's 1/e² radius).
``centre``
    That averaged dose on the line itself over its peak: 1 for a plain line; a circle dwells
    longest at its sides, and a wide one leaves its middle underdosed (two tramlines).
``peak_j_cm2``, ``peak_rel``
    Largest dose across the averaged profile, and that over the plain line's: the wobble
    spreads the same energy wider, so a process needs this much less speed or more power.
``ripple``
    Coefficient of variation of the dose along the line, on its centre and at a quarter of the
    track's width to each side (the largest of the three): the figure's turns show when they
    are farther apart than the spot.
``reach``
    How far the mirror really swings across the line, over the amplitude commanded: the galvo
    model's lag shrinks a fast figure.
"""

import math

import numpy as np

from .dose import Region, dose_map, pulses_along
from .galvo import FRAME_PERIOD, FULL_RANGE
from .patterns import Frames


__all__ = ["WOBBLE_AMPLITUDES_UM", "WOBBLE_FREQUENCIES_HZ", "STUDY_SPEED_MM_S", "line_frames",
           "wobble_line", "wobble_study"]

#: Amplitudes across the line the study sweeps (µm; at :data:`STUDY_HZ`), 0: the plain line.
WOBBLE_AMPLITUDES_UM = (0, 25, 50, 100, 150)
#: Frequencies the study sweeps (Hz; at :data:`STUDY_AMPLITUDE_UM`).
WOBBLE_FREQUENCIES_HZ = (500, 1000, 2000, 4000, 8000)
STUDY_HZ = 2000
STUDY_AMPLITUDE_UM = 50
#: Line marked, mm, and the settling time before it, s.
LINE_MM = 3.0
_LEAD_S = 2e-3


def line_frames(head, *, speed_mm_s, prr_hz, across_um, along_um, hz, line_mm=LINE_MM):
    """Frames of a line along X through the field centre, marked at ``speed_mm_s`` with one
    pulse a point, the figure laid over it; the mirror waits at the start first."""
    lead = int(round(_LEAD_S / FRAME_PERIOD))
    count = int(round(line_mm / speed_mm_s / FRAME_PERIOD))
    t = np.arange(count) * FRAME_PERIOD
    pitch_mm = speed_mm_s / prr_hz
    # The point in force in each frame: one pitch per pulse period.
    along_mm = np.floor(t * prr_hz + 1e-9) * pitch_mm
    theta = 2 * math.pi * hz * t
    x_mm = -line_mm / 2 + along_mm + along_um / 1000 * np.sin(theta)
    y_mm = across_um / 1000 * np.cos(theta)
    centre = FULL_RANGE // 2
    x = np.concatenate((np.full(lead, x_mm[0]), x_mm))
    y = np.concatenate((np.full(lead, y_mm[0]), y_mm))
    laser = np.concatenate((np.zeros(lead, bool), np.ones(count, bool)))
    return Frames(np.rint(head.units(x)) + centre, np.rint(head.units(y)) + centre,
                  laser=laser), lead


def wobble_line(head, laser, galvo, *, speed_mm_s, across_um, along_um, hz):
    """One line's metrics (see the module's description), its dose map and the dose across
    it."""
    frames, lead = line_frames(head, speed_mm_s=speed_mm_s, prr_hz=laser.prr_hz,
                               across_um=across_um, along_um=along_um, hz=hz)
    path = galvo.follow(frames.x, frames.y)
    pulses = pulses_along(path, frames, laser, head, t0=lead * FRAME_PERIOD)
    centre_mm = head.mm(FULL_RANGE // 2)
    pulses.x = pulses.x - centre_mm
    pulses.y = pulses.y - centre_mm
    reach_mm = max(across_um, along_um) / 1000 + laser.spot_mm
    region = Region((0.0, 0.0), (LINE_MM, 2 * reach_mm))
    dose = dose_map(pulses, laser, region, cell_mm=laser.spot_mm / 10)
    middle = np.abs(dose.x) <= LINE_MM / 4                  # away from the line's ends
    profile = dose.dose[middle].mean(axis=0)
    # From the outermost cells at half the peak: a wide circle dwells at its sides, and the
    # middle can fall below half (``flat`` then says so).
    above = np.flatnonzero(profile >= profile.max() / 2)
    inside = np.zeros(len(profile), bool)
    inside[above[0]:above[-1] + 1] = True
    width = float(inside.sum() * dose.cell)
    half = width / 2
    ripple = 0.0
    for y in (0.0, -half / 2, half / 2):
        row = dose.dose[middle, int(np.argmin(np.abs(dose.y - y)))]
        ripple = max(ripple, float(row.std() / row.mean()) if row.mean() > 0 else 0.0)
    swing = head.mm(path.y[lead * 10:] - FULL_RANGE // 2)
    # The swing over the line's middle half, against what was commanded.
    quarter = len(swing) // 4
    reach = float(np.max(np.abs(swing[quarter:-quarter]))) / (across_um / 1000) \
        if across_um else 1.0
    metrics = {
        "across_um": across_um, "along_um": along_um, "hz": hz, "speed_mm_s": speed_mm_s,
        "turn_um": speed_mm_s / hz * 1000,
        "width_mm": width,
        "centre": float(profile[int(np.argmin(np.abs(dose.y)))] / profile.max()),
        "peak_j_cm2": float(profile.max()),
        "ripple": ripple,
        "reach": reach,
    }
    return metrics, dose, profile


#: Line speed of the study, mm/s: at :data:`STUDY_HZ` a turn of the figure every 25 µm, half the
#: default spot.
STUDY_SPEED_MM_S = 50.0


def wobble_study(head, laser, galvo, *, speed_mm_s=STUDY_SPEED_MM_S, progress=None):
    """The amplitude sweep (circles at :data:`STUDY_HZ`) and the frequency sweep (circles of
    :data:`STUDY_AMPLITUDE_UM`). Returns ``(amplitude_runs, frequency_runs)``, each a list of
    ``(metrics, dose, profile)``."""
    plain = wobble_line(head, laser, galvo, speed_mm_s=speed_mm_s, across_um=0, along_um=0,
                        hz=STUDY_HZ)
    plain[0]["peak_rel"] = 1.0

    def run(amplitude, hz):
        result = wobble_line(head, laser, galvo, speed_mm_s=speed_mm_s, across_um=amplitude,
                             along_um=amplitude, hz=hz)
        result[0]["peak_rel"] = result[0]["peak_j_cm2"] / plain[0]["peak_j_cm2"]
        if progress:
            progress(1)
        return result

    amplitudes = [plain] + [run(a, STUDY_HZ) for a in WOBBLE_AMPLITUDES_UM if a]
    frequencies = [run(STUDY_AMPLITUDE_UM, hz) for hz in WOBBLE_FREQUENCIES_HZ]
    return amplitudes, frequencies
