"""The drawing: polylines in mm, Y up, as every reader gives them and every planner takes
them (:class:`Drawing`); what a path is picked by (:class:`PathStyle`); and the one error a
drawing that cannot be marked raises (:class:`DrawingError`)."""

from dataclasses import dataclass

import numpy as np


__all__ = ["DrawingError", "Drawing", "PathStyle", "FileLayer"]


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
    styles : tuple of :class:`PathStyle`
        One per path (or none at all): its colour and layer, what a :class:`~galvoscan.plan.layers.Layer`
        picks it by.
    layers : tuple of :class:`FileLayer`
        The layers whose settings the file itself gives (a G-code file's S and F), each
        holding the paths whose style's layer is its name.
    """
    name: str
    paths: tuple
    closed: tuple
    skipped: tuple = ()
    notes: tuple = ()
    styles: tuple = ()
    layers: tuple = ()

    def bounds(self):
        """``(xmin, ymin, xmax, ymax)`` in mm."""
        points = np.concatenate(self.paths)
        return (*points.min(axis=0).tolist(), *points.max(axis=0).tolist())



@dataclass(frozen=True)
class PathStyle:
    """What a drawing's path is picked by: its colour (``#rrggbb``, the SVG stroke, else the
    fill; None: none) and the layer it is on (an Inkscape layer's label, a DXF layer's name;
    None: none)."""
    colour: str = None
    layer: str = None


@dataclass(frozen=True)
class FileLayer:
    """A layer whose settings the drawing's file gives (a G-code file's S and F): its
    ``name``, what its paths' :attr:`PathStyle.layer` is, and its speed (mm/s) and power
    (% of the laser's maximum)."""
    name: str
    speed_mm_s: float
    power_percent: float
