"""Fills of a drawing's closed shapes: hatch sets (cross-hatch, an angle step a pass) and
contour rings, in the order a marking laser should take them.

EzCad2 gives an object up to three hatch sets, LightBurn cross-hatch and offset fill, meerk40t
an angle step per loop. Here:

* a :class:`HatchSet` is lines ``spacing_mm`` apart at ``angle_deg``, moved ``offset_mm``
  across, turned ``step_deg`` more on each pass; several sets fill the same shapes, one after
  the other (two at 0° and 90°: a cross-hatch);
* the lines of a set are taken line by line across the shape: ``serpentine`` (each line the
  other way from the last: the least jumping), ``oneway`` (every line the same way: every
  line starts cold from the same side, for an even mark where the material cares), or
  ``joined`` (serpentine, and where the step from one line's end to the next line's start
  lies inside the shape it is marked, not jumped: one stroke, no jump delay);
* a contour fill is rings inward from the shapes' edges, ``spacing_mm`` apart, through
  shapely's ``buffer`` (LightBurn's offset fill).

Shapes are filled by the even-odd rule (:func:`.hatch.hatch`); the contour's region is the
shapes' symmetric difference, the same rule for shapes that do not cross themselves (shapely
has no fill rule: a self-crossing outline is first made valid, its crossing kept).
"""

import enum
import math
from dataclasses import dataclass

import numpy as np
from shapely.geometry import LineString, Polygon
import shapely

from .field import PlanError
from .hatch import hatch, hatch_extent


__all__ = ["HatchSet", "LineOrder", "Contour", "hatch_strokes", "contour_rings", "oriented"]


#: Rings a contour fill makes at most.
MAX_RINGS = 10_000


class LineOrder(enum.Enum):
    """How the lines of a hatch set follow each other."""
    SERPENTINE = "serpentine"
    ONEWAY = "oneway"
    JOINED = "joined"


@dataclass(frozen=True)
class HatchSet:
    """Lines ``spacing_mm`` apart at ``angle_deg`` (from +X, counter-clockwise), moved
    ``offset_mm`` across, turned ``step_deg`` more on each pass after the first."""
    spacing_mm: float
    angle_deg: float = 0.0
    step_deg: float = 0.0
    offset_mm: float = 0.0

    def __post_init__(self):
        if not (math.isfinite(self.spacing_mm) and 0.001 <= self.spacing_mm <= 100):
            raise PlanError(f"hatch spacing {self.spacing_mm} mm: must be from 0.001 to 100")
        for name in ("angle_deg", "step_deg", "offset_mm"):
            if not math.isfinite(getattr(self, name)):
                raise PlanError(f"hatch {name.split('_')[0]} {getattr(self, name)}: must be a "
                                f"finite number")

    def angle_on_pass(self, index):
        """The lines' angle on pass ``index`` (0: the first)."""
        return (self.angle_deg + index * self.step_deg) % 360


@dataclass(frozen=True)
class Contour:
    """Rings inward from the shapes' edges, ``spacing_mm`` apart, the first that far in;
    ``count`` of them at most (None: until the shape is filled)."""
    spacing_mm: float
    count: int = None

    def __post_init__(self):
        if not (math.isfinite(self.spacing_mm) and 0.001 <= self.spacing_mm <= 100):
            raise PlanError(f"contour spacing {self.spacing_mm} mm: must be from 0.001 to 100")
        if self.count is not None and not 1 <= self.count <= MAX_RINGS:
            raise PlanError(f"contour rings {self.count}: must be from 1 to {MAX_RINGS}")


