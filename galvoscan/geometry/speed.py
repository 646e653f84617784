"""Speed and time of a marking job: the pitch and pulses per point for a speed
(:func:`choose_pitch`), the time the board takes (:func:`estimate_seconds`) and the lengths
marked and jumped (:func:`jump_mark_lengths`), for segments in galvo units.

It is below planning: it takes :class:`~.field.PlanError` and ``CENTRE`` from :mod:`.field`.
"""

from dataclasses import dataclass
import math

import numpy as np

from .field import CENTRE, PlanError
from .segments import IO, JUMP, MARK, PIXELS, STEPPED


__all__ = ["POINTS_PER_S_MAX", "Pitch", "choose_pitch", "fixed_pitch", "estimate_seconds",
           "segment_seconds", "jump_mark_lengths", "path_length_mm", "settled_jumps"]


#: The most points a second vector mode makes: one an XY2-100 frame.
POINTS_PER_S_MAX = 100e3


def path_length_mm(paths_mm):
    """The length of polylines in mm (a pass of a job's marks, as the preview draws them)."""
    return sum(float(np.sum(np.hypot(*np.diff(np.asarray(p, dtype=float), axis=0).T)))
               for p in paths_mm)


@dataclass(frozen=True)
class Pitch:
    """A marking speed as the board makes it: ``pitch_units`` galvo units between points, each
    point held for ``pulses_per_point`` laser pulses.

    Attributes
    ----------
    pitch_units, pulses_per_point : int
    speed_mm_s : float
        The speed this gives, ``pitch_mm * prr_hz / pulses_per_point``.
    pitch_mm : float
    error : float
        ``(speed_mm_s - asked) / asked``.
    """
    pitch_units: int
    pulses_per_point: int
    speed_mm_s: float
    pitch_mm: float
    error: float


def choose_pitch(speed_mm_s, prr_hz, units_per_mm, *, max_pitch_mm,
                 max_prr_per_point_hz=POINTS_PER_S_MAX, strict=True, pulses_per_point=None):
    """The pitch and pulses per point closest to a marking speed.

    ``v = pitch_units / units_per_mm * prr_hz / N`` mm/s, with N (pulses per point) in
    1 … 255, at least ``prr_hz / max_prr_per_point_hz`` (the most points a second the galvo
    link takes: one per 10 µs frame), and the pitch 1 … 65535 units, at most ``max_pitch_mm``.
    The closest speed wins; of equal ones, the smallest N (the finest pitch).
    ``pulses_per_point``: N is that (a layer's), only the pitch chosen.

    Raises
    ------
    PlanError
        When nothing comes within 2 % of the speed (``strict``; else the closest is taken;
        ``"range"``: the closest when the speed is inside the reachable range, refused only
        outside it); the message gives the reachable range, or the two speeds either side.
    """

    values = (speed_mm_s, prr_hz, units_per_mm, max_pitch_mm, max_prr_per_point_hz)
    if not all(v > 0 and math.isfinite(v) for v in values):
        raise PlanError(f"speed {speed_mm_s} mm/s, PRR {prr_hz} Hz, {units_per_mm} units/mm, "
                        f"pitch ≤ {max_pitch_mm} mm: all must be > 0")
    top = min(65535, math.floor(max_pitch_mm * units_per_mm + 1e-9))
    low_n = max(1, math.ceil(prr_hz / max_prr_per_point_hz - 1e-9))
    if top < 1 or low_n > 255:
        raise PlanError(f"no pitch fits: {max_pitch_mm} mm is under one galvo unit, or "
                        f"{prr_hz:g} Hz needs more than 255 pulses per point")
    high_n = 255
    if pulses_per_point is not None:
        if not low_n <= pulses_per_point <= 255:
            raise PlanError(f"{pulses_per_point} pulses per point: at {prr_hz / 1e3:g} kHz "
                            f"from {low_n} to 255 (a point a 10 µs frame at most)")
        low_n = high_n = int(pulses_per_point)
    n = np.arange(low_n, high_n + 1)
    ideal = speed_mm_s * n * units_per_mm / prr_hz
    candidates = np.clip(np.stack([np.floor(ideal), np.ceil(ideal)]), 1, top)
    speeds = candidates / units_per_mm * prr_hz / n
    errors = np.abs(speeds - speed_mm_s) / speed_mm_s
    least = errors.min()
    row, column = np.nonzero(errors <= least * (1 + 1e-9) + 1e-15)
    best = np.lexsort((candidates[row, column], column))[0]       # smallest N, then pitch
    pitch, pulses = int(candidates[row[best], column[best]]), int(n[column[best]])
    speed = pitch / units_per_mm * prr_hz / pulses
    if strict and abs(speed - speed_mm_s) / speed_mm_s > 0.02:
        slowest, fastest = prr_hz / units_per_mm / high_n, top / units_per_mm * prr_hz / low_n
        if slowest <= speed_mm_s <= fastest and strict == "range":
            return Pitch(pitch, pulses, speed, pitch / units_per_mm,
                         (speed - speed_mm_s) / speed_mm_s)
        if slowest <= speed_mm_s <= fastest:
            # Inside the range, between two speeds whole pitches and pulses make.
            below, above = speeds[speeds <= speed_mm_s].max(), speeds[speeds >= speed_mm_s].min()
            raise PlanError(f"{speed_mm_s:g} mm/s falls between the speeds whole galvo units "
                            f"and pulses make at {prr_hz / 1e3:g} kHz (pitch ≤ "
                            f"{max_pitch_mm:g} mm): {below:.4g} or {above:.4g} mm/s, or "
                            f"another PRR")
        raise PlanError(f"{speed_mm_s:g} mm/s is out of reach at {prr_hz / 1e3:g} kHz: "
                        f"{slowest:.3g} … {fastest:.4g} mm/s (pitch ≤ {max_pitch_mm:g} mm, "
                        f"{low_n}{'' if low_n == high_n else f' … {high_n}'} "
                        f"pulse{'' if low_n == high_n == 1 else 's'} per point)")
    return Pitch(pitch, pulses, speed, pitch / units_per_mm, (speed - speed_mm_s) / speed_mm_s)


