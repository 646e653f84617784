"""The G-code reader of :func:`.drawings.load_drawing`: a laser's G-code (GRBL's dialect, as
LightBurn, LaserGRBL and Inkscape's laser extensions write it) as polylines in mm, Y up, each
distinct pair of power (S) and feed (F) a layer of its own.

What it reads, as GRBL 1.1 in laser mode runs it:

- ``G0`` moves are jumps; ``G1``, ``G2`` and ``G3`` mark when the laser is on (``M3`` or
  ``M4`` with ``S`` above 0), else they too are jumps. ``M4``'s power that follows the
  speed is GRBL's answer to a gantry's acceleration: a galvo marks at one speed, so M3 and
  M4 are one.
- Arcs (``G2`` clockwise, ``G3`` counter-clockwise, in the XY plane) by their centre
  (``I``, ``J``: from the start, ``G91.1``, GRBL's only mode; or from the origin,
  ``G90.1``) or their radius (``R``; negative: the arc of more than half a turn), held to
  GRBL's own checks and flattened within the tolerance.
- ``G20`` inches, ``G21`` mm (numbers, arc words and ``F`` alike); ``G90`` absolute,
  ``G91`` relative moves.
- ``S`` and ``F`` as GRBL applies them: before the move on their line, and kept after.
  ``S`` is read as a share of the file's S maximum (GRBL's ``$30``, 1000 by default;
  Inkscape's J Tech extension writes ``S255`` for full power); ``F`` is mm (or inches) a
  minute.
- ``;`` and ``( )`` comments, ``N`` line numbers, a ``*`` checksum (checked), ``%`` lines,
  ``G17``, ``G40``, ``G54``, ``G94``, ``M2`` and ``M30`` (program ends: the laser off, moves
  absolute) are what they are. Dwells (``G4``), air assist (``M7``, ``M8``, ``M9``), pauses
  (``M0``, ``M1``), homing (``G28``, ``G30``), tool words and Z moves are nothing a galvo
  does: each is counted as left out. Anything else (another plane, inverse-time feed, an
  unknown word, a damaged line) is refused in one line naming the line.

:func:`_read_gcode` is called only by :func:`.drawings.load_drawing`, which turns what it
raises into a :class:`~galvoscan.geometry.drawing.DrawingError` naming the file and checks the
polylines it returns.
"""

import math
import re
from collections import Counter

import numpy as np

from ..geometry.drawing import DrawingError, FileLayer, PathStyle
from ..settings.laser import SPEED
from .reading import UNITS, TooManyChords, _round_chords


__all__ = ["GCODE_SUFFIXES", "S_MAX", "S_MAX_RANGE"]


#: The file names read as G-code (LightBurn writes .gc, .gcode and .nc; LaserGRBL .nc).
GCODE_SUFFIXES = (".gcode", ".gco", ".gc", ".nc", ".ngc")
#: The S value that is full power when none is given: GRBL's ``$30`` (its maximum spindle
#: speed, in laser mode the PWM's full scale) by default.
S_MAX = 1000.0
#: The S maxima ``--s-max`` takes: Marlin's and Inkscape's J Tech extension's 255, GRBL's
#: 1000, Smoothieware's 1, a $30 set to 10000 or more.
S_MAX_RANGE = (1e-3, 1e6)

#: One word: a letter and a number as GRBL reads it (no exponent).
_WORD = re.compile(r"([A-Z])([+-]?(?:\d+\.?\d*|\.\d+))")
#: No number in a laser's G-code is larger (10^9 mm is a million km; N line numbers fit).
_LARGEST = 1e9
#: A line's checksum (RepRap's, as hosts add it): ``*`` and a number at the end.
_CHECKSUM = re.compile(r"\*\s*(\d+)\s*$")
#: GRBL's arc checks (its ``mc_arc`` and ``gc_execute_line``): a centre whose distance from the
#: end differs from its distance from the start by more than this (mm), and this share of it,
#: is an error; a sweep within this of nothing is a whole turn.
_ARC_RADIUS_SLACK_MM = 0.005
_ARC_RADIUS_SLACK_SHARE = 0.001
_ARC_ANGULAR_EPSILON = 5e-7

