"""Photos to engrave: a PNG or JPEG (read by Pillow) as scan lines, each run of dark pixels of a
line one mark.

The picture is scaled to ``width_mm`` (its height by its own aspect) on a grid of square cells
``line_spacing_mm`` wide, made grey, and dithered to dark and light cells:

- ``floyd``: Floyd–Steinberg error diffusion (Pillow's, as its ``convert("1")`` makes it);
- ``ordered``: an 8 × 8 Bayer threshold map, the dots in a regular screen;
- ``threshold``: dark below mid-grey, no dithering (line art, logos).

A run of dark cells is marked from its first cell's centre to its last's (one cell: a dot), so
with the spacing the spot's width the marks cover the run's cells and no more. Lines run one
after the other from the top, each the other way from the last (bidirectional), or all left to
right (``bidirectional=False``); their order is kept, not re-planned. A transparent pixel is
light (not marked).
"""

import math
from dataclasses import dataclass
from enum import Enum
from pathlib import Path

import numpy as np
from PIL import Image, ImageOps, UnidentifiedImageError

from ..geometry.drawing import Drawing, DrawingError
from ..geometry.field import PlanError


__all__ = ["Dither", "PhotoSpec", "photo_bitmap", "photo_drawing", 
           "MAX_CELLS", "MAX_PIXELS"]

#: Cells of the dithered grid at most: 4 million (a 100 mm square at 0.05 mm), some 2 million
#: marks at worst, hours of marking; more is a size or spacing mistake.
MAX_CELLS = 4_000_000
#: Pixels of the file at most (a 50-megapixel camera's), checked before it is decoded.
MAX_PIXELS = 60_000_000



class Dither(Enum):
    """How grey becomes dark and light cells."""
    FLOYD = "floyd"
    ORDERED = "ordered"
    THRESHOLD = "threshold"


@dataclass(frozen=True)
class PhotoSpec:
    """A photo to engrave, and how."""
    path: str
    width_mm: float
    line_spacing_mm: float
    dither: Dither = Dither.FLOYD
    bidirectional: bool = True

    def __post_init__(self):
        if not (math.isfinite(self.width_mm) and 0.1 <= self.width_mm <= 1000):
            raise PlanError(f"image width {self.width_mm} mm: must be from 0.1 to 1000")
        if not (math.isfinite(self.line_spacing_mm) and 0.001 <= self.line_spacing_mm <= 10):
            raise PlanError(f"image line spacing {self.line_spacing_mm} mm: must be from "
                            f"0.001 to 10")
        if self.line_spacing_mm > self.width_mm:
            raise PlanError(f"image line spacing {self.line_spacing_mm:g} mm is wider than the "
                            f"image ({self.width_mm:g} mm)")
        object.__setattr__(self, "dither", Dither(self.dither))


def _grey(spec):
    """The file as a grey Pillow image (0 black … 255 white), transparency as white, turned as
    its EXIF orientation says; one line for a file that is missing, unreadable or huge."""
    path = Path(spec.path)
    try:
        with Image.open(path) as image:
            width, height = image.size
            if width * height > MAX_PIXELS:
                raise DrawingError(f"{path}: {width} × {height} pixels, more than "
                                   f"{MAX_PIXELS // 1_000_000} million: scale it down first")
            image.load()
            image = ImageOps.exif_transpose(image)
    except DrawingError:
        raise
    except FileNotFoundError:
        raise DrawingError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise DrawingError(f"{path}: a folder, not an image") from None
    except UnidentifiedImageError:
        raise DrawingError(f"{path}: not an image Pillow reads (PNG, JPEG, …)") from None
    except Image.DecompressionBombError:
        raise DrawingError(f"{path}: more pixels than an image may have (a decompression "
                           f"bomb?)") from None
    except (OSError, ValueError, SyntaxError) as error:     # truncated or damaged data
        raise DrawingError(f"{path}: a damaged image ({' '.join(str(error).split())[:80]})") \
            from None
    if image.mode in ("RGBA", "LA", "PA") or "transparency" in image.info:
        rgba = image.convert("RGBA")
        white = Image.new("RGBA", rgba.size, (255, 255, 255, 255))
        image = Image.alpha_composite(white, rgba)
    return image.convert("L")


#: The 8 × 8 Bayer index matrix (each entry its place in the order the cells darken).
def _bayer(n=8):
    matrix = np.zeros((1, 1), dtype=int)
    while matrix.shape[0] < n:
        matrix = np.block([[4 * matrix, 4 * matrix + 2], [4 * matrix + 3, 4 * matrix + 1]])
    return matrix


def photo_bitmap(spec):
    """The dithered grid: a bool array, ``True`` for a dark cell (marked), row 0 at the top."""
    return _bitmap(spec)[0]


def _bitmap(spec):
    """The dithered grid and the picture's width in pixels."""
    grey = _grey(spec)
    pixels = grey.width
    columns = max(1, round(spec.width_mm / spec.line_spacing_mm))
    rows = max(1, round(columns * grey.height / grey.width))
    if rows * columns > MAX_CELLS:
        raise DrawingError(f"{Path(spec.path).name}: {columns} × {rows} cells at "
                           f"{spec.line_spacing_mm:g} mm, more than {MAX_CELLS:,}: a smaller "
                           f"--width or a wider --line-spacing")
    grey = grey.resize((columns, rows), Image.Resampling.LANCZOS)
    if spec.dither is Dither.FLOYD:
        return np.asarray(grey.convert("1", dither=Image.Dither.FLOYDSTEINBERG)) == 0, pixels
    values = np.asarray(grey, dtype=float)
    if spec.dither is Dither.THRESHOLD:
        return values < 128, pixels
    bayer = _bayer()
    limits = (bayer + 0.5) / bayer.size * 255
    tiled = np.tile(limits, (rows // 8 + 1, columns // 8 + 1))[:rows, :columns]
    return values < tiled, pixels


def photo_drawing(spec):
    """The photo as a :class:`~galvoscan.geometry.drawing.Drawing` of open marks in scan order (its
    lower-left corner at 0,0, Y up), and its grid."""
    dark, pixels = _bitmap(spec)
    rows, columns = dark.shape
    s = spec.line_spacing_mm
    paths = []
    for r in range(rows):
        line = np.concatenate([[False], dark[r], [False]])
        edges = np.flatnonzero(line[1:] != line[:-1])
        y = (rows - r - 0.5) * s
        runs = [np.array([((a + 0.5) * s, y), ((b - 0.5) * s, y)])
                for a, b in zip(edges[0::2], edges[1::2])]
        if spec.bidirectional and r % 2:
            runs = [run[::-1] for run in runs[::-1]]
        paths += runs
    name = Path(spec.path).name
    if not paths:
        raise DrawingError(f"{name}: no dark pixels to mark at {s:g} mm ({spec.dither.value})")
    for path in paths:
        path.flags.writeable = False
    notes = [f"{name}: {columns} × {rows} cells of {s * 1000:.0f} µm ({spec.width_mm:g} × "
             f"{rows * s:.2f} mm), {spec.dither.value} dithered, {int(dark.sum()):,} dark in "
             f"{len(paths):,} marks"]
    if columns > 1.5 * pixels:
        notes.append(f"{name}: {pixels} pixels across made {columns} cells ({columns / pixels:.1f}"
                     f" × enlarged): a picture with more pixels, or a wider --line-spacing, "
                     f"keeps its detail")
    return Drawing(name=name, paths=tuple(paths), closed=(False,) * len(paths),
                   notes=tuple(notes)), dark
