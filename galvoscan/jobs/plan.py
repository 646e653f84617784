"""Planning a marking job in field mm: placement, hatching, path order, pitch and pulses per
point for a speed, and the time it takes.

Field mm have (0, 0) at the field centre and Y up. Galvo units run 0 … 65535 across the field,
32768 at the centre, ``units_per_mm = 65536 / field_mm``, Y up is increasing units.
"""

from dataclasses import dataclass, replace
import math

import numpy as np


__all__ = ["PlanError", "Placement", "place", "hatch", "order_paths", "Pitch", "choose_pitch",
           "estimate_seconds", "jump_mark_lengths", "to_galvo", "from_galvo", "field_check"]


CENTRE = 32768
UNITS = 65536


class PlanError(ValueError):
    """A job that cannot be planned as asked; the message is one line."""


def _mm(value):
    """``−55.0``, ``55.001``: one decimal, more only when they matter (1 µm)."""
    text = f"{value:.3f}".rstrip("0")
    text = text + "0" if text.endswith(".") else text
    return text.replace("-", "\u2212") if text.strip("-0.") else "0.0"


@dataclass(frozen=True)
class Placement:
    """Where a drawing goes in the field.

    The drawing is scaled by ``scale`` and turned by ``rotate_deg`` (counter-clockwise) about its
    bounding-box centre; then moved so that its reference point lands on ``offset_mm``. The
    reference is the bounding-box centre (``"centre"``) or the lower-left corner
    (``"lower-left"``) of the box around the scaled, turned bounding box. For turns that are
    not multiples of 90° that box is a little larger than the turned drawing's own.

    Attributes
    ----------
    origin : str
        ``"centre"`` (or ``"center"``) or ``"lower-left"``.
    offset_mm : tuple of float
        Field mm, (0, 0) the field centre, Y up.
    scale : float
        > 0.
    rotate_deg : float
        Counter-clockwise.
    """
    origin: str = "centre"
    offset_mm: tuple = (0.0, 0.0)
    scale: float = 1.0
    rotate_deg: float = 0.0

    def __post_init__(self):
        origin = {"center": "centre"}.get(self.origin, self.origin)
        if origin not in ("centre", "lower-left"):
            raise PlanError(f"placement origin {self.origin!r}: centre or lower-left")
        if not (self.scale > 0 and math.isfinite(self.scale)):
            raise PlanError(f"placement scale {self.scale}: must be > 0")
        try:
            offset = tuple(float(v) for v in self.offset_mm)
            good = len(offset) == 2 and all(map(math.isfinite, offset + (self.rotate_deg,)))
        except (TypeError, ValueError):
            good = False
        if not good:
            raise PlanError(f"placement offset {self.offset_mm} mm, turn {self.rotate_deg}°: "
                            "finite numbers needed")
        object.__setattr__(self, "origin", origin)
        object.__setattr__(self, "offset_mm", offset)

    def _affine(self, bounds):
        """``(matrix, translation)``: field = matrix @ drawing + translation."""
        xmin, ymin, xmax, ymax = bounds
        centre = np.array([(xmin + xmax) / 2, (ymin + ymax) / 2])
        turn = math.radians(self.rotate_deg)
        matrix = self.scale * np.array([[math.cos(turn), -math.sin(turn)],
                                        [math.sin(turn), math.cos(turn)]])
        reference = np.zeros(2)             # where the centre goes, before the offset
        if self.origin == "lower-left":
            half = np.array([xmax - xmin, ymax - ymin]) / 2
            reference = np.abs(matrix) @ half   # half the size of the turned box
        return matrix, np.array(self.offset_mm) + reference - matrix @ centre

    def forward(self, points, bounds):
        """Drawing mm → field mm. ``bounds`` is the drawing's ``(xmin, ymin, xmax, ymax)``."""
        matrix, translation = self._affine(bounds)
        return np.asarray(points, dtype=float) @ matrix.T + translation

    def inverse(self, points, bounds):
        """Field mm → drawing mm: the exact inverse of :meth:`forward` (to float rounding)."""
        matrix, translation = self._affine(bounds)
        return np.linalg.solve(matrix, (np.asarray(points, dtype=float) - translation).T).T


