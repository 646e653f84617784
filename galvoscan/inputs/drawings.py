"""Drawings to mark: SVG (svgelements, :mod:`.svg`) and DXF (ezdxf, :mod:`.dxf`) files as
polylines in mm, Y up.

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
from .reading import _counted, _one_line
from .svg import _read_svg


__all__ = ["load_drawing"]


#: Refused beyond this extent: no lens field is 10 m wide, so it is a unit mistake.
MAX_EXTENT_MM = 10_000.0
#: Below this, two consecutive points are one (float noise of transforms and flattening).
SAME_POINT_MM = 1e-9


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
        reader = _read_svg if suffix == ".svg" else _read_dxf
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
