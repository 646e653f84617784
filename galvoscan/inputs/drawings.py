"""Drawings to mark: SVG (svgelements, :mod:`.svg`), DXF (ezdxf, :mod:`.dxf`) and G-code
(:mod:`.gcode`) files as polylines in mm, Y up.

Curves are flattened into chords within ``tolerance_mm`` of the true curve. Every problem with a
file is a :class:`~galvoscan.geometry.drawing.DrawingError`, one line that names the file;
nothing else escapes :func:`load_drawing`. What the file holds but is not marked (text, images,
hatches, dimensions, hidden layers …) is counted in ``Drawing.skipped``, so the user hears of it.
The clean-up and checks both formats share are here (:func:`_finish`).
"""

import math
from pathlib import Path

import numpy as np

from ..geometry.drawing import Drawing, DrawingError
from .dxf import _read_dxf
from .gcode import GCODE_SUFFIXES, _read_gcode
from .reading import MAX_CHORDS, UNITS, TooManyChords, _counted, _one_line
from .svg import _read_svg


__all__ = ["load_drawing", "UNITS"]


#: Refused beyond this extent: no lens field is 10 m wide, so it is a unit mistake.
MAX_EXTENT_MM = 10_000.0
#: The sizes a drawing may be placed at, smallest and largest (``mark --scale``).
SCALES = (1e-3, 1e3)
#: Below this, two consecutive points are one (float noise of transforms and flattening).
SAME_POINT_MM = 1e-9


