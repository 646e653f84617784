"""Commanded frame sequences of the scan patterns, in galvo units (one position per 10 µs frame).

* :func:`spiral_frames` is the Python model of the gateware's spiral sequencer and scale stage
  (docs/design/architecture.md). The full-pattern replay test (``tests/gateware/sources/test_spiral.py``) checks it
  frame for frame against the XY2-100 wires of the simulated system top, so the analysis speaks
  of what the gateware emits.
* :func:`raster_frames` is the line-by-line fill the paper compares the spiral with: lines at a
  constant speed, one after the other, the turn-arounds left to the mirror.

:class:`ScanHead` converts between millimetres on the work piece and galvo units.
"""

import math

import numpy as np

from ..gateware.field.scale import AMP_ONE
from ..gateware.host.regmap import BY_NAME
from ..gateware.sources.spiral_table import SpiralTable
from .galvo import FRAME_PERIOD, FULL_RANGE


__all__ = ["ScanHead", "Frames", "INTERPOLATIONS", "spiral_frames", "spiral_amplitude", "spiral_dwell_for_speed",
           "raster_frames"]


class ScanHead:
    """Scan head geometry: a square field of ``field_mm`` millimetres across 65536 galvo units.

    Parameters
    ----------
    field_mm : float
        Field side, mm. Default 110 mm (Wan et al. 2018: 110 mm ↔ 65536 units, 1 unit ≈ 1.68 µm;
        a typical f = 160 mm f-theta lens, as in Dai & Tang 2020).
    """

    def __init__(self, field_mm=110.0):
        if not isinstance(field_mm, (int, float)) or not 1 <= field_mm <= 2000:
            raise ValueError(f"field_mm must be a number of millimetres from 1 to 2000, "
                             f"not {field_mm!r}")
        self.field_mm = float(field_mm)

    @property
    def units_per_mm(self):
        return FULL_RANGE / self.field_mm

    def mm(self, units):
        """Galvo units (a length, or a position relative to the centre) in mm."""
        return np.asarray(units) / self.units_per_mm

    def units(self, mm):
        return np.asarray(mm) * self.units_per_mm

    def __repr__(self):
        return f"ScanHead(field_mm={self.field_mm:g})"


class Frames:
    """Commanded positions, one per 10 µs frame, and whether the laser may fire in each.

    Attributes
    ----------
    x, y : numpy.ndarray of int
        Galvo units, 0 … 65535.
    laser : numpy.ndarray of bool
        Laser enabled during the frame.
    points : numpy.ndarray of int
        Index of the pattern point each frame shows (for "the first p % of the pattern").
    """

    def __init__(self, x, y, laser=None, points=None):
        self.x = np.asarray(x, dtype=np.int64)
        self.y = np.asarray(y, dtype=np.int64)
        self.laser = np.ones(len(self.x), bool) if laser is None else np.asarray(laser, bool)
        self.points = np.arange(len(self.x)) if points is None else np.asarray(points)

    def __len__(self):
        return len(self.x)

    @property
    def duration(self):
        """Seconds the frames take on the wires."""
        return len(self.x) * FRAME_PERIOD


#: Settings of the ``spiral_interp`` register, by value.
INTERPOLATIONS = ("off", "linear")

#: Longest dwell the gateware interpolates (frames); longer ones are held.
MAX_INTERPOLATED_DWELL = 255


