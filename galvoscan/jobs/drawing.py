"""Drawings to mark: SVG (svgelements) and DXF (ezdxf) files as polylines in mm, Y up.

Curves are flattened into chords within ``tolerance_mm`` of the true curve. Every problem with a
file is a :class:`DrawingError`, one line that names the file; nothing else escapes
:func:`load_drawing`. What the file holds but is not marked (text, images, hatches, dimensions,
hidden layers …) is counted in :attr:`Drawing.skipped`, so the user hears of it.

This module holds the common part (:class:`Drawing`, :class:`DrawingError`,
:func:`load_drawing` and the clean-up and checks both formats share) and the SVG reader. The DXF
reader is :mod:`.dxf`; it imports :class:`DrawingError` and the helpers from here, so
``load_drawing`` imports it only when it reads a DXF file (no import cycle).
"""

from collections import Counter
from dataclasses import dataclass
import io
import math
import re
from pathlib import Path

import numpy as np


__all__ = ["DrawingError", "Drawing", "load_drawing"]


#: Refused beyond this extent: no lens field is 10 m wide, so it is a unit mistake.
MAX_EXTENT_MM = 10_000.0
#: Below this, two consecutive points are one (float noise of transforms and flattening).
SAME_POINT_MM = 1e-9
MM_PER_PX = 25.4 / 96                       # svgelements gives px at 96 ppi
#: Chords one curve may be flattened into. A curve that fits in :data:`MAX_EXTENT_MM` needs far
#: fewer (a circle 10 m across at 0.01 mm: some 1,600); more means coordinates far beyond any
#: lens field (a unit mistake, a damaged file), refused before the points are made: a Bézier
#: with a control point at 9e14 would have taken 240 million points, gigabytes.
MAX_CHORDS = 1_000_000


class DrawingError(ValueError):
    """A drawing that cannot be marked; the message is one line naming the file."""


@dataclass(frozen=True, eq=False)          # eq=False: arrays have no truth value to compare
class Drawing:
    """A drawing as polylines.

    Attributes
    ----------
    name : str
        The file name.
    paths : tuple of numpy.ndarray
        Read-only float arrays of shape (n, 2), n >= 2, in mm, Y up.
    closed : tuple of bool
        One per path: it ends where it starts (its last point equals its first).
    skipped : tuple of str
        What the file holds but is not marked, e.g. ``"3 text elements (convert text to
        paths)"``.
    notes : tuple of str
        How the file was read, e.g. ``"DXF has no units ($INSUNITS 0): taken as mm"``.
    styles : tuple of :class:`~.layers.PathStyle`
        One per path (or none at all): its colour and layer, what a :class:`~.layers.Layer`
        picks it by.
    """
    name: str
    paths: tuple
    closed: tuple
    skipped: tuple = ()
    notes: tuple = ()
    styles: tuple = ()

    def bounds(self):
        """``(xmin, ymin, xmax, ymax)`` in mm."""
        points = np.concatenate(self.paths)
        return (*points.min(axis=0).tolist(), *points.max(axis=0).tolist())


def _one_line(error):
    text = " ".join(str(error).split()) or type(error).__name__
    return text if len(text) <= 120 else text[:117] + "..."


def _counted(counter, hints=None):
    """``["3 text elements (convert text to paths)"]`` from counts of singular phrases."""
    plural = lambda m: m[1] + ("ies" if m[2] else "s")          # noqa: E731
    return [f"{n} {what if n == 1 else re.sub(r'(element|path|entit)(y?)', plural, what, 1)}"
            f"{(hints or {}).get(what, '')}" for what, n in sorted(counter.items()) if n]