def shapes(paths, closed):
    """The closed paths grouped into shapes: each outline with the holes inside it (by the
    even-odd rule: a ring inside an odd number of others is a hole of the smallest of them
    that is inside an even number). Lists of indices into ``paths``, one a shape."""
    rings = [i for i, (p, c) in enumerate(zip(paths, closed)) if c and len(p) >= 4]
    polygons = [shapely.make_valid(Polygon(np.asarray(paths[i], dtype=float)))
                for i in rings]
    tree = shapely.STRtree(polygons)
    inside = []                         # for each ring, the rings that contain it
    for k, polygon in enumerate(polygons):
        point = polygon.representative_point() if not polygon.is_empty else None
        around = [] if point is None else [j for j in tree.query(point, "intersects")
                                           if j != k and polygons[j].area > polygon.area and
                                           polygons[j].contains(polygon)]
        inside.append(around)
    groups, owner = {}, {}
    for k in range(len(rings)):
        if len(inside[k]) % 2 == 0:
            groups[k] = [rings[k]]
            owner[k] = k
    for k in range(len(rings)):
        if len(inside[k]) % 2:
            outer = [j for j in inside[k] if len(inside[j]) == len(inside[k]) - 1]
            if outer:
                groups[min(outer, key=lambda j: polygons[j].area)].append(rings[k])
    return list(groups.values())


def hatch_strokes(paths, closed, hatch_set, *, pass_index=0, order=LineOrder.SERPENTINE,
                  per_shape=True, across=None):
    """The hatch lines of one set on one pass, as strokes (open polylines, field mm) in marking
    order: one stroke a line run, or, ``joined``, runs joined into longer strokes.

    ``per_shape``: each shape (:func:`shapes`: an outline and its holes) hatched whole before
    the next, the nearest next (a line of text jumps letter to letter, not across every letter
    on each line), on the one grid of lines the whole drawing's would be on; else the lines
    run across all of them."""
    if per_shape:
        groups = shapes(paths, closed)
        if len(groups) > 1:
            extent = hatch_extent(paths, closed, hatch_set.angle_on_pass(pass_index))
            blocks = [hatch_strokes([paths[i] for i in group], [True] * len(group), hatch_set,
                                    pass_index=pass_index, order=order, per_shape=False,
                                    across=extent)
                      for group in groups]
            return _nearest_blocks([b for b in blocks if b], LineOrder(order))
    order = LineOrder(order)
    runs, lines = hatch(paths, closed, hatch_set.spacing_mm,
                        hatch_set.angle_on_pass(pass_index), offset_mm=hatch_set.offset_mm,
                        with_lines=True, across=across)
    if not runs:
        return []
    by_line = {}
    for run, line in zip(runs, lines):
        by_line.setdefault(line, []).append(run)
    # Strip by strip, each line by line, every other line reversed; the strips one after the
    # other, the nearest next.
    strips = [_serpentine(strip, order) for strip in _strips(by_line)]
    strokes = strips[0] if len(strips) == 1 else \
        _nearest_blocks(strips, order, start=strips[0][0][0])
    if order is LineOrder.JOINED:
        strokes = _joined(strokes, paths, closed, hatch_set.spacing_mm)
    return strokes


def _strips(by_line):
    """The runs (``{line: runs along it, in order}``) as strips: runs on consecutive lines,
    each overlapping the last along the lines and no other run of either line. Where a hole
    splits the lines (or two branches meet), a strip ends and others start; so a shape with
    a hole is hatched around it a side at a time, not across it on every line (a boustrophedon
    decomposition)."""
    strips, open_runs, last_line = [], [], None
    for line in sorted(by_line):
        runs = by_line[line]
        direction = runs[0][-1] - runs[0][0]
        direction = direction / (np.hypot(*direction) or 1.0)
        spans = [tuple(sorted((float(run[0] @ direction), float(run[-1] @ direction))))
                 for run in runs]
        if last_line is None or line != last_line + 1:
            open_runs = []                      # a gap between lines: every strip ends
        here = []
        for k, (low, high) in enumerate(spans):
            above = [o for o in open_runs if o[0] < high and low < o[1]]
            strip = None
            if len(above) == 1:
                a_low, a_high, index = above[0]
                below = [q for q in spans if q[0] < a_high and a_low < q[1]]
                if len(below) == 1:
                    strip = index
            if strip is None:
                strips.append([])
                strip = len(strips) - 1
            strips[strip].append(runs[k])
            here.append((low, high, strip))
        open_runs, last_line = here, line
    return strips


