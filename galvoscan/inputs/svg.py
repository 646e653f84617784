"""The SVG reader of :func:`.drawings.load_drawing`: an SVG file (svgelements) as polylines in
mm, Y up: shapes and paths with their transforms, arcs and Béziers flattened, ``<text>`` as glyph
outlines of an installed font (:mod:`.text`), after :mod:`.svg_screen` has screened it."""

from collections import Counter
import io
import math

import numpy as np
import svgelements as svg

from ..geometry.drawing import DrawingError, PathStyle
from ..geometry.field import PlanError
from .reading import _chords, _counted, _round_chords
from .svg_screen import FLOW_ATTRIBUTE, FLOW_X_ATTRIBUTE, LAYER_ATTRIBUTE, screen_svg
from .text import svg_text_outlines


MM_PER_PX = 25.4 / 96                       # svgelements gives px at 96 ppi


def _arc_points(arc, tolerance_px):
    """An elliptical arc from its conjugate semi-diameters ``u``, ``v`` (``prx``, ``pry``
    minus the centre): any affine image of an ellipse is ``c + u cos t + v sin t``.

    svgelements' own ``svg.Arc.point`` takes ``u`` and ``v`` as perpendicular, which a skew or a
    turned non-uniform scale breaks (0.75 mm off on a skewed 10 mm ellipse). ``n`` equal steps
    in ``t`` leave chords within ``a (1 - cos(sweep / 2n))``, ``a`` the largest semi-axis.
    """
    c = np.array(arc.center, dtype=float)
    uv = np.column_stack([np.array(arc.prx, float) - c, np.array(arc.pry, float) - c])
    start, end = np.array(arc.start, dtype=float), np.array(arc.end, dtype=float)
    if abs(np.linalg.det(uv)) < 1e-12 or arc.sweep == 0:
        return [end]
    t0 = math.atan2(*np.linalg.solve(uv, start - c)[::-1])
    major = np.linalg.norm(uv, 2)

    def at(t):
        return c + (uv @ np.array([np.cos(t), np.sin(t)])).T

    # svgelements keeps the sweep relative to (u, u turned +90°), flipping it under a mirror:
    # relative to (u, v) it is that times the sign of u × v. Checked against the arc's end (a
    # half turn lands there either way round).
    sweep = arc.sweep * (1.0 if np.linalg.det(uv) > 0 else -1.0)
    misses = [np.hypot(*(at(np.array([t0 + s]))[0] - end)) for s in (sweep, -sweep)]
    sweep = -sweep if misses[0] > misses[1] + 1e-9 * major else sweep
    n = _round_chords(major, sweep, tolerance_px)
    points = at(t0 + sweep * np.arange(1, n + 1) / n)
    points[-1] = end
    return list(points)


def _bezier_points(segment, tolerance_px):
    """A Bézier curve in ``n`` equal parameter steps: linear interpolation over a step ``h``
    is within ``h² / 8 · max |B''|``, and ``|B''|`` is bounded by the control polygon."""
    p = np.array([np.array(q, dtype=float) for q in segment])
    degree = len(p) - 1
    second = np.max(np.hypot(*(p[:-2] - 2 * p[1:-1] + p[2:]).T)) * degree * (degree - 1)
    n = _chords(max(1, math.ceil(math.sqrt(second / (8 * tolerance_px)))))
    return list(np.asarray(segment.npoint(np.arange(1, n + 1) / n), dtype=float))


def _svg_subpaths(path, tolerance_px):
    """The flattened subpaths of one reified svgelements Path: ``(points_px, closed)``."""

    subpaths, points, closed = [], [], False
    for segment in path:
        if isinstance(segment, svg.Move) or segment.start is None or not points or closed:
            # A new subpath: at a svg.Move, or drawing on after a svg.Close.
            if points:
                subpaths.append((np.array(points), closed))
            first = segment.end if isinstance(segment, svg.Move) else segment.start
            points, closed = ([] if first is None else [np.array(first, dtype=float)]), False
            if isinstance(segment, svg.Move) or first is None:
                continue
        if isinstance(segment, svg.Arc):
            points += _arc_points(segment, tolerance_px)
        elif isinstance(segment, (svg.CubicBezier, svg.QuadraticBezier)):
            points += _bezier_points(segment, tolerance_px)
        else:                               # Line, svg.Close
            points.append(np.array(segment.end, dtype=float))
            closed = isinstance(segment, svg.Close)
    if points:
        subpaths.append((np.array(points), closed))
    return subpaths


