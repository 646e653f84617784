"""Text to mark, as a drawing in mm: TrueType and OpenType outlines (matplotlib's font
machinery, DejaVu Sans by default), filled by hatch; or the public-domain Hershey single-line
fonts (the Hershey-Fonts package), strokes marked once each, for fast marking.

The height is a capital letter's (an "H": its cap height), in mm; lines go down by
``line_spacing`` times that from the first line's baseline (y = 0); ``align`` puts each line's
marks' left end, centre or right end at x = 0; ``letter_spacing_mm`` is added between letters (the
font's own kerning kept where it is 0). Curves of the outlines are flattened to
``tolerance_mm``, as a drawing's are.
"""

import logging
import math
import os
from dataclasses import dataclass
from pathlib import Path

from HersheyFonts import HersheyFonts
import numpy as np

from ..geometry.drawing import Drawing
from ..geometry.field import PlanError


__all__ = ["TextSpec", "text_drawing", "HERSHEY_PREFIX", "ALIGNMENTS"]


#: ``--font hershey:NAME`` picks a Hershey single-line font (``hershey`` alone: futural).
HERSHEY_PREFIX = "hershey"
ALIGNMENTS = ("left", "centre", "right")
#: Characters a text may hold at most (a serial plate, not a book).
MAX_CHARACTERS = 2000


@dataclass(frozen=True)
class TextSpec:
    """Text to mark, and how it is set."""
    text: str
    height_mm: float
    font: str = None                # a family name, a .ttf/.otf file, or hershey[:NAME]
    align: str = "left"
    letter_spacing_mm: float = 0.0
    line_spacing: float = 1.4

    def __post_init__(self):
        if not self.text.strip():
            raise PlanError("the text is empty")
        if len(self.text) > MAX_CHARACTERS:
            raise PlanError(f"a text of {len(self.text):,} characters: {MAX_CHARACTERS:,} at "
                            f"most")
        if not (math.isfinite(self.height_mm) and 0.1 <= self.height_mm <= 500):
            raise PlanError(f"text height {self.height_mm} mm: must be from 0.1 to 500")
        align = {"center": "centre"}.get(self.align, self.align)
        if align not in ALIGNMENTS:
            raise PlanError(f"text alignment {self.align!r}: left, centre or right")
        object.__setattr__(self, "align", align)
        if not (math.isfinite(self.letter_spacing_mm) and
                -self.height_mm <= self.letter_spacing_mm <= 10 * self.height_mm):
            raise PlanError(f"letter spacing {self.letter_spacing_mm} mm: must be from "
                            f"-{self.height_mm:g} to {10 * self.height_mm:g} (the height's)")
        if not (math.isfinite(self.line_spacing) and 0.5 <= self.line_spacing <= 10):
            raise PlanError(f"line spacing {self.line_spacing}: must be from 0.5 to 10 "
                            f"(times the height)")

    @property
    def hershey(self):
        """The Hershey font's name, or None for an outline font."""
        font = self.font or ""
        if font == HERSHEY_PREFIX:
            return "futural"
        return font.split(":", 1)[1] if font.startswith(HERSHEY_PREFIX + ":") else None


def text_drawing(spec, *, tolerance_mm=0.01):
    """The text as a :class:`~galvoscan.geometry.drawing.Drawing` in mm, Y up: closed outlines (an
    outline font) or open strokes (Hershey). One line
    (:class:`~galvoscan.geometry.field.PlanError`) for a font that cannot be found or read."""
    lines = spec.text.split("\n")
    if spec.hershey:
        pieces = [_hershey_line(line, spec) for line in lines]
        closed_default = False
        font = f"Hershey {spec.hershey}"
    else:
        prop = _font(spec.font)
        pieces = [_outline_line(line, spec, prop, tolerance_mm) for line in lines]
        closed_default = True
        font = Path(prop.get_file()).name
    paths, closed = [], []
    for number, line_paths in enumerate(pieces):
        # Aligned by the ink: the line's marks start, are centred or end at x = 0.
        if line_paths:
            xs = np.concatenate([p[:, 0] for p in line_paths])
            low, high = xs.min(), xs.max()
        else:
            low = high = 0.0
        shift = {"left": -low, "centre": -(low + high) / 2, "right": -high}[spec.align]
        down = number * spec.line_spacing * spec.height_mm
        for path in line_paths:
            moved = path + (shift, -down)
            moved.flags.writeable = False
            paths.append(moved)
            closed.append(closed_default and len(path) > 3 and
                          bool(np.array_equal(path[0], path[-1])))
    if not paths:
        raise PlanError(f"the text {spec.text[:30]!r} has nothing to mark in this font")
    name = f"text {spec.text[:20]!r}"
    return Drawing(name=name, paths=tuple(paths), closed=tuple(closed),
                   notes=(f"{name}: {font}, {spec.height_mm:g} mm capitals",))


