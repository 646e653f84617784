"""The field: where a drawing goes in it (:class:`Placement`, :func:`place`), field mm and
galvo units (:func:`to_galvo`, :func:`from_galvo`), the check that a job stays inside it
(:func:`field_check`), and the error a job that cannot be planned raises (:class:`PlanError`).

Field mm have (0, 0) at the field centre and Y up. Galvo units run 0 … 65535 across the field,
32768 at the centre, ``units_per_mm = 65536 / field_mm``, Y up is increasing units.
"""

from dataclasses import dataclass, replace
import math

import numpy as np

from ..gateware.points import FIELD_CENTRE, FIELD_MAX


__all__ = ["PlanError", "Placement", "place", "to_galvo", "from_galvo", "field_check",
           "CENTRE", "UNITS"]


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
