"""A plain Python model of the spiral scanner, written from Dai & Tang 2020 and the docs'
architecture page (docs/design/architecture.md), not from the gateware.

Given the two tables and the settings, it lists the positions a scan head receives, frame by
frame from power-up.
"""

PARK = (32768, 32768)

#: Longest dwell that is interpolated (docs/results/analyses.md): longer ones are held.
MAX_INTERPOLATED_DWELL = 255


def scaled(offset, gain, centre):
    """Galvo position of one axis: gain is Q1.15 (32768 = 1.0), result clamped to 16 bits."""
    value = centre + (offset * gain) // 32768     # Python's // floors, as the spec says
    return min(max(value, 0), 65535)


def spiral_offsets(table_x, table_y, count, *, x_range, y_range):
    """The first ``count`` spiral points as table offsets (signed, 0 = centre)."""
    xs = list(range(x_range[0], x_range[1] + 1))
    ys = list(range(y_range[0], y_range[1] + 1))
    return [(table_x[xs[k % len(xs)]], table_y[ys[k % len(ys)]]) for k in range(count)]


def spiral_points(table_x, table_y, count, *, x_range, y_range, gain=(32768, 32768),
                  centre=(32768, 32768)):
    """The first ``count`` spiral points in galvo units."""
    return [(scaled(x, gain[0], centre[0]), scaled(y, gain[1], centre[1]))
            for x, y in spiral_offsets(table_x, table_y, count, x_range=x_range,
                                       y_range=y_range)]


def between(p, q, k, d):
    """Frame ``k`` of ``d`` on the straight way from offset ``p`` to ``q`` (README "Held points"):
    the displacement ``(q - p)·k/d`` with its magnitude rounded down, so towards ``p``."""
    magnitude = abs(q - p) * k // d
    return p + magnitude if q >= p else p - magnitude


def _per_point(value, count):
    return list(value) if isinstance(value, (list, tuple)) else [value] * count


def spiral_frames(table_x, table_y, count, *, dwell, interp=0, x_range, y_range,
                  gain=(32768, 32768), centre=(32768, 32768)):
    """Frames from power-up: two park frames (the first point is due at the end of the first
    frame and goes out at the end of the second), then each point for its dwell.

    ``dwell`` and ``interp`` are one value or one per point (a register written while the
    spiral runs takes effect at a point). With ``interp`` 1 a point's frames walk to the next
    point (:func:`between`); with 0 they hold it."""
    dwells, interps = _per_point(dwell, count), _per_point(interp, count)
    offsets = spiral_offsets(table_x, table_y, count + 1, x_range=x_range, y_range=y_range)
    frames = [PARK, PARK]
    for i in range(count):
        (px, py), (qx, qy) = offsets[i], offsets[i + 1]
        d = dwells[i]
        for k in range(d):
            if interps[i] and d <= MAX_INTERPOLATED_DWELL:
                x, y = between(px, qx, k, d), between(py, qy, k, d)
            else:
                x, y = px, py
            frames.append((scaled(x, gain[0], centre[0]), scaled(y, gain[1], centre[1])))
    return frames