# --- outline fonts --------------------------------------------------------------------------

def _font(font):
    """matplotlib's FontProperties of a family name or a font file, by its file (the family's
    found here, once); one line if missing."""
    # Here: matplotlib's fonts take 0.6 s to import; the CLI's parser imports this module.
    from matplotlib.font_manager import FontProperties
    if font and (os.sep in font or font.lower().endswith((".ttf", ".otf", ".ttc")) or
                 Path(font).is_file()):
        if not Path(font).is_file():
            raise PlanError(f"font file {font}: not found")
        # Here: matplotlib's fonts take 0.6 s to import; the CLI's parser imports this module.
        from matplotlib.font_manager import get_font
        try:
            get_font(font)
        except (RuntimeError, OSError, ValueError):
            raise PlanError(f"font file {font}: not a font (TrueType or OpenType) that can "
                            f"be read") from None
        return FontProperties(fname=font)
    family = font or "DejaVu Sans"
    found = _installed(family)
    if found is None:
        raise PlanError(f"font {family!r} is not installed (give a .ttf/.otf file, or "
                        f"hershey for a single-line font)")
    return FontProperties(fname=found)


def _installed(family, weight="normal", style="normal"):
    """The file of an installed font of ``family`` (its face of that weight and style, as
    matplotlib finds it), or None: no other family's in its place."""
    # Here: matplotlib's fonts take 0.6 s to import; the CLI's parser imports this module.
    from matplotlib.font_manager import FontProperties, findfont
    logger = logging.getLogger("matplotlib.font_manager")
    level, logger.level = logger.level, logging.ERROR   # (its "not found" warning)
    try:
        return findfont(FontProperties(family=family, weight=weight, style=style),
                        fallback_to_default=False)
    except ValueError:
        return None
    finally:
        logger.level = level


def missing_characters(text, font_file):
    """The characters of ``text`` (spaces aside) that the font file has no glyph for."""
    # Here: matplotlib's fonts take 0.6 s to import; the CLI's parser imports this module.
    from matplotlib.font_manager import get_font
    face = get_font(font_file)
    return "".join(dict.fromkeys(ch for ch in text if not ch.isspace() and
                                 face.get_char_index(ord(ch)) == 0))


def _outline_line(line, spec, font, tolerance_mm):
    """One line's glyph outlines, baseline at y = 0, from x = 0."""
    # Here: matplotlib's fonts take 0.6 s to import; the CLI's parser imports this module.
    from matplotlib.textpath import TextPath
    missing = missing_characters(line, font.get_file())
    if missing:
        raise PlanError(f"{missing!r} {'is' if len(missing) == 1 else 'are'} not in "
                        f"{Path(font.get_file()).name}: give a font that has "
                        f"{'it' if len(missing) == 1 else 'them'} (--font)")
    prop = font.copy()
    prop.set_size(100)              # laid out at 100 units an em, scaled to the cap height
    try:
        cap = TextPath((0, 0), "H", prop=prop).get_extents().height
        scale = spec.height_mm / cap
        if spec.letter_spacing_mm == 0:
            pieces = [(0.0, line)]          # the font's own layout, kerning and all
        else:
            # Letter by letter: each at the font's advances and kerning so far (as its layout
            # puts them), plus the spacing asked.
            # Here: matplotlib's fonts take 0.6 s to import; the CLI's parser imports this module.
            from matplotlib.font_manager import get_font
            from matplotlib.ft2font import Kerning
            face = get_font(font.get_file())
            face.set_size(100, 72)
            pieces, x, before = [], 0.0, None
            for i, ch in enumerate(line):
                index = face.get_char_index(ord(ch))
                if before is not None:
                    x += face.get_kerning(before, index, Kerning.DEFAULT) / 64
                pieces.append((x + i * spec.letter_spacing_mm / scale, ch))
                x += face.load_char(ord(ch)).linearHoriAdvance / 65536
                before = index
        paths = []
        for x, piece in pieces:
            if piece.strip():
                path = TextPath((x, 0), piece, prop=prop)
                paths += _flattened(path, scale, tolerance_mm)
    except (RuntimeError, ValueError, OSError) as error:
        raise PlanError(f"font {font.get_file()}: cannot be read "
                        f"({' '.join(str(error).split())})") from None
    return paths


