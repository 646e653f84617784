"""The corner holds of RTC's variable polygon delay, worked out on the host.

Between two marks the mirrors hold the corner, laser on, for the polygon delay; scaled by
(1 - cos φ), φ the turn at the corner (SCANLAB's RTC5/6 "variable polygon delay"): nothing
straight on, the full delay at a right angle, twice it at a reversal. The board cannot take
the angle (it would need a multiplier and a divider it has no room for), so the host sends
each corner's hold in whole 10 µs frames with the mark that leaves it, in ``vec_op`` bits 7:1.
"""

import math

from ..gateware.host.regmap import CORNER_FRAMES_MAX, FRAME_US
from .segments import IO, PIXELS


__all__ = ["corner_frames", "FRAME_US"]


def corner_frames(segments, polygon_delay_us, *, start=(32768, 32768)):
    """Frames to hold the corner before each segment: 0 for a jump, for a mark not after a
    mark, and for a zero-length mark (which turns nothing); ``polygon_delay_us × (1 - cos φ)``
    rounded up to frames, at most :data:`CORNER_FRAMES_MAX`, for a mark after a mark.

    ``segments`` are ``(op, x, y)`` in galvo units, from ``start``."""
    if isinstance(polygon_delay_us, bool) or not isinstance(polygon_delay_us, (int, float)) or \
            not math.isfinite(polygon_delay_us) or polygon_delay_us < 0:
        raise ValueError(f"a polygon delay is a number of µs from 0 up, not "
                         f"{polygon_delay_us!r}")
    holds = []
    here = start
    direction = None                # the last mark's, while marks follow each other
    for op, x, y in segments:
        if op in (PIXELS, IO):          # (a pixel word, an I/O step: no move, no corner)
            holds.append(0)
            continue
        dx, dy = x - here[0], y - here[1]
        length = math.hypot(dx, dy)
        hold = 0
        if op != "mark":
            direction = None
        elif length:
            if direction is not None:
                cos_phi = (dx * direction[0] + dy * direction[1]) / length
                us = polygon_delay_us * (1 - max(-1.0, min(1.0, cos_phi)))
                hold = min(CORNER_FRAMES_MAX, math.ceil(us / FRAME_US - 1e-9))
            direction = (dx / length, dy / length)
        holds.append(hold)
        here = (x, y)
    return holds
