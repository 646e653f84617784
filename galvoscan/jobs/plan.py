"""Planning a marking job in field mm: placement, hatching, path order, pitch and pulses per
point for a speed, and the time it takes.

Field mm have (0, 0) at the field centre and Y up. Galvo units run 0 … 65535 across the field,
32768 at the centre, ``units_per_mm = 65536 / field_mm``, Y up is increasing units.

The speed and time part (:class:`Pitch`, :func:`choose_pitch`, :func:`estimate_seconds`,
:func:`jump_mark_lengths`) is in :mod:`.speed` and re-exported here; :mod:`.speed` takes
:class:`PlanError` and ``CENTRE`` from here only inside its functions (no import cycle).
"""

from dataclasses import dataclass, replace
import math

import numpy as np

from ..gateware.points import FIELD_CENTRE, FIELD_MAX
from .speed import Pitch, choose_pitch, estimate_seconds, jump_mark_lengths


__all__ = ["PlanError", "Placement", "place", "hatch", "hatch_extent", "order_paths",
           "jump_length", "Pitch",
           "choose_pitch",
           "estimate_seconds", "jump_mark_lengths", "to_galvo", "from_galvo", "field_check"]


CENTRE = FIELD_CENTRE
UNITS = FIELD_MAX + 1


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
    not multiples of 90° that box is a little larger than the turned drawing's own. With
    ``"page"`` the drawing keeps its own coordinates: its origin (a DXF's 0,0; an SVG's
    top-left corner, its Y turned up) lands on ``offset_mm``, and it is scaled and turned
    about that origin.

    Attributes
    ----------
    origin : str
        ``"centre"`` (or ``"center"``), ``"lower-left"`` or ``"page"``.
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
        if origin not in ("centre", "lower-left", "page"):
            raise PlanError(f"placement origin {self.origin!r}: centre, lower-left or page")
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
        if self.origin == "page":
            return matrix, np.array(self.offset_mm)
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


def hatch(paths, closed, spacing_mm, angle_deg=0.0, *, offset_mm=0.0, with_lines=False,
          across=None):
    """Lines filling the closed paths by the even-odd rule: a shape inside another is a hole,
    a shape inside that is filled again, a self-crossing star has an empty centre.

    Lines run at ``angle_deg`` from +X, ``spacing_mm`` apart, centred on the shapes' extent
    across them (the outermost at most half a spacing in from it), then moved ``offset_mm``
    across (to the left of their direction). Open paths are not hatched. ``across``: the
    ``(low, high)`` extent (mm across the lines, in the lines' own frame, as
    :func:`hatch_extent` gives it) to centre the lines on instead, so that shapes hatched one
    by one share one grid of lines.

    Returns
    -------
    list of numpy.ndarray
        ``(2, 2)`` arrays, start and end point in mm, all running the same way, line by line
        across the shapes and along each line in order.
    list of int, with ``with_lines``
        The line each run lies on (0 the first), the same for the runs of one line.

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
        return ([], []) if with_lines else []
    a = np.concatenate([r[:-1] for r in rings])
    b = np.concatenate([r[1:] for r in rings])
    if not (np.isfinite(a).all() and np.isfinite(b).all()):
        raise PlanError("hatch: paths with coordinates that are not finite numbers")
    ymin, ymax = across if across is not None else \
        (min(r[:, 1].min() for r in rings), max(r[:, 1].max() for r in rings))
    # (A shape a whole number of spacings across takes that many lines, half a spacing in
    # from its edges, even with the dust of a unit conversion on its extent: an SVG's mm come
    # back from svgelements' px some 5e-7 off, which made a line more, on the edges.)
    count = max(1, math.ceil((ymax - ymin) / spacing_mm - 1e-4))
    if count > 1_000_000:
        raise PlanError(f"hatch spacing {spacing_mm} mm: {count} lines, too many")
    first = ymin + ((ymax - ymin) - (count - 1) * spacing_mm) / 2
    if offset_mm:
        # Moved across: one line more, the first a spacing below, so the extent stays covered.
        if not math.isfinite(offset_mm):
            raise PlanError(f"hatch offset {offset_mm} mm: must be a finite number")
        first += math.fmod(offset_mm, spacing_mm) - spacing_mm
        count += 2
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
    lines = list(runs @ to_lines)               # turned back (to_lines is orthonormal)
    return (lines, [int(n) for n in line[0::2][keep]]) if with_lines else lines


def hatch_extent(paths, closed, angle_deg):
    """``(low, high)``: the closed paths' extent across lines at ``angle_deg``, in the lines'
    frame (what :func:`hatch` centres its lines on), or None if there is none."""
    turn = math.radians(angle_deg)
    across = np.array([-math.sin(turn), math.cos(turn)])
    values = [np.asarray(p, dtype=float) @ across for p, c in zip(paths, closed)
              if c and len(p) >= 3]
    if not values:
        return None
    return float(min(v.min() for v in values)), float(max(v.max() for v in values))


def _rotated(path, k):
    """A closed path started at its vertex ``k``."""
    return np.concatenate([path[k:-1], path[:k], path[k:k + 1]])


def jump_length(paths, start=(0.0, 0.0)):
    """mm jumped from ``start`` through ``paths`` in their order."""
    return _jumps([np.asarray(p, dtype=float) for p in paths], start)


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