def place(drawing, placement):
    """The drawing moved into field mm.

    Returns
    -------
    Drawing
        The same drawing (name, closed flags, skipped, notes) with its paths in field mm.
    """
    bounds = drawing.bounds()
    paths = []
    for path in drawing.paths:
        moved = placement.forward(path, bounds)
        moved.flags.writeable = False
        paths.append(moved)
    return replace(drawing, paths=tuple(paths))


def hatch(paths, closed, spacing_mm, angle_deg=0.0):
    """Lines filling the closed paths by the even-odd rule: a shape inside another is a hole,
    a shape inside that is filled again, a self-crossing star has an empty centre.

    Lines run at ``angle_deg`` from +X, ``spacing_mm`` apart, centred on the shapes' extent
    across them (the outermost at most half a spacing in from it). Open paths are not hatched.

    Returns
    -------
    list of numpy.ndarray
        ``(2, 2)`` arrays, start and end point in mm, all running the same way.

    Notes
    -----
    A scanline fill rather than shapely: GEOS has no fill rule (``make_valid`` fills a star
    whole), and its overlay of each line with the area took 48 s for 400 circles (this, 0.5 s).
    On each line the edge crossings (an edge counts where one end is above the line and the
    other not, so a vertex on the line counts once or twice, never wrongly), sorted, pair up
    into the inside runs: that pairing is the even-odd rule itself.
    """
    if not (spacing_mm > 0 and math.isfinite(spacing_mm)):
        raise PlanError(f"hatch spacing {spacing_mm} mm: must be > 0")
    turn = math.radians(angle_deg)
    # Lines horizontal: turn the drawing by -angle, hatch, turn the lines back.
    to_lines = np.array([[math.cos(turn), math.sin(turn)], [-math.sin(turn), math.cos(turn)]])
    rings = []
    for path, is_closed in zip(paths, closed):
        path = np.asarray(path, dtype=float)
        if is_closed and len(path) >= 3:
            path = path if np.array_equal(path[0], path[-1]) else np.vstack([path, path[:1]])
            rings.append(path @ to_lines.T)
    if not rings:
        return []
    a = np.concatenate([r[:-1] for r in rings])
    b = np.concatenate([r[1:] for r in rings])
    if not (np.isfinite(a).all() and np.isfinite(b).all()):
        raise PlanError("hatch: paths with coordinates that are not finite numbers")
    ymin, ymax = min(r[:, 1].min() for r in rings), max(r[:, 1].max() for r in rings)
    count = max(1, math.ceil((ymax - ymin) / spacing_mm - 1e-9))
    if count > 1_000_000:
        raise PlanError(f"hatch spacing {spacing_mm} mm: {count} lines, too many")
    first = ymin + ((ymax - ymin) - (count - 1) * spacing_mm) / 2
    ys = first + spacing_mm * np.arange(count)
    # The lines each edge may cross (one more each side against rounding), then the exact test.
    low = np.clip(np.floor((np.minimum(a[:, 1], b[:, 1]) - first) / spacing_mm) - 1, 0, count)
    high = np.clip(np.ceil((np.maximum(a[:, 1], b[:, 1]) - first) / spacing_mm) + 1, 0, count)
    spans = (high - low).astype(np.int64)
    if spans.sum() > 50_000_000:                # about 2 GB of work arrays
        raise PlanError(f"hatch spacing {spacing_mm} mm: too many hatch lines for this drawing")
    edge = np.repeat(np.arange(len(a)), spans)
    line = (np.repeat(low.astype(np.int64) - np.cumsum(spans) + spans, spans) +
            np.arange(spans.sum()))
    y = ys[line]
    (ax, ay), (bx, by) = a[edge].T, b[edge].T
    crossing = (ay > y) != (by > y)
    edge, line, y = edge[crossing], line[crossing], y[crossing]
    (ax, ay), (bx, by) = a[edge].T, b[edge].T
    x = ax + (y - ay) * (bx - ax) / (by - ay)
    order = np.lexsort((x, line))
    line, x = line[order], x[order]
    starts, ends, levels = x[0::2], x[1::2], ys[line[0::2]]
    keep = ends - starts > 1e-12                # runs of zero length: a line grazing a vertex
    runs = np.stack([np.column_stack([starts, levels]), np.column_stack([ends, levels])],
                    axis=1)[keep]
    return list(runs @ to_lines)                # turned back (to_lines is orthonormal)