def _flattened(path, scale, tolerance_mm):
    """A matplotlib path's contours as polylines in mm: each quadratic and cubic piece in
    enough equal steps that the chords stay within the tolerance (``h²/8 · max |B''|``)."""
    # Here: matplotlib's fonts take 0.6 s to import; the CLI's parser imports this module.
    from matplotlib.path import Path as MPath
    contours, current = [], []
    vertices = np.asarray(path.vertices, dtype=float) * scale
    codes = path.codes
    i = 0
    while i < len(codes):
        code = codes[i]
        if code == MPath.MOVETO:
            if len(current) > 1:
                contours.append(np.array(current))
            current = [vertices[i]]
            i += 1
        elif code == MPath.LINETO:
            current.append(vertices[i])
            i += 1
        elif code in (MPath.CURVE3, MPath.CURVE4):
            degree = 2 if code == MPath.CURVE3 else 3
            p = np.vstack([current[-1], vertices[i:i + degree]])
            second = np.max(np.hypot(*(p[:-2] - 2 * p[1:-1] + p[2:]).T)) * degree * (degree - 1)
            n = max(1, math.ceil(math.sqrt(second / (8 * tolerance_mm))))
            t = (np.arange(1, n + 1) / n)[:, None]
            if degree == 2:
                points = (1 - t) ** 2 * p[0] + 2 * (1 - t) * t * p[1] + t ** 2 * p[2]
            else:
                points = ((1 - t) ** 3 * p[0] + 3 * (1 - t) ** 2 * t * p[1] +
                          3 * (1 - t) * t ** 2 * p[2] + t ** 3 * p[3])
            current += list(points)
            i += degree
        else:                                       # CLOSEPOLY
            if current:
                current.append(current[0])
                if len(current) > 2:
                    contours.append(np.array(current))
            current = []
            i += 1
    if len(current) > 1:
        contours.append(np.array(current))
    return contours


# --- Hershey single-line fonts ----------------------------------------------------------------

def _hershey_line(line, spec):
    """One line's strokes in a Hershey font, baseline at y = 0, from x = 0."""
    font = HersheyFonts()
    if spec.hershey not in font.default_font_names:
        raise PlanError(f"Hershey font {spec.hershey!r}: one of "
                        f"{', '.join(font.default_font_names[:12])}, …")
    font.load_default_font(spec.hershey)
    missing = "".join(dict.fromkeys(ch for ch in line if ch not in font.all_glyphs))
    if missing:
        raise PlanError(f"{missing!r} {'is' if len(missing) == 1 else 'are'} not in the "
                        f"Hershey font {spec.hershey} (it has the printable ASCII "
                        f"characters): give an outline font (--font)")
    font.normalize_rendering(100)
    cap = [np.array(s, dtype=float) for s in font.strokes_for_text("H")]
    cap_points = np.concatenate(cap)
    scale = spec.height_mm / np.ptp(cap_points[:, 1])
    base = cap_points[:, 1].min()
    strokes, x = [], 0.0
    chars = [line] if spec.letter_spacing_mm == 0 else list(line)
    for piece in chars:
        piece_strokes = [np.array(s, dtype=float) for s in font.strokes_for_text(piece)]
        for s in piece_strokes:
            if len(s) >= 2:
                strokes.append(np.column_stack([(s[:, 0]) * scale + x,
                                                (s[:, 1] - base) * scale]))
        # The advance: the glyphs' own (the font's widths), then the spacing asked.
        x += _hershey_width(font, piece) * scale + spec.letter_spacing_mm
    return strokes


def _hershey_width(font, text):
    """The advance of ``text`` in the loaded Hershey font (its glyphs' widths), in rendering
    units."""
    return sum(glyph.char_width for glyph in font.glyphs_for_text(text)) * \
        abs(font.render_options["scalex"])
