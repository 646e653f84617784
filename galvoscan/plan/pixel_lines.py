"""A photo as pixel lines (SCANLAB RTC's pixel mode, EzCad's bitmap mode): each row of the
dithered grid one sweep at one speed, its pixels lit by bits queued after it, instead of a
mark for each run of dark cells and a jump for each gap.

* A row is swept from a little before its first dark pixel to a little after its last (the
  **run-in** and **run-out**, dark, three tracking delays at the line's speed: the mirrors
  reach the speed before the first pixel and keep it past the last), so every pixel is
  marked at the line's speed with the same pulses.
* Rows go back and forth (unless one way is asked), and each row is sent the mirrors'
  **tracking delay** ahead of its pixels in its own direction (the **scan offset**): a
  mirror that lags its set point by that time then puts each pixel where it belongs, and
  the two directions' edges meet.
* Between rows, a jump (its delay by its length, as every jump's).

The columns are one pitch apart, the pitch a whole number of galvo units: the photo's cells
are made that size (:func:`cell_units`).
"""

from dataclasses import dataclass
import math

import numpy as np

from ..geometry.field import CENTRE, UNITS, PlanError
from ..geometry.segments import JUMP, LINE, pixel_words


__all__ = ["PixelRaster", "PHOTO_LINES", "cell_units", "pixel_line_segments",
           "RUN_IN_TRACKING_DELAYS"]


#: How a photo may be marked (``mark --image-lines``, an ``[image]``'s ``lines``; the first
#: is the default): as pixel lines, or as a mark for each run of dark cells.
PHOTO_LINES = ("pixels", "runs")


#: The run-in and run-out, in tracking delays at the line's speed: a critically damped
#: mirror that starts from rest is within 2 % of its speed after three.
RUN_IN_TRACKING_DELAYS = 3


@dataclass(frozen=True, eq=False)
class PixelRaster:
    """A photo's dithered grid to mark as pixel lines.

    Attributes
    ----------
    dark : ndarray of bool
        Rows × columns, ``True`` for a dark (marked) cell, row 0 at the top.
    cell_units : int
        Galvo units between two columns and between two rows: the pitch its lines are
        stepped at.
    bidirectional : bool
        Rows back and forth; else every row left to right.
    """
    dark: np.ndarray
    cell_units: int
    bidirectional: bool = True


def cell_units(cell_mm, units_per_mm):
    """The whole galvo units nearest ``cell_mm`` (at least one): a pixel line's pitch."""
    return max(1, round(cell_mm * units_per_mm))


def pixel_line_segments(raster, corner_mm, *, field_mm, speed_mm_s, tracking_delay_us):
    """``(segments, notes)``: the raster's rows as jumps, pixel lines and pixel words, its
    grid's lower-left corner at ``corner_mm`` (field mm), swept at ``speed_mm_s`` by mirrors
    that lag ``tracking_delay_us``. Rows with no dark pixel are left out. A
    :class:`~galvoscan.geometry.field.PlanError` when a run-in reaches past the field."""
    dark = np.asarray(raster.dark, dtype=bool)
    rows = dark.shape[0]
    units_per_mm = UNITS / field_mm
    pitch = raster.cell_units
    lag_s = tracking_delay_us * 1e-6
    run = max(1, math.ceil(RUN_IN_TRACKING_DELAYS * speed_mm_s * lag_s * units_per_mm / pitch))
    offset = round(speed_mm_s * lag_s * units_per_mm)
    # The grid's corner, galvo units: cell (r, c)'s centre is (c + ½, rows - r - ½) pitches
    # from it (photo_drawing's cells).
    corner_x, corner_y = (v * units_per_mm + CENTRE for v in corner_mm)
    segments, lines = [], 0
    for r in range(rows):
        cols = np.flatnonzero(dark[r])
        if not len(cols):
            continue
        first, last = int(cols[0]), int(cols[-1])
        bits = [0] * run + [int(b) for b in dark[r, first:last + 1]] + [0] * run
        # The run-in's first point, at the left end.
        x_first = round(corner_x + (first - run + 0.5) * pitch)
        x_last = x_first + (len(bits) - 1) * pitch
        y = round(corner_y + (rows - r - 0.5) * pitch)
        forward = not (raster.bidirectional and lines % 2)
        start, end = (x_first + offset, x_last + offset) if forward else \
            (x_last - offset, x_first - offset)
        for value in (start, end, y):
            if not 0 <= value < UNITS:
                raise PlanError(f"the photo's pixel lines run in and out "
                                f"{run * pitch / units_per_mm:.2f} mm past its sides at "
                                f"{speed_mm_s:g} mm/s, beyond the field's edge: move it "
                                f"that far in")
        segments += [(JUMP, start, y), (LINE, end, y)]
        segments += pixel_words(bits if forward else bits[::-1])
        lines += 1
    notes = [f"photo as {lines:,} pixel lines at {speed_mm_s:.0f} mm/s"
             f"{', back and forth' if raster.bidirectional else ', one way'}: run in and out "
             f"{run} pixels ({run * pitch / units_per_mm:.2f} mm), sent "
             f"{tracking_delay_us:g} µs ({offset / units_per_mm * 1000:.0f} µm) ahead of "
             f"the mirrors' lag"]
    return segments, notes