def _rotated(path, k):
    """A closed path started at its vertex ``k``."""
    return np.concatenate([path[k:-1], path[:k], path[k:k + 1]])


def _jumps(paths, start):
    here, total = np.asarray(start, dtype=float), 0.0
    for path in paths:
        total += math.hypot(*(path[0] - here))
        here = path[-1]
    return total


def order_paths(paths, closed, start=(0.0, 0.0)):
    """Paths in an order that cuts the jumps between them: greedy nearest neighbour.

    Each step goes to the nearest way into a path not yet taken: either end of an open path
    (reversed when entered at its end), any vertex of a closed one (started there). If that
    order jumps further than the input order, the input order is kept.

    Returns
    -------
    ordered : list of numpy.ndarray
    jump_before_mm, jump_after_mm : float
        Sum of the jumps from ``start`` through the paths, in input order and in the order
        returned.
    """
    import shapely

    paths = [np.asarray(p, dtype=float) for p in paths]
    before = _jumps(paths, start)
    if not paths:
        return [], 0.0, 0.0
    # Every way in: its point, path, vertex, and whether the path is taken reversed.
    entries, owners, vertices, flips = [], [], [], []
    for index, (path, is_closed) in enumerate(zip(paths, closed)):
        ks = np.arange(len(path) - 1) if is_closed and len(path) > 2 else [0, len(path) - 1]
        entries.append(path[ks])
        owners.append(np.full(len(ks), index))
        vertices.append(ks)
        flips.append(np.array([False] * len(ks) if len(ks) != 2 or is_closed else [False, True]))
    entries, owners = np.concatenate(entries), np.concatenate(owners)
    vertices, flips = np.concatenate(vertices), np.concatenate(flips)
    # Nearest alive entry: an R-tree asked for everything within a radius that doubles until
    # something alive is found; rebuilt without the dead once they are half of it.
    alive, ways_in = np.ones(len(paths), dtype=bool), np.bincount(owners)
    extent = np.ptp(entries, axis=0).max() + 1e-9
    radius = smallest = extent / math.sqrt(len(entries))
    ordered, here, tree, members, live = [], np.asarray(start, dtype=float), None, None, 0
    for _ in paths:
        if tree is None or 2 * live < len(members):
            members = np.flatnonzero(alive[owners])
            tree, live = shapely.STRtree(shapely.points(entries[members])), len(members)
        radius = max(smallest, radius)
        while True:
            near = members[tree.query(shapely.Point(here), "dwithin", radius)]
            near = near[alive[owners[near]]]
            if len(near):
                break
            radius *= 2
        distance = np.hypot(*(entries[near] - here).T)
        best = near[np.argmin(distance)]
        radius = 2 * distance.min()
        index, k = owners[best], vertices[best]
        path = paths[index]
        if flips[best]:
            path = path[::-1]
        elif k:
            path = _rotated(path, k)
        alive[index], live = False, live - ways_in[index]
        ordered.append(path)
        here = path[-1]
    after = _jumps(ordered, start)
    if after > before:
        return paths, before, before
    return ordered, before, after


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
                 max_prr_per_point_hz=100e3):
    """The pitch and pulses per point closest to a marking speed.

    ``v = pitch_units / units_per_mm * prr_hz / N`` mm/s, with N (pulses per point) in
    1 … 255, at least ``prr_hz / max_prr_per_point_hz`` (the most points a second the galvo
    link takes: one per 10 µs frame), and the pitch 1 … 65535 units, at most ``max_pitch_mm``.
    The closest speed wins; of equal ones, the smallest N (the finest pitch).

    Raises
    ------
    PlanError
        When nothing comes within 2 % of the speed; the message gives the reachable range.
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
    n = np.arange(low_n, 256)
    ideal = speed_mm_s * n * units_per_mm / prr_hz
    candidates = np.clip(np.stack([np.floor(ideal), np.ceil(ideal)]), 1, top)
    speeds = candidates / units_per_mm * prr_hz / n
    errors = np.abs(speeds - speed_mm_s) / speed_mm_s
    least = errors.min()
    row, column = np.nonzero(errors <= least * (1 + 1e-9) + 1e-15)
    best = np.lexsort((candidates[row, column], column))[0]       # smallest N, then pitch
    pitch, pulses = int(candidates[row[best], column[best]]), int(n[column[best]])
    speed = pitch / units_per_mm * prr_hz / pulses
    if abs(speed - speed_mm_s) / speed_mm_s > 0.02:
        slowest, fastest = prr_hz / units_per_mm / 255, top / units_per_mm * prr_hz / low_n
        raise PlanError(f"{speed_mm_s:g} mm/s is out of reach at {prr_hz / 1e3:g} kHz: "
                        f"{slowest:.3g} … {fastest:.4g} mm/s (pitch ≤ {max_pitch_mm:g} mm, "
                        f"{low_n} … 255 pulses per point)")
    return Pitch(pitch, pulses, speed, pitch / units_per_mm, (speed - speed_mm_s) / speed_mm_s)


def _walk(segments):
    """Lengths (galvo units) and ops of the segments, from the field centre."""
    here, out = (CENTRE, CENTRE), []
    for op, x, y in segments:
        out.append((op, math.hypot(x - here[0], y - here[1])))
        here = (x, y)
    return out


def estimate_seconds(segments, *, pitch_units, pulses_per_point, prr_hz, jump_delay_frames,
                     frame_s=10e-6):
    """An estimate of the time the board takes for the segments.

    ``segments`` are ``(op, x, y)`` in galvo units, op ``"jump"`` or ``"mark"``, from the field
    centre. A mark of ``L`` units is ``ceil(L / pitch_units)`` points, each held
    ``pulses_per_point / prr_hz`` s; a jump is ``1 + jump_delay_frames`` frames. Laser on/off
    delays, the host link and anything the board adds are not counted.
    """
    dwell_s = pulses_per_point / prr_hz
    total = 0.0
    for op, length in _walk(segments):
        if op == "mark":
            total += math.ceil(length / pitch_units - 1e-12) * dwell_s
        else:
            total += (1 + jump_delay_frames) * frame_s
    return total


def jump_mark_lengths(segments, units_per_mm):
    """``(mark_mm, jump_mm)``: the lengths marked and jumped, from the field centre."""
    mark = sum(length for op, length in _walk(segments) if op == "mark")
    jump = sum(length for op, length in _walk(segments) if op != "mark")
    return mark / units_per_mm, jump / units_per_mm


def to_galvo(points_mm, field_mm):
    """Field mm → galvo units (rounded, int64), refusing points outside the field."""
    units = np.rint(np.asarray(points_mm, dtype=float) * (UNITS / field_mm) + CENTRE)
    field_check([np.asarray(points_mm, dtype=float).reshape(-1, 2)], field_mm)
    return units.astype(np.int64)


def from_galvo(units, field_mm):
    """Galvo units → field mm."""
    return (np.asarray(units, dtype=float) - CENTRE) * (field_mm / UNITS)


def field_check(paths, field_mm):
    """Refuse paths (field mm) with any point outside 0 … 65535 galvo units after rounding."""
    points = np.concatenate([np.asarray(p, dtype=float).reshape(-1, 2) for p in paths] or
                            [np.empty((0, 2))])
    if not len(points):
        return
    units = np.rint(points * (UNITS / field_mm) + CENTRE)
    if not np.isfinite(units).all() or units.min() < 0 or units.max() > UNITS - 1:
        low, high = points.min(axis=0), points.max(axis=0)
        half = field_mm / 2
        raise PlanError(f"the drawing spans X {_mm(low[0])}…{_mm(high[0])} mm, "
                        f"Y {_mm(low[1])}…{_mm(high[1])} mm after placement; the field is "
                        f"{_mm(-half)}…{_mm(half)} mm ({field_mm:g} mm lens)")