#: Units of an SVG size that svgelements converts (``None``/``""``: user units, px).
_SVG_UNITS = {None, "", "px", "mm", "cm", "in", "pt", "pc", "%", "em", "ex"}


def _read_svg(data, tolerance_mm):

    data, notes = screen_svg(data)
    document = svg.SVG.parse(io.BytesIO(data), reify=True, ppi=96)
    # svgelements reads a size in a unit it does not know as plain px: the drawing would come
    # out at a scale nobody asked for. Refuse it instead.
    for name in ("width", "height"):
        text = document.values.get(name)
        if text is not None and svg.Length(text).units not in _SVG_UNITS:
            raise DrawingError(f"the SVG's {name} {str(text)[:30]!r} is in a unit galvoscan "
                               f"does not know (mm, cm, in, pt, pc, px or none)")
    paths, closed, styles, skipped = [], [], [], Counter()
    for element in document.elements():
        if not isinstance(element, (svg.Shape, svg.Text, svg.Image)):
            continue                        # groups, the document, <use> (its copy follows)
        if str(element.values.get("visibility", "")).lower() in ("hidden", "collapse"):
            skipped["hidden element"] += 1
        elif isinstance(element, svg.Text):
            if element.text and element.text.strip():
                found = _svg_text(element, tolerance_mm / MM_PER_PX)
                if isinstance(found, str):
                    skipped[found] += 1
                    continue
                style = PathStyle(_svg_colour(element), element.values.get(LAYER_ATTRIBUTE))
                for points_px in found:
                    paths.append(points_px * [MM_PER_PX, -MM_PER_PX])  # Y down → Y up
                    closed.append(True)
                    styles.append(style)
        elif isinstance(element, svg.Image):
            skipped["image element"] += 1
        else:
            style = PathStyle(_svg_colour(element), element.values.get(LAYER_ATTRIBUTE))
            # Path(shape) keeps the shape's own transform aside: abs() applies it.
            for points_px, is_closed in _svg_subpaths(abs(svg.Path(element)),
                                                      tolerance_mm / MM_PER_PX):
                paths.append(points_px * [MM_PER_PX, -MM_PER_PX])      # Y down → Y up
                closed.append(is_closed)
                styles.append(style)
    return paths, closed, _counted(skipped), notes, styles


def _svg_text(element, tolerance_px):
    """A ``<text>`` (or ``<tspan>``: svgelements gives each its own) as glyph outlines in px,
    placed by its x, y, anchor and transform; or, for a font that is not installed, what is
    said of it instead."""
    weight = element.font_weight if element.font_weight not in (None, "") else "normal"
    before = element.values.get(FLOW_ATTRIBUTE)
    x0 = element.x
    if before is not None:                          # follows on from the text before it
        try:
            x0 = float(element.values.get(FLOW_X_ATTRIBUTE))      # its dx in it
        except (TypeError, ValueError):
            before = None
    try:
        outlines, _ = svg_text_outlines(
            element.text, element.font_family, float(element.font_size or 16),
            weight=weight, style=element.values.get("font-style") or "normal",
            anchor=element.anchor or "start", tolerance=tolerance_px, before=before or "")
    except PlanError as error:
        return f"text element left out: its {error} (convert text to paths)"
    m = element.transform
    placed = []
    for glyph in outlines:
        x = x0 + glyph[:, 0]
        y = element.y - glyph[:, 1]                 # the glyphs' Y up, the SVG's down
        placed.append(np.column_stack([m.a * x + m.c * y + m.e, m.b * x + m.d * y + m.f]))
    return placed


def _svg_colour(element):
    """The element's stroke colour as ``#rrggbb``, else its fill's; None for neither."""
    for paint in (element.stroke, element.fill):
        if paint is not None and paint.value is not None and paint.alpha != 0:
            return paint.hexrgb.lower()
    return None