#: G words that change nothing here: the XY plane, no cutter compensation, the first work
#: coordinate system, feed in units a minute (every one GRBL's default).
_HARMLESS_G = {17.0, 40.0, 54.0, 94.0}
#: What is counted as left out, by the word: ``(one, many)``.
_LEFT_OUT = {
    "G4": ("G4 dwell left out (a galvo marks no dwell from G-code)",
           "G4 dwells left out (a galvo marks no dwell from G-code)"),
    "G28": ("G28/G30 homing move left out (not a move on a galvo)",
            "G28/G30 homing moves left out (not a move on a galvo)"),
    "M0": ("M0/M1 pause left out", "M0/M1 pauses left out"),
    "M7": ("M7/M8/M9 air assist command left out", "M7/M8/M9 air assist commands left out"),
    "T": ("tool change word (T, M6) left out", "tool change words (T, M6) left out"),
    "Z": ("Z word left out (a galvo has no Z)", "Z words left out (a galvo has no Z)"),
}
#: The M codes left out, and what each is counted as (:data:`_LEFT_OUT`'s key).
_LEFT_OUT_M = {"M0": "M0", "M1": "M0", "M6": "T", "M7": "M7", "M8": "M7", "M9": "M7"}
#: The letters of lengths: the axes and an arc's centre and radius.
_AXES = ("X", "Y", "Z", "I", "J", "K", "R")
#: The letters a line may hold: each once, but G and M once a code.
_KNOWN = set("GMNSFPT") | set(_AXES)


class _LineError(DrawingError):
    """A fault on one line: the reader adds its number and text."""


def _decoded(data):
    """The file as text: UTF-8, else Latin-1 (comments in a Windows program's code page); a
    file with NUL bytes is not G-code."""
    if b"\x00" in data:
        raise DrawingError("not a G-code text file (it holds NUL bytes)")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def _code_part(line):
    """The line with its comments taken out, and its checksum, if it has one, checked and
    taken out."""
    code, _, _ = line.partition(";")
    out, depth = [], 0
    for char in code:
        if char == "(":
            if depth:
                raise _LineError("a comment opened inside a comment")
            depth = 1
        elif char == ")":
            if not depth:
                raise _LineError("')' with no '(' before it")
            depth = 0
        elif not depth:
            out.append(char)
    if depth:
        raise _LineError("a comment '(' not closed on its line")
    code = "".join(out)
    match = _CHECKSUM.search(code)
    if match:
        body = code[:match.start()]
        expected = 0
        for char in body.encode("latin-1", "replace"):
            expected ^= char
        if int(match.group(1)) != expected:
            raise _LineError(f"checksum *{match.group(1)} does not match the line's "
                             f"({expected}): the line is damaged")
        code = body
    return code


def _words(code):
    """The line's words, ``[(letter, value)]``; a line that is not only words refused."""
    text = re.sub(r"[ \t\r]", "", code)
    if not text.isascii():
        # (Before upper(): "ſ".upper() is "S".)
        odd = next(char for char in text if not char.isascii())
        raise _LineError(f"{odd!r} is not a character of G-code's words")
    text = text.upper()
    if not text or text == "%":
        return []
    words, at = [], 0
    for match in _WORD.finditer(text):
        if match.start() != at:
            break
        value = float(match.group(2))
        if not abs(value) <= _LARGEST:
            raise _LineError(f"{match.group(0)[:16]}: a number beyond any machine's")
        words.append((match.group(1), value))
        at = match.end()
    if at != len(text):
        rest = text[at:at + 12]
        raise _LineError(f"{rest!r} is not a G-code word (a letter and a number)")
    return words


def _code(value):
    """A G or M number as written: ``G1``, ``G90.1``."""
    return f"{value:g}"