def _between(p, q, dwell):
    """Frames ``0 … dwell-1`` of the straight way from offsets ``p`` to ``q`` (arrays, one row
    per point): ``p + sign(q - p) × floor(|q - p| × k / dwell)``, rounded towards ``p``."""
    k = np.arange(dwell)
    p, q = np.asarray(p, np.int64)[:, None], np.asarray(q, np.int64)[:, None]
    return (p + np.sign(q - p) * (np.abs(q - p) * k // dwell)).ravel()


def _scaled(offsets, amp, centre):
    # The gateware's scale stage: centre + floor(offset × amp / AMP_ONE), saturated to 16 bits.
    return np.clip(centre + (np.asarray(offsets, np.int64) * amp) // AMP_ONE, 0, FULL_RANGE - 1)


def spiral_frames(table, *, dwell=BY_NAME["dwell"].reset,
                  amp=(BY_NAME["amp_x"].reset, BY_NAME["amp_y"].reset),
                  centre=(BY_NAME["center_x"].reset, BY_NAME["center_y"].reset),
                  x_range=None, y_range=None, count=None,
                  interpolation=INTERPOLATIONS[BY_NAME["spiral_interp"].reset]):
    """The spiral sequencer's frames after the scale stage, from its first point.

    Parameters
    ----------
    table : SpiralTable
    dwell : int
        Frames per point (the ``dwell`` register).
    amp, centre : (int, int)
        The ``amp_x/amp_y`` (Q1.15) and ``center_x/center_y`` (galvo units) registers.
    x_range, y_range : (int, int), optional
        ROM addresses walked, inclusive; default the paper's ``(0, N-1)`` and ``(1, N-2)``.
    count : int, optional
        Points to produce; default one whole pattern, lcm of the two cycle lengths.
    interpolation : str
        The ``spiral_interp`` register: ``"off"`` holds each point for its dwell, ``"linear"``
        (the reset) walks each frame part of the way to the next point (dwells up to
        :data:`MAX_INTERPOLATED_DWELL`).
    """
    if not isinstance(table, SpiralTable):
        raise TypeError(f"table must be a SpiralTable, not {table!r}")
    n = table.points
    x_range = (0, n - 1) if x_range is None else tuple(x_range)
    y_range = (1, n - 2) if y_range is None else tuple(y_range)
    for name, (first, last) in (("x_range", x_range), ("y_range", y_range)):
        if not 0 <= first <= last < n:
            raise ValueError(f"{name} must be (first, last) with 0 <= first <= last < {n}")
    low, high = BY_NAME["dwell"].low, BY_NAME["dwell"].high
    if not isinstance(dwell, int) or not low <= dwell <= high:
        raise ValueError(f"dwell must be an integer from {low} to {high} frames, not {dwell!r}")
    x_len = x_range[1] - x_range[0] + 1
    y_len = y_range[1] - y_range[0] + 1
    if count is None:
        count = math.lcm(x_len, y_len)
    if interpolation not in INTERPOLATIONS:
        raise ValueError(f"interpolation must be one of {', '.join(INTERPOLATIONS)}, "
                         f"not {interpolation!r}")
    k = np.arange(count + 1)
    x = np.asarray(table.x)[x_range[0] + k % x_len]
    y = np.asarray(table.y)[y_range[0] + k % y_len]
    if interpolation == "linear" and dwell <= MAX_INTERPOLATED_DWELL:
        x, y = _between(x[:-1], x[1:], dwell), _between(y[:-1], y[1:], dwell)
    else:
        x, y = np.repeat(x[:-1], dwell), np.repeat(y[:-1], dwell)
    return Frames(_scaled(x, amp[0], centre[0]), _scaled(y, amp[1], centre[1]),
                  points=np.repeat(k[:-1], dwell))


def spiral_amplitude(width_mm, head):
    """The Q1.15 amplitude whose pattern spans ``width_mm`` on ``head``'s field."""
    amp = round(head.units(width_mm) / 2 * AMP_ONE / 32767)
    if not BY_NAME["amp_x"].low <= amp <= BY_NAME["amp_x"].high:
        raise ValueError(f"a {width_mm:g} mm wide pattern does not fit a {head.field_mm:g} mm "
                         f"field")
    return amp


def spiral_dwell_for_speed(table, *, amp, speed_m_s, head, x_range=None, y_range=None):
    """The smallest dwell at which neither axis is commanded faster than ``speed_m_s``."""
    if not speed_m_s > 0:
        raise ValueError(f"speed must be positive, not {speed_m_s!r}")
    one = spiral_frames(table, dwell=1, amp=amp, x_range=x_range, y_range=y_range)
    steps = [np.max(np.abs(np.diff(np.append(axis, axis[0])))) for axis in (one.x, one.y)]
    largest_mm = float(head.mm(max(steps)))
    return max(1, math.ceil(largest_mm * 1e-3 / (speed_m_s * FRAME_PERIOD) - 1e-9))


def raster_frames(*, corner, size, spacing, step, lines_along="x", bidirectional=True,
                  turn_gate=0, passes=1):
    """Line-by-line fill of a rectangle (the paper's baseline), one position per frame: the
    sequence the gateware's raster mode emits (``gateware/sources/raster.py``).

    A line runs ``0, step, 2·step, …`` from its start and ends exactly on the far edge; a line
    run backwards visits the mirror image of those positions (``along − k·step``, then 0).

    Parameters
    ----------
    corner : (int, int)
        Lower-left corner, galvo units.
    size : (int, int)
        Width and height, galvo units.
    spacing : int
        Line spacing, galvo units.
    step : int
        Distance moved per 10 µs frame along a line, galvo units (sets the line speed).
    lines_along : "x" or "y"
        Axis the lines run along (the other one steps by ``spacing``).
    bidirectional : bool
        Serpentine (every other line reversed) or every line in the same direction with a
        jump back.
    turn_gate : int
        Frames at the start of each line after the first with the laser off, while the mirror
        turns round. 0 (default) keeps the laser on, as the paper's raster does: it is what
        over-burns the line ends.
    passes : int
        Passes over the rectangle, one after the other (from the second on, the first line is
        gated too).
    """
    (x0, y0), (width, height) = corner, size
    if not isinstance(passes, int) or passes < 1:
        raise ValueError(f"passes must be a positive whole number, not {passes!r}")
    for name, value in (("spacing", spacing), ("step", step)):
        if not isinstance(value, (int, np.integer)) or value < 1:
            raise ValueError(f"{name} must be a positive number of galvo units, not {value!r}")
    if min(x0, y0, width, height) < 0 or x0 + width >= FULL_RANGE or y0 + height >= FULL_RANGE:
        raise ValueError("the rectangle must lie within the field (0 … 65535)")
    if not isinstance(turn_gate, int) or turn_gate < 0:
        raise ValueError(f"turn_gate must be a whole number of frames, not {turn_gate!r}")
    if lines_along not in ("x", "y"):
        raise ValueError(f"lines_along must be 'x' or 'y', not {lines_along!r}")
    along, across = (width, height) if lines_along == "x" else (height, width)
    line = np.minimum(np.arange(0, along + step, step), along)
    line = line[np.concatenate(([True], np.diff(line) > 0))]    # end exactly, no repeat
    lines = across // spacing + 1
    positions_along, positions_across, laser, points = [], [], [], []
    for n in range(passes * lines):
        j = n % lines
        run = line if not (bidirectional and j % 2) else along - line
        positions_along.append(run)
        positions_across.append(np.full(len(run), j * spacing))
        enabled = np.ones(len(run), bool)
        if n > 0:
            enabled[:turn_gate] = False
        laser.append(enabled)
        points.append(np.full(len(run), n))
    along_pos = np.concatenate(positions_along)
    across_pos = np.concatenate(positions_across)
    if lines_along == "x":
        x, y = x0 + along_pos, y0 + across_pos
    else:
        x, y = x0 + across_pos, y0 + along_pos
    return Frames(x, y, laser=np.concatenate(laser), points=np.concatenate(points))