def _serpentine(strip, order):
    """A strip's runs, every other one reversed (not oneway)."""
    if order is LineOrder.ONEWAY:
        return list(strip)
    return [run[::-1] if rank % 2 else run for rank, run in enumerate(strip)]


def _nearest_blocks(blocks, order, start=(0.0, 0.0)):
    """Blocks of strokes one after the other, each the nearest to where the last ended, taken
    from its nearer end (oneway: its lines' order reversed, their directions kept)."""
    here, strokes = np.asarray(start, dtype=float), []
    todo = list(blocks)
    while todo:
        def cost(block):
            first = np.hypot(*(block[0][0] - here))
            last = np.hypot(*((block[-1][0] if order is LineOrder.ONEWAY else block[-1][-1])
                              - here))
            return min(first, last)
        block = todo.pop(min(range(len(todo)), key=lambda k: cost(todo[k])))
        strokes += oriented(block, here, order)
        here = strokes[-1][-1]
    return strokes


def oriented(block, here, order):
    """A set's strokes taken from whichever end is nearer ``here``: reversed whole
    (serpentine, joined), or, oneway, its lines' order reversed and their directions kept."""
    if order is LineOrder.ONEWAY:
        if np.hypot(*(block[-1][0] - here)) < np.hypot(*(block[0][0] - here)):
            return block[::-1]
    elif np.hypot(*(block[-1][-1] - here)) < np.hypot(*(block[0][0] - here)):
        return [stroke[::-1] for stroke in reversed(block)]
    return block


def _region(paths, closed):
    """The closed shapes as one shapely area, by the even-odd rule (symmetric difference)."""
    region = None
    for path, is_closed in zip(paths, closed):
        if not is_closed or len(path) < 3:
            continue
        shape = shapely.make_valid(Polygon(np.asarray(path, dtype=float)))
        region = shape if region is None else region.symmetric_difference(shape)
    return region


def _joined(strokes, paths, closed, spacing_mm):
    """Consecutive strokes joined where the step between them is short (at most two spacings)
    and lies inside the shapes, so it can be marked."""
    region = _region(paths, closed)
    if region is None or region.is_empty:
        return strokes
    # The step runs along the shape's edge at worst: a little slack for the flattening.
    inside = region.buffer(spacing_mm * 1e-3)
    joined = [np.asarray(strokes[0])]
    for stroke in strokes[1:]:
        end, start = joined[-1][-1], stroke[0]
        if np.hypot(*(start - end)) <= 2 * spacing_mm and \
                inside.covers(LineString([end, start])):
            joined[-1] = np.vstack([joined[-1], stroke])
        else:
            joined.append(np.asarray(stroke))
    return joined


def contour_rings(paths, closed, contour):
    """The rings of a contour fill (closed polylines, field mm), outermost first."""
    region = _region(paths, closed)
    rings = []
    if region is None or region.is_empty:
        return rings
    k = 1
    while contour.count is None or k <= contour.count:
        inner = region.buffer(-k * contour.spacing_mm, join_style="mitre", mitre_limit=2.0)
        if inner.is_empty:
            break
        for polygon in getattr(inner, "geoms", [inner]):
            if polygon.geom_type != "Polygon":
                continue
            for ring in [polygon.exterior, *polygon.interiors]:
                rings.append(np.asarray(ring.coords, dtype=float))
        if len(rings) > MAX_RINGS:
            raise PlanError(f"contour spacing {contour.spacing_mm} mm: more than "
                            f"{MAX_RINGS:,} rings")
        k += 1
    return rings
