"""The SVG reader of :func:`.drawings.load_drawing`: an SVG file (svgelements) as polylines in
mm, Y up: shapes and paths with their transforms, arcs and Béziers flattened, ``<text>`` as glyph
outlines laid out by resvg's usvg (:mod:`.svg_text`), after :mod:`.svg_screen` has screened
it."""

import io
import math

import numpy as np
import svgelements as svg

from ..geometry.drawing import DrawingError, PathStyle
from .reading import UNITS, TooManyChords, _chords, _counted, _round_chords
from .svg_screen import LAYER_ATTRIBUTE, screen_svg
from .svg_text import texts_as_paths


MM_PER_PX = UNITS["px"][0]                  # svgelements gives px at 96 ppi


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


def bezier_points(segment, tolerance_px):
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
            points += bezier_points(segment, tolerance_px)
        else:                               # Line, svg.Close
            points.append(np.array(segment.end, dtype=float))
            closed = isinstance(segment, svg.Close)
    if points:
        subpaths.append((np.array(points), closed))
    return subpaths


#: Units of an SVG size that svgelements converts (``None``/``""``: user units, px).
_SVG_UNITS = {None, "", "px", "mm", "cm", "in", "pt", "pc", "%", "em", "ex"}


def _svg_units(document, asked, notes):
    """``(to_mm, (what the units were taken from, mm a unit))``: ``to_mm`` the 2 × 3 affine
    map from svgelements' px (the root's viewBox applied) to mm, Y up. ``asked`` (a
    :data:`~.reading.UNITS` key): the drawing's own numbers, its user units, are in that unit
    (the root's width, height and viewBox undone); None: as its width, height and viewBox
    say."""
    width, height = (document.values.get(name) for name in ("width", "height"))
    viewport = document.viewbox_transform
    m = svg.Matrix(viewport) if viewport else svg.Matrix()
    px_per_user = np.array([[m.a, m.c, m.e], [m.b, m.d, m.f]], dtype=float)
    if asked is None:
        per_unit = MM_PER_PX * math.sqrt(abs(np.linalg.det(px_per_user[:, :2])))
        size = " and ".join(f"{name} {value}" for name, value in
                            (("width", width), ("height", height)) if value)
        said = f"its {size}: {per_unit:.4g} mm a unit" if size else \
            "no width and height: its numbers taken as px, 96 per inch"
        return np.array([[MM_PER_PX, 0, 0], [0, -MM_PER_PX, 0]]), (said, per_unit)
    mm, name = UNITS[asked]
    if abs(np.linalg.det(px_per_user[:, :2])) < 1e-300:
        raise DrawingError("the SVG's viewBox or size is zero wide or high")
    inverse = np.linalg.inv(px_per_user[:, :2])
    user = np.column_stack([inverse, -inverse @ px_per_user[:, 2]])
    notes.append(f"SVG numbers taken as {name} (--units {asked}; its width {width}, height "
                 f"{height})")
    return np.diag([mm, -mm]) @ user, (f"--units {asked}", mm)


def _element_said(element):
    """An SVG element as its file names it: its tag, and its id if it has one."""
    tag, name = element.values.get("tag") or type(element).__name__.lower(), element.id
    return f"<{tag}{f' id={name!r}' if name else ''}> element"


def _read_svg(data, tolerance_mm, units_asked=None):
    """``(polylines in mm, closed flags, skipped, notes, styles, (what the units were taken
    from, mm a unit))``; ``units_asked``: the unit the numbers are in (a
    :data:`~.reading.UNITS` key), in place of the root's width, height and viewBox."""

    data, notes = screen_svg(data)
    # Each <text> as its glyphs' outlines, <path> elements read below as any other shape.
    data, text_notes, skipped = texts_as_paths(data)
    notes += text_notes
    document = svg.SVG.parse(io.BytesIO(data), reify=True, ppi=96)
    # svgelements reads a size in a unit it does not know as plain px: the drawing would come
    # out at a scale nobody asked for. Refuse it instead (unless the units are given).
    for name in ("width", "height"):
        text = document.values.get(name)
        if units_asked is None and text is not None and \
                svg.Length(text).units not in _SVG_UNITS:
            raise DrawingError(f"the SVG's {name} {str(text)[:30]!r} is in a unit galvoscan "
                               f"does not know (mm, cm, in, pt, pc, px or none; or give "
                               f"--units)")
    to_mm, units_said = _svg_units(document, units_asked, notes)
    # Flattened within the tolerance where the map to mm stretches most.
    tolerance_px = tolerance_mm / np.linalg.norm(to_mm[:, :2], 2)

    def in_mm(points_px):
        return points_px @ to_mm[:, :2].T + to_mm[:, 2]

    paths, closed, styles = [], [], []
    for element in document.elements():
        if not isinstance(element, (svg.Shape, svg.Text, svg.Image)):
            continue                        # groups, the document, <use> (its copy follows)
        try:
            _read_element(element, tolerance_px, in_mm, paths, closed, styles, skipped)
        except TooManyChords:
            try:
                box = element.bbox()
                size = None if box is None else \
                    tuple(np.abs(to_mm[:, :2]) @ [box[2] - box[0], box[3] - box[1]])
            except Exception:               # (svgelements cannot bound it: said without)
                size = None
            raise TooManyChords(_element_said(element), size, units_said) from None
    return paths, closed, _counted(skipped), notes, styles, units_said


def _read_element(element, tolerance_px, in_mm, paths, closed, styles, skipped):
    """One shape, text or image: its polylines in mm appended, or why not counted."""
    if str(element.values.get("visibility", "")).lower() in ("hidden", "collapse"):
        skipped["hidden element"] += 1
    elif isinstance(element, svg.Text):
        # (Only where the file is no XML that ElementTree reads, which svgelements reads no
        # better: every other <text> is outlines by now.)
        skipped["text element left out (not laid out)"] += 1
    elif isinstance(element, svg.Image):
        skipped["image element"] += 1
    else:
        style = PathStyle(_svg_colour(element), element.values.get(LAYER_ATTRIBUTE))
        # Path(shape) keeps the shape's own transform aside: abs() applies it.
        for points_px, is_closed in _svg_subpaths(abs(svg.Path(element)), tolerance_px):
            paths.append(in_mm(points_px))
            closed.append(is_closed)
            styles.append(style)


def _svg_colour(element):
    """The element's stroke colour as ``#rrggbb``, else its fill's; None for neither."""
    for paint in (element.stroke, element.fill):
        if paint is not None and paint.value is not None and paint.alpha != 0:
            return paint.hexrgb.lower()
    return None