def load_drawing(path, *, tolerance_mm=0.01, units=None, scale=1.0, s_max=None):
    """Read an SVG, DXF or G-code drawing.

    Parameters
    ----------
    path : str or os.PathLike
        ``.svg``, ``.dxf`` or G-code (``.gcode``, ``.gco``, ``.gc``, ``.nc``, ``.ngc``), by
        suffix, any case.
    tolerance_mm : float
        The largest distance allowed between a chord and the curve it stands for, as marked
        (at ``scale``).
    units : str or None
        The unit the drawing's numbers are in (a key of :data:`UNITS`: ``mm``, ``cm``, ``m``,
        ``in``, ``pt``, ``px``), in place of what it declares (an SVG's width, height and
        viewBox; a DXF's $INSUNITS; G-code's G20 and G21); None: what it declares.
    scale : float
        The size factor it will be placed at (the drawing returned is not scaled): curves are
        flattened for the size they are marked at, and the size refused beyond is that size.
    s_max : float or None
        G-code only: the S value that is full power (None: GRBL's default ``$30``,
        :data:`~.gcode.S_MAX`).

    Returns
    -------
    Drawing
        A G-code file's with its ``layers``: one for each distinct S and F it marks with.

    Raises
    ------
    DrawingError
        For anything that is not a readable drawing with something to mark.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".job":
        raise DrawingError(f"{path}: a job file is in galvo units, not a drawing to place")
    gcode = suffix in GCODE_SUFFIXES
    if suffix not in (".svg", ".dxf") and not gcode:
        raise DrawingError(f"{path}: not a drawing galvoscan reads (.svg, .dxf, "
                           f"{', '.join(GCODE_SUFFIXES)}, .job)")
    if s_max is not None and not gcode:
        raise DrawingError(f"{path}: an S maximum is for G-code, not {suffix or 'this file'}")
    if not (tolerance_mm > 0 and math.isfinite(tolerance_mm)):
        raise DrawingError(f"{path}: the flattening tolerance must be > 0 mm, not {tolerance_mm}")
    if units is not None and units not in UNITS:
        raise DrawingError(f"{path}: units {units!r}: one of {', '.join(UNITS)}")
    if not (scale > 0 and math.isfinite(scale)):
        raise DrawingError(f"{path}: the scale must be > 0, not {scale}")
    # The chords are made in the drawing's own mm: finer where it is scaled down (a chord
    # 0.01 mm off as marked is 10 mm off in a drawing marked at 1/1000).
    tolerance = tolerance_mm / scale
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
    layers = ()
    try:
        if gcode:
            raw, closed, skipped, notes, styles, units_said, layers = \
                _read_gcode(data, tolerance, units, s_max)
        else:
            reader = _read_svg if suffix == ".svg" else _read_dxf
            raw, closed, skipped, notes, styles, units_said = reader(data, tolerance, units)
    except TooManyChords as error:
        raise DrawingError(f"{path}: {_chords_said(error, scale, tolerance_mm)}") from None
    except DrawingError as error:
        raise DrawingError(f"{path}: {error}") from None
    except Exception as error:              # the libraries raise many types on bad input
        kind = "G-code" if gcode else suffix[1:].upper()
        raise DrawingError(f"{path}: not a readable {kind} file ({_one_line(error)})") from None
    return _finish(path, raw, closed, skipped, notes, tolerance, styles, units_said, scale,
                   layers)


def _pair_said(width_mm, height_mm):
    """A width and height as a person reads them: both in m when the larger is a metre or
    more, else in mm; 3 figures, thousands grouped (``1,200 × 800 m``)."""
    per, unit = (1000.0, "m") if max(width_mm, height_mm) >= 1000 else (1.0, "mm")

    def figures(mm):
        value = float(f"{mm / per:.3g}")
        return f"{value:,.0f}" if value >= 100 else f"{value:g}"
    return f"{figures(width_mm)} × {figures(height_mm)} {unit}"


def _scale_said(fits):
    """The largest scale that fits, rounded down to 2 figures (it must fit as said)."""
    digits = 1 - math.floor(math.log10(fits))
    return f"{math.floor(fits * 10 ** digits) / 10 ** digits:g}"


def _ways_out(mm_per_unit, scale_said):
    """What a drawing too large may be marked with: its numbers taken as mm, when it was
    read in a larger unit; a ``scale_said`` (or none)."""
    return "give " + ", or ".join(
        (["--units mm if its numbers are millimetres"] if mm_per_unit > 1 else []) +
        ([scale_said] if scale_said else [])) if scale_said or mm_per_unit > 1 else \
        "check its units (--units)"


def _chords_said(error, scale, tolerance_mm):
    """The refusal of a curve with too many chords: the element or entity, its size as
    marked, the units it was read in, and the ways out."""
    known = error.size_mm is not None and all(map(math.isfinite, error.size_mm))
    size = f", {_pair_said(*(v * scale for v in error.size_mm))}" if known else ""
    said, mm_per_unit = error.units or (None, 1.0)
    where = f"{error.what}{size}{f' at --scale {scale:g}' if size and scale != 1 else ''}" \
        f"{f' ({said})' if said else ''}: a curve in it" if error.what else "a curve"
    return (f"{where} would take more than {MAX_CHORDS:,} chords within {tolerance_mm:g} mm: "
            f"coordinates far beyond any field: {_ways_out(mm_per_unit, 'a smaller --scale')}")


def _finish(path, raw, closed_flags, skipped, notes, tolerance_mm, styles, units_said, scale,
            layers=()):
    """Clean the polylines up and check them: one rule set for every format (``tolerance_mm``
    in the drawing's own mm, ``scale`` the size it is marked at); the file's ``layers`` kept
    where a path is left on them."""
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
    held = {style.layer for style in kept if style is not None}
    drawing = Drawing(path.name, tuple(paths), tuple(closed), tuple(skipped), tuple(notes),
                      tuple(kept), tuple(layer for layer in layers if layer.name in held))
    xmin, ymin, xmax, ymax = drawing.bounds()
    width, height = (xmax - xmin) * scale, (ymax - ymin) * scale
    if max(width, height) > MAX_EXTENT_MM:
        said, mm_per_unit = units_said
        fits = MAX_EXTENT_MM / max(width, height) * scale      # the largest scale that fits
        scale_said = f"--scale {_scale_said(fits)} or less" if fits >= SCALES[0] else None
        raise DrawingError(
            f"{path}: {_pair_said(width, height)}"
            f"{f' at --scale {scale:g}' if scale != 1 else ''} ({said}), more than "
            f"{MAX_EXTENT_MM / 1000:g} m: {_ways_out(mm_per_unit, scale_said)}")
    return drawing
