"""A plain Python model of the wobble figure on vector marks (SCANLAB RTC's "wobbel": an
ellipse laid over the marked path), written from its description, in floating point: the
unit vector of each line, the ellipse's two amplitudes along and across it, its frequency in
turns per second, and the frame count since marking began."""

import math

from vector_model import PARK, dda


def marked_points(job, pitch):
    """The marked points of a job in marking order, each with the unit vector of the line it
    lies on: a line's points and end point get the line's own direction when the line is longer
    than the pitch; a mark's first point (the laser was off) and a line no longer than the
    pitch keep that of the last longer line (+X before any). A point that repeats the one
    before it while the laser stays on (a DDA point that rounds onto the line's end) is one
    run of frames on the wires, so one point here."""
    position, pen_down, direction, out = PARK, False, (1.0, 0.0), []
    for op, x, y in job:
        if op == "jump":
            pen_down = False
        else:
            if not pen_down:
                out.append((position, direction))
                pen_down = True
            dx, dy = x - position[0], y - position[1]
            length = math.hypot(dx, dy)
            if length > pitch:
                direction = (dx / length, dy / length)
            for point in dda(position, (x, y), pitch):
                if point != out[-1][0]:
                    out.append((point, direction))
        position = (x, y)
    return out


def offset(along, across, hz, frame_rate, frames_marked, direction):
    """The figure's offset ``frames_marked`` frames after marking began: along the line
    ``along · sin θ``, across it (to the left) ``across · cos θ``, θ = 2π · hz · t."""
    theta = 2 * math.pi * hz * frames_marked / frame_rate
    ux, uy = direction
    a, c = along * math.sin(theta), across * math.cos(theta)
    return a * ux - c * uy, a * uy + c * ux


def wobbled_frames(frames, marked, points, *, along, across, hz, frame_rate=100_000):
    """The positions a wobbled job puts on the wires, frame for frame, from the same job's
    frames without wobble (``frames``, and whether each is marked): each marked frame gets its
    point plus the figure's offset, counting frames from the first of a run of marked frames;
    the others pass as they are. ``points``: :func:`marked_points`, one per run of marked
    frames on one point, in order. Returns (x, y) floats, unclamped."""
    out, run, index, since = [], None, -1, 0
    for k, (position, on) in enumerate(zip(frames, marked)):
        if not on:
            out.append(position)
            run, since = None, 0
            continue
        if run != position:
            index += 1
            run = position
            assert points[index][0] == position, (k, points[index], position)
        dx, dy = offset(along, across, hz, frame_rate, since, points[index][1])
        out.append((position[0] + dx, position[1] + dy))
        since += 1
    assert index == len(points) - 1, "every marked point is marked"
    return out