class _Reader:
    """The machine's state as the file runs, and the polylines it marks."""

    def __init__(self, tolerance_mm, units_asked, s_max):
        self.tolerance = tolerance_mm
        self.forced = UNITS[units_asked][0] if units_asked is not None else None
        self.s_max = s_max
        self.mm = 1.0                       # mm a unit: G21
        self.inches_seen = self.mm_seen = False
        self.relative = False               # G91
        self.ij_absolute = False            # G90.1
        self.motion = 0                     # G0 (GRBL's state at power-up)
        self.on = False                     # M3/M4
        self.s = 0.0
        self.f_mm_min = None
        self.at = np.zeros(2)
        self.path, self.key = None, None    # the polyline being marked and its layer
        self.paths, self.styles = [], []
        self.layers = {}                    # name → FileLayer, in the order the file uses them
        self.left_out = Counter()
        self.number = 0                     # the line being read

    # --- the state ---------------------------------------------------------------------------

    @property
    def unit_mm(self):
        return self.forced if self.forced is not None else self.mm

    def _end_path(self):
        if self.path is not None and len(self.path) >= 2:
            self.paths.append(np.array(self.path))
            self.styles.append(PathStyle(layer=self.key))
        self.path, self.key = None, None

    def _layer(self):
        """The name of the layer a mark now is on (its S and F), the layer made when it is
        new."""
        if self.f_mm_min is None:
            raise _LineError("a mark with no feed rate (F) given yet")
        if self.s > self.s_max:
            raise _LineError(f"S{self.s:g} is more than the S maximum {self.s_max:g} "
                             f"(GRBL's $30; give the file's with --s-max)")
        # The layer's name is its key: an S and F that print alike (to 6 figures) are one.
        key = f"S{self.s:g} F{self.f_mm_min:g}"
        if key not in self.layers:
            speed = self.f_mm_min / 60
            if not SPEED.low <= speed <= SPEED.high:
                raise _LineError(f"F{self.f_mm_min:g} mm/min is {speed:g} mm/s: galvoscan "
                                 f"marks at {SPEED.low:g} to {SPEED.high:g} mm/s")
            self.layers[key] = FileLayer(key, speed, 100.0 * self.s / self.s_max)
        return key

    def _move_to(self, points, marks):
        """Along ``points`` (the move's, its end last): a mark at the layer of now, or a
        jump."""
        if marks:
            key = self._layer()
            if self.path is None or key != self.key:
                self._end_path()
                self.path, self.key = [self.at.copy()], key
            self.path.extend(points)
        elif not np.array_equal(points[-1], self.at):
            self._end_path()
        self.at = np.array(points[-1], dtype=float)

    # --- a line ------------------------------------------------------------------------------

    def line(self, text):
        words = _words(_code_part(text))
        if not words:
            return
        given, gs, ms = {}, [], []
        for letter, value in words:
            if letter not in _KNOWN:
                raise _LineError(f"{letter}{value:g}: not a word a laser's G-code holds here")
            if letter == "G":
                gs.append(value)
            elif letter == "M":
                ms.append(value)
            elif letter in given:
                raise _LineError(f"{letter} given twice")
            else:
                given[letter] = value
        if len(set(gs)) != len(gs) or len(set(ms)) != len(ms):
            raise _LineError("a G or M code given twice")
        if "K" in given:
            raise _LineError("K: an arc in the XY plane has I and J, not K")
        # As GRBL takes a line: its units and modes first (its F and lengths are in the
        # line's units), then the feed, the power, the laser on or off, and the move last.
        motion, dwell, homing = None, False, False
        for g in gs:
            if g in (0.0, 1.0, 2.0, 3.0):
                if motion is not None:
                    raise _LineError("two moves (G0…G3) on one line")
                motion = int(g)
            elif g == 4.0:
                dwell = True
            elif g in (20.0, 21.0):
                self.mm = 25.4 if g == 20.0 else 1.0
                self.inches_seen |= g == 20.0
                self.mm_seen |= g == 21.0
            elif g in (90.0, 91.0):
                self.relative = g == 91.0
            elif g in (90.1, 91.1):
                self.ij_absolute = g == 90.1
            elif g in (28.0, 30.0):
                self.left_out["G28"] += 1
                homing = True
            elif g not in _HARMLESS_G:
                raise _LineError(f"G{_code(g)}: not a G code galvoscan reads (G0–G4, G17, "
                                 f"G20, G21, G28, G30, G40, G54, G90, G91, G90.1, G91.1, G94)")
        if dwell:
            self.left_out["G4"] += 1
            if motion is not None or any(axis in given for axis in _AXES):
                raise _LineError("a dwell (G4) and a move on one line")
            given.pop("P", None)
        if "P" in given:
            raise _LineError("P without a dwell (G4)")
        if "F" in given:
            if not given["F"] > 0:
                raise _LineError(f"F{given['F']:g}: a feed rate is more than 0")
            self.f_mm_min = given["F"] * self.unit_mm
        if "S" in given:
            if given["S"] < 0:
                raise _LineError(f"S{given['S']:g}: a power is 0 or more")
            self.s = given["S"]
        for m in ms:
            if m in (3.0, 4.0):
                self.on = True
            elif m == 5.0:
                self.on = False
            elif m in (2.0, 30.0):          # program end: GRBL's reset of the modes
                self.on, self.relative, self.motion = False, False, 1
            elif f"M{_code(m)}" in _LEFT_OUT_M:
                self.left_out[_LEFT_OUT_M[f"M{_code(m)}"]] += 1
            else:
                raise _LineError(f"M{_code(m)}: not an M code galvoscan reads (M2–M5, M30; "
                                 f"M0, M1, M6–M9 left out)")
        if "T" in given:
            self.left_out["T"] += 1
        if "Z" in given:
            self.left_out["Z"] += 1
        if motion is not None:
            self.motion = motion
        if homing:
            if motion is not None:
                raise _LineError("a homing move (G28, G30) and another move on one line")
            return                          # (its X Y are a point on the way home: no mark)
        if not any(axis in given for axis in ("X", "Y", "I", "J", "R")):
            if motion in (2, 3):
                raise _LineError(f"G{motion} with no end point, centre or radius")
            return
        self._motion(given)

    def _motion(self, given):
        unit = self.unit_mm
        target = self.at.copy()
        for axis, k in (("X", 0), ("Y", 1)):
            if axis in given:
                target[k] = (target[k] if self.relative else 0.0) + given[axis] * unit
        marks = self.on and self.s > 0 and self.motion != 0
        if self.motion in (0, 1):
            if any(word in given for word in ("I", "J", "R")):
                raise _LineError(f"{'/'.join(w for w in 'IJR' if w in given)} on a "
                                 f"G{self.motion} move (arcs are G2 and G3)")
            self._move_to([target], marks)
            return
        points = self._arc(target, given, unit, clockwise=self.motion == 2, flatten=marks)
        self._move_to(points, marks)

    def _arc(self, end, given, unit, clockwise, flatten):
        """The arc's points after its start, its end last (GRBL's ``gc_execute_line`` and
        ``mc_arc`` as to what an arc is and what is an error); not ``flatten``: its end
        only (a jump)."""
        start = self.at
        if "R" in given:
            if "I" in given or "J" in given:
                raise _LineError("an arc with both R and I/J")
            radius = given["R"] * unit
            d = end - start
            if not np.any(d):
                raise _LineError("an R arc ending where it starts (a whole circle needs I, J)")
            h_x2_div_d = 4.0 * radius * radius - d @ d
            if h_x2_div_d < 0:
                raise _LineError(f"R{given['R']:g}: shorter than half the way to the end")
            h = -math.sqrt(h_x2_div_d) / math.hypot(*d)
            if not clockwise:
                h = -h
            if radius < 0:
                h, radius = -h, -radius
            centre = start + 0.5 * np.array([d[0] - d[1] * h, d[1] + d[0] * h])
        else:
            offset = np.array([given.get("I", 0.0), given.get("J", 0.0)]) * unit
            centre = offset if self.ij_absolute else start + offset
            radius = math.hypot(*(start - centre))
            delta = abs(math.hypot(*(end - centre)) - radius)
            if delta > _ARC_RADIUS_SLACK_MM and (delta > 0.5 or
                                                 delta > _ARC_RADIUS_SLACK_SHARE * radius):
                raise _LineError(f"the arc's end is {delta:.4g} mm off its circle (its centre's "
                                 f"I J do not fit its start and end)")
            if radius == 0:
                raise _LineError("an arc of radius 0 (I and J both 0)")
        if not flatten:
            return [end]
        r0, r1 = start - centre, end - centre
        sweep = math.atan2(r0[0] * r1[1] - r0[1] * r1[0], r0 @ r1)
        if clockwise and sweep >= -_ARC_ANGULAR_EPSILON:
            sweep -= 2 * math.pi
        elif not clockwise and sweep <= _ARC_ANGULAR_EPSILON:
            sweep += 2 * math.pi
        try:
            n = _round_chords(radius, sweep, self.tolerance)
        except TooManyChords:
            raise TooManyChords(f"the arc on line {self.number}", (2 * radius, 2 * radius),
                                self.units_said()) from None
        t = math.atan2(r0[1], r0[0]) + sweep * np.arange(1, n + 1) / n
        points = centre + radius * np.column_stack([np.cos(t), np.sin(t)])
        points[-1] = end
        return list(points)

    def units_said(self):
        if self.forced is not None:
            return "--units", self.forced
        if self.inches_seen:
            return f"G20: inches{' and G21: mm' if self.mm_seen else ''}", 25.4
        return ("G21: mm" if self.mm_seen else "no G20 or G21: mm, as GRBL starts"), 1.0

    def left_out_said(self):
        return [f"{n} {_LEFT_OUT[what][n > 1]}" for what, n in sorted(self.left_out.items())]


