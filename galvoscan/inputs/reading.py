"""What the SVG and DXF readers share: the units a drawing's numbers may be in
(:data:`UNITS`), curves flattened into a bounded number of chords (:func:`_chords`,
:func:`_round_chords`; :class:`TooManyChords` names the entity), what a file holds but is not
marked counted in words (:func:`_counted`), and a library's error said in one line
(:func:`_one_line`)."""

import math
import re

from ..geometry.drawing import DrawingError


#: Chords one curve may be flattened into. A curve that fits in :data:`MAX_EXTENT_MM` needs far
#: fewer (a circle 10 m across at 0.01 mm: some 1,600); more means coordinates far beyond any
#: lens field (a unit mistake, a damaged file), refused before the points are made: a Bézier
#: with a control point at 9e14 would have taken 240 million points, gigabytes.
MAX_CHORDS = 1_000_000

#: The units a drawing's numbers may be said to be in (``mark --units``, a job file's
#: ``units``), in place of those it declares: mm each, and the word a refusal says.
#: (pt and px are CSS's: 1/72 and 1/96 in, as SVG and every browser take them.)
UNITS = {"mm": (1.0, "millimetres"), "cm": (10.0, "centimetres"), "m": (1000.0, "metres"),
         "in": (25.4, "inches"), "pt": (25.4 / 72, "points"), "px": (25.4 / 96, "pixels")}


class TooManyChords(DrawingError):
    """A curve that would take more than :data:`MAX_CHORDS` chords. The reader adds the
    element or entity it is in (``what``), that one's size in the drawing's mm (``size_mm``:
    width, height, or None) and the units it took the drawing's numbers in (``units``: what
    they were taken from, mm a unit), and :func:`.drawings.load_drawing` says it."""

    def __init__(self, what=None, size_mm=None, units=None):
        super().__init__(f"a curve that would take more than {MAX_CHORDS:,} chords")
        self.what, self.size_mm, self.units = what, size_mm, units


def _one_line(error):
    text = " ".join(str(error).split()) or type(error).__name__
    return text if len(text) <= 120 else text[:117] + "..."


def _counted(counter, hints=None):
    """``["3 text elements (convert text to paths)"]`` from counts of singular phrases."""
    plural = lambda m: m[1] + ("ies" if m[2] else "s")          # noqa: E731
    return [f"{n} {what if n == 1 else re.sub(r'(element|path|entit)(y?)', plural, what, 1)}"
            f"{(hints or {}).get(what, '')}" for what, n in sorted(counter.items()) if n]



def _chords(n):
    """``n``, the chords a curve is about to be flattened into, if it is not too many."""
    if not n <= MAX_CHORDS:                 # (nan too)
        raise TooManyChords()
    return n


def _round_chords(radius, sweep, tolerance):
    """Chords within ``tolerance`` on an arc of ``radius`` turning ``sweep`` radians: a chord
    turning ``2 acos(1 - tolerance / radius)`` (written with asin, which stays above 0 where
    ``1 - tolerance / radius`` rounds to 1)."""
    step = 4 * math.asin(math.sqrt(tolerance / radius / 2)) if tolerance < radius else math.pi
    return _chords(max(1, math.ceil(abs(sweep) / step - 1e-9)))
