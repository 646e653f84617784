"""A plain Python model of vector marking, written from Wan et al. 2018's line marking,
with exact decimal arithmetic (not the gateware's fixed point)."""

from decimal import Decimal, ROUND_FLOOR, localcontext


#: Where the mirrors park after reset.
PARK = (32768, 32768)


# --- the model, from Wan et al. 2018 -----------------------------------------------------------

def half_up(value):
    return int((value + Decimal("0.5")).to_integral_value(rounding=ROUND_FLOOR))


def dda(start, end, pitch):
    """Wan et al.'s DDA: step the major axis by p/√(1+m²), the minor by m times that, round each
    coordinate; stop before the end and finish on it exactly. Nothing for zero length."""
    (x0, y0), (x1, y1) = start, end
    dx, dy = x1 - x0, y1 - y0
    if dx == 0 and dy == 0:
        return []
    with localcontext() as context:
        context.prec = 60                       # far beyond the gateware's 2^-32
        return _dda(x0, y0, x1, y1, dx, dy, pitch)


def _dda(x0, y0, x1, y1, dx, dy, pitch):
    swap = abs(dy) > abs(dx)
    major, minor = (dy, dx) if swap else (dx, dy)
    slope = Decimal(minor) / Decimal(major)
    step = Decimal(pitch) / (1 + slope * slope).sqrt()        # along the major axis
    sign = 1 if major > 0 else -1
    points, k = [], 1
    while k * step < abs(major):
        a = k * step * sign
        b = a * slope
        da, db = (b, a) if swap else (a, b)
        points.append((half_up(x0 + da), half_up(y0 + db)))
        k += 1
    return points + [(x1, y1)]


def job_model(job, pitch, pulses):
    """(position, pulses) runs for a job from the park position: a jump's point gets none; a
    mark first marks where it starts if the laser was off, then every DDA point."""
    position, pen_down, out = PARK, False, []
    for op, x, y in job:
        if op == "jump":
            out.append(((x, y), 0))
            pen_down = False
        else:
            if not pen_down:
                out.append((position, pulses))
                pen_down = True
            out += [(p, pulses) for p in dda(position, (x, y), pitch)]
        position = (x, y)
    return merge(out)


def merge(runs):
    merged = []
    for point, count in runs:
        if merged and merged[-1][0] == point:
            merged[-1] = (point, merged[-1][1] + count)
        else:
            merged.append((point, count))
    return merged