def load_drawing(path, *, tolerance_mm=0.01):
    """Read an SVG or DXF drawing.

    Parameters
    ----------
    path : str or os.PathLike
        ``.svg`` or ``.dxf`` (by suffix, any case).
    tolerance_mm : float
        The largest distance allowed between a chord and the curve it stands for.

    Returns
    -------
    Drawing

    Raises
    ------
    DrawingError
        For anything that is not a readable drawing with something to mark.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".job":
        raise DrawingError(f"{path}: a job file is in galvo units, not a drawing to place")
    if suffix not in (".svg", ".dxf"):
        raise DrawingError(f"{path}: not a drawing galvoscan reads (.svg, .dxf, .job)")
    if not (tolerance_mm > 0 and math.isfinite(tolerance_mm)):
        raise DrawingError(f"{path}: the flattening tolerance must be > 0 mm, not {tolerance_mm}")
    try:
        data = path.read_bytes()
    except IsADirectoryError:
        raise DrawingError(f"{path}: a folder, not a drawing") from None
    except FileNotFoundError:
        raise DrawingError(f"{path}: no such file") from None
    except OSError as error:
        raise DrawingError(f"{path}: cannot read ({error.strerror or _one_line(error)})") from None
    if not data.strip():
        raise DrawingError(f"{path}: empty file")
    try:
        if suffix == ".svg":
            reader = _read_svg
        else:
            from .dxf import _read_dxf      # here: .dxf imports this module
            reader = _read_dxf
        raw, closed, skipped, notes, styles = reader(data, tolerance_mm)
    except DrawingError as error:
        raise DrawingError(f"{path}: {error}") from None
    except Exception as error:              # the libraries raise many types on bad input
        kind = suffix[1:].upper()
        raise DrawingError(f"{path}: not a readable {kind} file ({_one_line(error)})") from None
    return _finish(path, raw, closed, skipped, notes, tolerance_mm, styles)


def _finish(path, raw, closed_flags, skipped, notes, tolerance_mm, styles):
    """Clean the polylines up and check them: one rule set for both formats."""
    paths, closed, kept, degenerate = [], [], [], 0
    for points, is_closed, style in zip(raw, closed_flags, styles):
        points = np.array(points, dtype=float).reshape(-1, 2)
        if not np.isfinite(points).all():
            raise DrawingError(f"{path}: coordinates that are not finite numbers")
        if len(points):
            step = np.hypot(*np.diff(points, axis=0).T)
            points = points[np.concatenate([[True], step > SAME_POINT_MM])]
        # A path back at its start, within what flattening promises anyway, is closed.
        if len(points) > 2 and np.hypot(*(points[-1] - points[0])) <= tolerance_mm:
            points[-1], is_closed = points[0], True
        elif is_closed and len(points) >= 2:
            points = np.vstack([points, points[:1]])
        if len(points) < 2:
            degenerate += 1
            continue
        points.flags.writeable = False
        paths.append(points)
        closed.append(bool(is_closed and len(points) > 2))
        kept.append(style)
    skipped = list(skipped) + _counted({"zero-length path": degenerate})
    if not paths:
        # (What was left out may be why: say it, so the reason is not lost.)
        why = f" (left out: {'; '.join(skipped)})" if skipped else ""
        raise DrawingError(f"{path}: no lines or curves to mark{why}")
    drawing = Drawing(path.name, tuple(paths), tuple(closed), tuple(skipped), tuple(notes),
                      tuple(kept))
    xmin, ymin, xmax, ymax = drawing.bounds()
    if max(xmax - xmin, ymax - ymin) > MAX_EXTENT_MM:
        said = [note for note in notes if "units" in note]
        raise DrawingError(f"{path}: {xmax - xmin:.6g} × {ymax - ymin:.6g} mm, more than "
                           f"{MAX_EXTENT_MM / 1000:g} m: check the drawing's units"
                           f"{f' ({said[0]})' if said else ''}")
    return drawing


def _chords(n):
    """``n``, the chords a curve is about to be flattened into, if it is not too many."""
    if not n <= MAX_CHORDS:                 # (nan too)
        raise DrawingError(f"a curve that would take more than {MAX_CHORDS:,} chords: "
                           f"coordinates far beyond any field (check the drawing's units)")
    return n


def _round_chords(radius, sweep, tolerance):
    """Chords within ``tolerance`` on an arc of ``radius`` turning ``sweep`` radians: a chord
    turning ``2 acos(1 - tolerance / radius)`` (written with asin, which stays above 0 where
    ``1 - tolerance / radius`` rounds to 1)."""
    step = 4 * math.asin(math.sqrt(tolerance / radius / 2)) if tolerance < radius else math.pi
    return _chords(max(1, math.ceil(abs(sweep) / step - 1e-9)))


# --- SVG ------------------------------------------------------------------------------------

def _arc_points(arc, tolerance_px):
    """An elliptical arc from its conjugate semi-diameters ``u``, ``v`` (``prx``, ``pry``
    minus the centre): any affine image of an ellipse is ``c + u cos t + v sin t``.

    svgelements' own ``Arc.point`` takes ``u`` and ``v`` as perpendicular, which a skew or a
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
    from svgelements import Arc, Close, CubicBezier, Move, QuadraticBezier

    subpaths, points, closed = [], [], False
    for segment in path:
        if isinstance(segment, Move) or segment.start is None or not points or closed:
            # A new subpath: at a Move, or drawing on after a Close.
            if points:
                subpaths.append((np.array(points), closed))
            first = segment.end if isinstance(segment, Move) else segment.start
            points, closed = ([] if first is None else [np.array(first, dtype=float)]), False
            if isinstance(segment, Move) or first is None:
                continue
        if isinstance(segment, Arc):
            points += _arc_points(segment, tolerance_px)
        elif isinstance(segment, (CubicBezier, QuadraticBezier)):
            points += _bezier_points(segment, tolerance_px)
        else:                               # Line, Close
            points.append(np.array(segment.end, dtype=float))
            closed = isinstance(segment, Close)
    if points:
        subpaths.append((np.array(points), closed))
    return subpaths


#: Units of an SVG size that svgelements converts (``None``/``""``: user units, px).
_SVG_UNITS = {None, "", "px", "mm", "cm", "in", "pt", "pc", "%", "em", "ex"}


def _read_svg(data, tolerance_mm):
    import svgelements as svg
    from .svg_screen import LAYER_ATTRIBUTE, screen_svg

    data, notes = screen_svg(data)
    document = svg.SVG.parse(io.BytesIO(data), reify=True, ppi=96)
    # svgelements reads a size in a unit it does not know as plain px: the drawing would come
    # out at a scale nobody asked for. Refuse it instead.
    for name in ("width", "height"):
        text = document.values.get(name)
        if text is not None and svg.Length(text).units not in _SVG_UNITS:
            raise DrawingError(f"the SVG's {name} {str(text)[:30]!r} is in a unit galvoscan "
                               f"does not know (mm, cm, in, pt, pc, px or none)")
    from .layers import PathStyle
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
    from .plan import PlanError
    from .text import svg_text_outlines
    from .svg_screen import FLOW_ATTRIBUTE, FLOW_X_ATTRIBUTE
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
