"""A plain Python model of the spiral scanner, written from Dai & Tang 2020 and README "What it
does", not from the gateware.

Given the two tables and the settings, it lists the positions a scan head receives, frame by
frame from power-up.
"""

PARK = (32768, 32768)


def scaled(offset, gain, centre):
    """Galvo position of one axis: gain is Q1.15 (32768 = 1.0), result clamped to 16 bits."""
    value = centre + (offset * gain) // 32768     # Python's // floors, as the spec says
    return min(max(value, 0), 65535)


def spiral_points(table_x, table_y, count, *, x_range, y_range, gain=(32768, 32768),
                  centre=(32768, 32768)):
    """The first ``count`` spiral points in galvo units."""
    xs = list(range(x_range[0], x_range[1] + 1))
    ys = list(range(y_range[0], y_range[1] + 1))
    return [(scaled(table_x[xs[k % len(xs)]], gain[0], centre[0]),
             scaled(table_y[ys[k % len(ys)]], gain[1], centre[1]))
            for k in range(count)]


def spiral_frames(table_x, table_y, count, *, dwell, **kwargs):
    """Frames from power-up: two park frames (the first point is due at the end of the first
    frame and goes out at the end of the second), then each point for ``dwell`` frames."""
    frames = [PARK, PARK]
    for point in spiral_points(table_x, table_y, count, **kwargs):
        frames.extend([point] * dwell)
    return frames
