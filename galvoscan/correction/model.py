"""Correction tables from the f-theta model of Liao & Chen 2016, and a synthetic scan head to
test them on.

Galvo units map linearly to mirror angle: a lens field of ``field_mm`` spans 65536 units, so a
unit ``u`` asks for the spot at ``x' = (u - 32768) × field_mm / 65536`` and the mirror at
``φ = x' / 2f``. A node offset of ``2f·Δφ / mm_per_unit`` units adds Liao & Chen's angle
correction Δφ.
"""

import numpy as np

from ..gateware.field.correction_table import OFFSET_MAX, OFFSET_MIN, CorrectionTable
from .ftheta import PAPER_FOCAL_MM, exact_compensation, landing, polynomial_compensation


__all__ = ["FIELD_CENTRE", "ftheta_table", "ScanHeadModel", "synthetic_head"]


#: Galvo position of the lens axis.
FIELD_CENTRE = 32768


def _check_positive(name, value, unit):
    if not isinstance(value, (int, float)) or isinstance(value, bool) or \
            not np.isfinite(value) or value <= 0:
        raise ValueError(f"{name} must be a positive number of {unit}, not {value!r}")


def ftheta_table(nodes=17, *, field_mm, focal_mm=PAPER_FOCAL_MM, k=1.0, method="exact"):
    """A correction table that undoes the f-theta distortion of Liao & Chen 2016.

    Parameters
    ----------
    nodes : int
        Nodes per axis (5, 9, 17, 33 or 65).
    field_mm : float
        Lens field: the width in mm that 65536 galvo units span.
    focal_mm : float
        Focal length of the f-theta lens (Liao & Chen: 300 mm).
    k : float
        Liao & Chen's trim factor for the polynomial (0.9706 … 1.0306; 1 for f = 300 mm). The
        exact formula takes the lens's real focal length instead, so ``k`` must be 1 with it.
    method : str
        ``"exact"`` (Liao & Chen's closed-form compensation) or ``"polynomial"`` (its fitted one).
    """
    _check_positive("field_mm", field_mm, "mm")
    _check_positive("focal_mm", focal_mm, "mm")
    if method not in ("exact", "polynomial"):
        raise ValueError(f"method must be exact or polynomial, not {method!r}")
    if not isinstance(k, (int, float)) or not 0.5 <= k <= 2.0:
        raise ValueError(f"k must be a number near 1 (Liao & Chen 2016: 0.9706 … 1.0306), "
                         f"not {k!r}")
    if method == "exact" and k != 1.0:
        raise ValueError("k trims the polynomial; give the exact formula the real focal length")
    identity = CorrectionTable.identity(nodes)
    mm_per_unit = field_mm / 65536
    grid = (identity.node_positions() - FIELD_CENTRE) * mm_per_unit
    x, y = np.meshgrid(grid, grid)
    if method == "exact":
        dphi_x, dphi_y = exact_compensation(x, y, focal_mm)
    else:
        dphi_x, dphi_y = polynomial_compensation(x, y, k)
    dx = np.round(2 * focal_mm * dphi_x / mm_per_unit)
    dy = np.round(2 * focal_mm * dphi_y / mm_per_unit)
    if not np.all(np.isfinite(dx)) or not np.all(np.isfinite(dy)) or \
            min(dx.min(), dy.min()) < OFFSET_MIN or max(dx.max(), dy.max()) > OFFSET_MAX:
        raise ValueError(f"a {field_mm} mm field on a {focal_mm} mm lens needs offsets beyond "
                         f"±32767 units: the field is too wide for that lens")
    return CorrectionTable(dx.astype(np.int64), dy.astype(np.int64))


class ScanHeadModel:
    """Where a scan head with Liao & Chen's f-theta distortion puts the spot, in galvo units.

    Parameters
    ----------
    field_mm, focal_mm : float
        Lens field (65536 units) and focal length.
    """

    def __init__(self, *, field_mm, focal_mm=PAPER_FOCAL_MM):
        _check_positive("field_mm", field_mm, "mm")
        _check_positive("focal_mm", focal_mm, "mm")
        self.field_mm = float(field_mm)
        self.focal_mm = float(focal_mm)
        self.mm_per_unit = self.field_mm / 65536

    def land(self, x, y):
        """Landed position (float galvo units) of commanded positions ``x``, ``y``."""
        to_angle = self.mm_per_unit / (2 * self.focal_mm)
        phi_x = (np.asarray(x, dtype=float) - FIELD_CENTRE) * to_angle
        phi_y = (np.asarray(y, dtype=float) - FIELD_CENTRE) * to_angle
        lx, ly = landing(phi_x, phi_y, self.focal_mm)
        return lx / self.mm_per_unit + FIELD_CENTRE, ly / self.mm_per_unit + FIELD_CENTRE

    def max_error(self, span=50_000, samples=101):
        """Largest distance (units) between commanded and landed over a centred square."""
        grid = np.linspace(FIELD_CENTRE - span / 2, FIELD_CENTRE + span / 2, samples)
        x, y = np.meshgrid(grid, grid)
        lx, ly = self.land(x, y)
        return float(np.hypot(lx - x, ly - y).max())


def synthetic_head(max_error=1400.0, span=50_000, focal_mm=PAPER_FOCAL_MM):
    """A :class:`ScanHeadModel` whose distortion over a ``span``-unit square peaks at
    ``max_error`` units (Zhu & Zhang's head: about 1400 over 50 000)."""
    _check_positive("max_error", max_error, "units")
    low, high = 1.0, 20 * focal_mm              # the error grows with the field width
    for _ in range(80):
        middle = (low + high) / 2
        if ScanHeadModel(field_mm=middle, focal_mm=focal_mm).max_error(span) < max_error:
            low = middle
        else:
            high = middle
    return ScanHeadModel(field_mm=(low + high) / 2, focal_mm=focal_mm)
