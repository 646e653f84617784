"""2-D and bar codes to mark: QR, DataMatrix and Code 128, their modules made by zxing-cpp (a
maintained encoder, whose decoder the tests read the marks back with), as a drawing in mm.

A code is ``size_mm`` wide, its modules square (Code 128's bars ``height_mm`` tall), and its
quiet zone (``quiet_modules`` each side: the symbologies' own minimum by default, 4 for QR,
1 for DataMatrix, 10 for Code 128) is kept clear: a code placed beside other objects is
refused if they reach into it. The dark modules are marked either filled (their outline and a
hatch along the rows, the modules of a row joined into one shape) or as dots, a zero-length
mark at each module's centre (a dot-peen look, for a spot about a module wide).
"""

import enum
import math
from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import box
import zxingcpp

from ..geometry.drawing import Drawing
from ..geometry.field import PlanError


__all__ = ["CodeKind", "CodeFill", "CodeSpec", "code_modules", "code_drawing", "data_said"]


class CodeKind(enum.Enum):
    """The symbologies ``--code`` makes."""
    QR = "qr"
    DATAMATRIX = "datamatrix"
    CODE128 = "code128"


class CodeFill(enum.Enum):
    """How the dark modules are marked."""
    HATCH = "hatch"
    DOTS = "dots"


#: The quiet zone each symbology asks for, in modules (ISO/IEC 18004, 16022, 15417).
QUIET_MODULES = {CodeKind.QR: 4, CodeKind.DATAMATRIX: 1, CodeKind.CODE128: 10}
#: QR's error-correction levels (the share of the symbol that may be lost: 7 … 30 %).
QR_LEVELS = ("L", "M", "Q", "H")
#: A code's data is shown whole up to this many characters, else cut with an ellipsis: a
#: URL cut without one reads as the whole URL, and the user takes the code for a wrong one.
DATA_SHOWN = 40


def data_said(data):
    """``data`` quoted as the notes, refusals and the preview's title show it: whole, or its
    first :data:`DATA_SHOWN` characters and "…" inside the quotes."""
    return repr(data if len(data) <= DATA_SHOWN else data[:DATA_SHOWN - 1] + "…")


@dataclass(frozen=True)
class CodeSpec:
    """A code to mark: what, how big, how filled."""
    kind: CodeKind
    data: str
    size_mm: float
    ec_level: str = None            # QR only: L, M, Q or H (default M)
    fill: CodeFill = CodeFill.HATCH
    quiet_modules: int = None       # None: the symbology's
    height_mm: float = None         # Code 128's bars (default: a quarter of its width)

    def __post_init__(self):
        object.__setattr__(self, "kind", CodeKind(self.kind))
        object.__setattr__(self, "fill", CodeFill(self.fill))
        if not self.data:
            raise PlanError("a code needs data (--data TEXT)")
        if not (math.isfinite(self.size_mm) and 0.5 <= self.size_mm <= 500):
            raise PlanError(f"code size {self.size_mm} mm: must be from 0.5 to 500")
        if self.ec_level is not None:
            if self.kind is not CodeKind.QR:
                raise PlanError(f"an error-correction level is QR's; {self.kind.value} sets "
                                f"its own")
            if self.ec_level not in QR_LEVELS:
                raise PlanError(f"QR error correction {self.ec_level!r}: one of "
                                f"{', '.join(QR_LEVELS)}")
        if self.quiet_modules is not None and not 0 <= self.quiet_modules <= 100:
            raise PlanError(f"quiet zone {self.quiet_modules} modules: must be from 0 to 100")
        if self.height_mm is not None and not (math.isfinite(self.height_mm) and
                                               0.5 <= self.height_mm <= 500):
            raise PlanError(f"bar height {self.height_mm} mm: must be from 0.5 to 500")

    @property
    def quiet(self):
        return QUIET_MODULES[self.kind] if self.quiet_modules is None else self.quiet_modules


def code_modules(spec):
    """The symbol's modules, ``True`` dark, row 0 at the top: ``(rows, columns)`` (Code 128:
    one row, a column a module). One line for data the symbology cannot encode."""
    formats = {CodeKind.QR: zxingcpp.BarcodeFormat.QRCode,
               CodeKind.DATAMATRIX: zxingcpp.BarcodeFormat.DataMatrix,
               CodeKind.CODE128: zxingcpp.BarcodeFormat.Code128}
    options = {"ec_level": spec.ec_level or "M"} if spec.kind is CodeKind.QR else {}
    try:
        symbol = zxingcpp.create_barcode(spec.data, formats[spec.kind], **options)
        image = np.asarray(symbol.to_image(scale=1, add_quiet_zones=False))
    except (ValueError, RuntimeError) as error:
        raise PlanError(f"{spec.kind.value} cannot hold {data_said(spec.data)}: "
                        f"{' '.join(str(error).split()) or type(error).__name__}") from None
    dark = image < 128
    return dark[:1] if spec.kind is CodeKind.CODE128 else dark


def code_drawing(spec):
    """The code as a :class:`~galvoscan.geometry.drawing.Drawing` in mm (Y up, its lower-left
    corner at 0,0, its quiet zone outside that), and its module size, mm."""
    dark = code_modules(spec)
    rows, columns = dark.shape
    module = spec.size_mm / columns
    height = spec.height_mm or spec.size_mm / 4 if spec.kind is CodeKind.CODE128 else None
    row_mm = height if height else module
    paths, closed, boxes = [], [], []
    for r in range(rows):
        top = (rows - r) * row_mm                 # row 0 at the top, Y up
        line = np.concatenate([[False], dark[r], [False]])
        edges = np.flatnonzero(line[1:] != line[:-1])
        for start, end in zip(edges[0::2], edges[1::2]):     # a run of dark modules
            if spec.fill is CodeFill.DOTS:
                for c in range(start, end):
                    centre = ((c + 0.5) * module, top - row_mm / 2)
                    if height:                   # a bar: a column of dots
                        for k in range(max(1, round(height / module))):
                            y = top - (k + 0.5) * height / max(1, round(height / module))
                            paths.append(np.array([(centre[0], y)] * 2))
                            closed.append(False)
                    else:
                        paths.append(np.array([centre, centre]))
                        closed.append(False)
                continue
            boxes.append((start * module, top - row_mm, end * module, top))
    if boxes:
        # The dark modules as one area (touching modules merged): its edges are the outline,
        # its holes the light modules inside it.
        area = shapely.unary_union([box(*b) for b in boxes])
        for polygon in getattr(area, "geoms", [area]):
            for ring in [polygon.exterior, *polygon.interiors]:
                paths.append(np.asarray(ring.coords, dtype=float))
                closed.append(True)
    for path in paths:
        path.flags.writeable = False
    quiet = spec.quiet * module
    name = f"{spec.kind.value} code {data_said(spec.data)}"
    notes = (f"{name}: {columns} × {rows if not height else 1} modules of "
             f"{module * 1000:.0f} µm, {spec.size_mm:g} mm wide; keep {quiet:.2f} mm clear "
             f"around it (its quiet zone, {spec.quiet} module{'' if spec.quiet == 1 else 's'})",)
    return Drawing(name=name, paths=tuple(paths), closed=tuple(closed), notes=notes), module
