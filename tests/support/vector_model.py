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


def pixel_bits(words):
    """The bits of pixel words, in the order the points take them: each word's x then y,
    bit 0 first (the register map's words)."""
    return [(value >> k) & 1 for x, y in words for value in (x | y << 16,) for k in range(32)]


def job_model(job, pitch, pulses):
    """(position, pulses) runs for a job from the park position: a jump's point gets none; a
    mark first marks where it starts if the laser was off, then every DDA point. A pixel line
    (``"line"``) steps the same points, each lit only if its bit (of the ``"pixels"`` words
    right after the line, in order) is 1; the points past the last bit are dark. A pixel word
    anywhere else moves nothing."""
    position, pen_down, out = PARK, False, []
    for index, (op, x, y) in enumerate(job):
        if op == "pixels":
            continue
        if op == "jump":
            out.append(((x, y), 0))
            pen_down = False
        else:
            points = [] if pen_down else [position]
            pen_down = True
            points += dda(position, (x, y), pitch)
            if op == "line":
                words = []
                for later in job[index + 1:]:
                    if later[0] != "pixels":
                        break
                    words.append(later[1:])
                bits = pixel_bits(words)
                out += [(p, pulses if k < len(bits) and bits[k] else 0)
                        for k, p in enumerate(points)]
            else:
                out += [(p, pulses) for p in points]
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