def fixed_pitch(speed_mm_s, prr_hz, units_per_mm, pitch_units, *, pulses_per_point=None):
    """The :class:`Pitch` of ``speed_mm_s`` at a pitch of ``pitch_units`` (a photo's pixel
    lines'): the pulses per point nearest it (``pulses_per_point``, if given), at most one
    point a 10 µs frame."""
    pitch_mm = pitch_units / units_per_mm
    fewest = max(1, math.ceil(prr_hz / POINTS_PER_S_MAX - 1e-9))
    pulses = pulses_per_point or max(fewest, round(pitch_mm * prr_hz / speed_mm_s))
    if not fewest <= pulses <= 255:
        raise PlanError(f"{speed_mm_s:g} mm/s at the photo's {pitch_mm * 1000:.1f} µm "
                        f"pixels and {prr_hz / 1e3:g} kHz needs {pulses} pulses a pixel: "
                        f"{fewest} … 255 (another speed or PRR)")
    speed = pitch_mm * prr_hz / pulses
    return Pitch(pitch_units, pulses, speed, pitch_mm, (speed - speed_mm_s) / speed_mm_s)


def _walk(segments):
    """Lengths (galvo units) and ops of the segments, from the field centre (a pixel word or an
    I/O step, which move nothing, 0)."""

    here, out = (CENTRE, CENTRE), []
    for op, x, y in segments:
        if op in (PIXELS, IO):
            out.append((op, 0.0))
            continue
        out.append((op, math.hypot(x - here[0], y - here[1])))
        here = (x, y)
    return out