def _read_gcode(data, tolerance_mm, units_asked=None, s_max=None):
    """``(polylines in mm, closed flags, skipped, notes, styles, (what the units were taken
    from, mm a unit), layers)``: ``layers`` the file's (:class:`~galvoscan.geometry.drawing.
    FileLayer`), one for each distinct S and F it marks with, in the order it first does.
    ``units_asked``: the unit every number is in, in place of G20 and G21; ``s_max``: the S
    that is full power (None: :data:`S_MAX`)."""
    s_max = S_MAX if s_max is None else s_max
    if not S_MAX_RANGE[0] <= s_max <= S_MAX_RANGE[1]:
        raise DrawingError(f"the S maximum must be from {S_MAX_RANGE[0]:g} to "
                           f"{S_MAX_RANGE[1]:g}, not {s_max:g}")
    reader = _Reader(tolerance_mm, units_asked, s_max)
    # (Lines end at \n, \r\n or \r, as senders split them; not at str.splitlines()'s form
    # feeds and separators, which would shift the line numbers a refusal names.)
    for number, text in enumerate(re.split(r"\r\n|\r|\n", _decoded(data)), 1):
        reader.number = number
        try:
            reader.line(text)
        except _LineError as error:
            shown = " ".join(text.split())
            shown = shown if len(shown) <= 40 else shown[:37] + "..."
            raise DrawingError(f"line {number} ({shown!r}): {error}") from None
    reader._end_path()
    default = " (GRBL's $30 by default; --s-max gives the file's)" if s_max == S_MAX else ""
    notes = [f"power: S as a share of S{s_max:g}, full power{default}"]
    if units_asked is not None:
        notes.append(f"G-code numbers taken as {UNITS[units_asked][1]} (--units {units_asked}),"
                     f" not as its G20 and G21 say")
    used = {style.layer for style in reader.styles}
    layers = tuple(layer for layer in reader.layers.values() if layer.name in used)
    return (reader.paths, [False] * len(reader.paths), reader.left_out_said(), notes,
            reader.styles, reader.units_said(), layers)
