"""A plain Python model of vector marking with the RTC's delays, frame by frame at the head and
clock by clock on the laser's modulation pin, written from SCANLAB's RTC5/6 definitions (laser-on,
laser-off, mark, polygon and jump delays) on top of Wan et al.'s points (vector_model.dda).

Time is the head's: frame ``f`` is in force from ``boundaries[f]`` (a clock number) to
``boundaries[f + 1]``; laser pulses are the PRR clock's rising edges (clock numbers). A marked
point in force from boundary ``b`` is held until ``pulses_per_point`` pulses have fallen in
``(b, b']`` for a later boundary ``b'`` (Wan et al.); then:

* a point that ends a mark segment, before another mark: held on, laser on, for the polygon
  delay in whole frames rounded up, none for 0 (scaled: for the frames sent with that mark);
* the same before a jump: held, laser off, for the mark delay likewise;
* a jump's point: held, laser off, for the jump delay, whole frames rounded up, at least one.

The laser wanted for each frame switches the modulation pin ``LATENCY`` clocks after the frame
comes in force, moved by ``laser_on_delay`` (rising) or ``laser_off_delay`` (falling) µs of
clocks; an edge due after a later-decided edge has come is dropped, and one edge of each
direction waits at a time (a newer replaces it).
"""

import bisect
import math

from vector_model import PARK, dda


#: Clocks from a frame coming in force to the modulation pin following it, without delays (the
#: laser controller's register that gates the pin).
LATENCY = 1
#: µs a frame lasts at XY2-100.
FRAME_US = 10


def hold_frames(us, *, at_least_one):
    frames = math.ceil(us / FRAME_US)
    return max(1, frames) if at_least_one or us else 0


def items(job, pitch, factors=None):
    """The points a job hands on, in order: ``(position, kind, ends_mark, corner_frames)``; kind
    is "jump" or "mark"; a mark's corner_frames is the scaled hold sent with it."""
    position, pen_down, out = PARK, False, []
    for index, (op, x, y) in enumerate(job):
        factor = 0 if factors is None else factors[index]
        if op == "jump":
            out.append(((x, y), "jump", False, None))
            pen_down = False
        else:
            if not pen_down:
                out.append((position, "mark", False, factor))
                pen_down = True
            points = dda(position, (x, y), pitch)
            out += [(p, "mark", i == len(points) - 1, factor) for i, p in enumerate(points)]
        position = (x, y)
    return out



def frames_model(job, *, boundaries, pulse_clocks, start, pitch, pulses_per_point, jump_us,
                 mark_us=0, polygon_us=0, scaled=False, factors=None):
    """Position and laser wanted for every frame from ``start`` (the first point's first frame)
    to the last boundary given: a list of ``(position, laser)``."""
    todo = items(job, pitch, factors)
    frames = []
    f = start
    last = len(boundaries) - 1

    def pulses_between(b0, b1):
        return bisect.bisect_right(pulse_clocks, b1) - bisect.bisect_right(pulse_clocks, b0)

    position = None
    for index, (position, kind, ends_mark, _) in enumerate(todo):
        if f >= last:
            break
        if kind == "jump":
            for _ in range(hold_frames(jump_us, at_least_one=True)):
                frames.append((position, 0))
            f = start + len(frames)
            continue
        # A marked point: until its pulses have fallen.
        first = f
        g = f + 1
        while g <= last and pulses_between(boundaries[first], boundaries[g]) < pulses_per_point:
            g += 1
        frames += [(position, 1)] * (g - first)
        f = start + len(frames)
        following = todo[index + 1] if index + 1 < len(todo) else None
        if ends_mark and following is not None:
            if following[1] == "mark":
                # Scaled: the hold the host worked out for that corner, sent with the mark.
                extra = following[3] if scaled else hold_frames(polygon_us, at_least_one=False)
                frames += [(position, 1)] * extra
            else:
                frames += [(position, 0)] * hold_frames(mark_us, at_least_one=False)
            f = start + len(frames)
    # Nothing more: the last point holds, laser off.
    while start + len(frames) < last:
        frames.append((position, 0))
    return frames[:last - start]


def modulation_edges(frames, *, boundaries, start, clocks_per_us, on_us, off_us):
    """The modulation pin's edges ``(clock, level)`` for the frames' laser (frames[i] is in
    force from ``boundaries[start + i]``; the laser is off before). Each frame's laser was
    decided two frames before it came in force, at ``boundaries[start + i - 2]``; an edge then
    replaces a waiting one of its direction, after any edge due by then has come."""
    decisions = []          # (due clock on the pin, level, decided at)
    previous = 0
    for i, (_, laser) in enumerate(frames):
        if laser != previous:
            at = boundaries[start + i]
            delay = on_us if laser else off_us
            decisions.append((at + LATENCY + delay * clocks_per_us, laser,
                              boundaries[start + i - 2]))
            previous = laser
    waiting = {}
    level, edges = 0, []

    def fire_until(limit):
        nonlocal level
        while waiting:
            due, lvl, at = min(waiting.values(), key=lambda e: (e[0], -e[2]))
            if due > limit:
                return
            del waiting[lvl]
            other = waiting.get(1 - lvl)
            if other is not None and other[2] < at:
                del waiting[1 - lvl]            # stale: decided before this edge
            if lvl != level:
                level = lvl
                edges.append((due, lvl))

    for due, lvl, at in decisions:
        fire_until(at + LATENCY)                # what comes due before the decision counts
        waiting[lvl] = (due, lvl, at)
    fire_until(float("inf"))
    return edges