def estimate_seconds(segments, *, pitch_units, pulses_per_point, prr_hz, jump_delay_us,
                     frame_s=10e-6):
    """An estimate of the time the board takes for the segments.

    ``segments`` are ``(op, x, y)`` in galvo units (:mod:`.segments`), from the field
    centre. A mark or pixel line of ``L`` units is ``ceil(L / pitch_units)`` points, each held
    ``pulses_per_point / prr_hz`` s; a jump is one frame and ``jump_delay_us`` rounded up to
    whole frames (at least one). Mark and polygon delays, the host link and anything the board
    adds are not counted.
    """
    return sum(segment_seconds(segments, pitch_units=pitch_units,
                               pulses_per_point=pulses_per_point, prr_hz=prr_hz,
                               jump_delay_us=jump_delay_us, frame_s=frame_s))


def segment_seconds(segments, *, pitch_units, pulses_per_point, prr_hz, jump_delay_us,
                    frame_s=10e-6):
    """Each segment's share of :func:`estimate_seconds`, in s (a list, in order): what the
    board takes at least to run it, so what the link must bring it in."""
    dwell_s = pulses_per_point / prr_hz
    jump_s = _jump_s(jump_delay_us, frame_s)
    return [math.ceil(length / pitch_units - 1e-12) * dwell_s if op in STEPPED else
            0.0 if op in (PIXELS, IO) else jump_s for op, length in _walk(segments)]


def jump_mark_lengths(segments, units_per_mm, *, pitch_units=None):
    """``(mark_mm, jump_mm)``: the lengths marked and jumped, from the field centre. A pixel
    line is marked where its bits are 1, a pitch (``pitch_units``) a lit point; the rest of
    its sweep is neither."""
    walked = _walk(segments)
    mark = sum(length for op, length in walked if op == MARK)
    jump = sum(length for op, length in walked if op == JUMP)
    lit = sum(bin(x | y << 16).count("1") for op, x, y in segments if op == PIXELS)
    return (mark + lit * (pitch_units or 0)) / units_per_mm, jump / units_per_mm


def _jump_s(delay_us, frame_s=10e-6):
    """What a jump costs the board, s: its frame, and its delay in whole frames (at least
    one)."""
    return (1 + max(1, math.ceil(delay_us * 1e-6 / frame_s - 1e-9))) * frame_s


def settled_jumps(segments, profile, units_per_mm, *, settle=True):
    """``(segments, jump_delay, extra, longest)``: the jumps each held as long as its own
    length needs, when that is quicker than holding every one for the longest's (``longest``,
    the jump delay that takes; ``settle=False``: that, every jump held once). The job's first
    jump, from wherever the head was, is held as long as one across the whole field.

    The board has one jump delay; a jump to where the head already is holds it once more. So
    the delay is set to what makes the whole job quickest, and a jump whose settling needs
    more (:meth:`~galvoscan.profile.machine.MachineProfile.jump_delay_register`, RTC's
    variable jump delay) is followed by as many such jumps as it needs: a photo's thousands
    of short gaps no longer each wait for its longest jump."""
    lengths = [length / units_per_mm if op == "jump" else None for op, length in _walk(segments)]
    jumps = [length for length in lengths if length is not None]
    if not jumps:
        return segments, profile.jump_delay_register(), 0, profile.jump_delay_register()
    # The first jump, from wherever the head was: as long as one across the field.
    needs = [profile.jump_delay_register()] + [profile.jump_delay_register(length)
                                                for length in jumps[1:]]
    longest = max(needs)
    if not settle or not profile.variable_jump_delay:
        return segments, longest, 0, longest
    needs = np.array(needs, float)
    # Each delay in whole frames: how many holds each jump takes, and what they cost.
    frames = np.arange(1, max(1, math.ceil(needs.max() / 10)) + 1)
    holds = np.ceil(needs[None, :] / (10.0 * frames[:, None]) - 1e-9).clip(min=1)
    cost = holds.sum(axis=1) * np.array([_jump_s(10 * f) for f in frames])
    best = int(np.argmin(cost))
    if cost[best] >= len(jumps) * _jump_s(longest):
        return segments, longest, 0, longest
    delay, holds = int(10 * frames[best]), holds[best].astype(int)
    settled, k = [], 0
    for segment, length in zip(segments, lengths):
        settled.append(segment)
        if length is not None:
            settled += [segment] * (holds[k] - 1)
            k += 1
    return settled, delay, int(holds.sum()) - len(jumps), longest
