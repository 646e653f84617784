"""The f-theta two-mirror distortion model of Liao & Chen 2016.

Two galvo mirrors deflect the beam by twice their angles ``φx``, ``φy``; through an f-theta lens
of focal length ``f`` the controller assumes the spot lands at ``x' = 2fφx``, ``y' = 2fφy``.
It does not: the second mirror sees a beam already tilted by the first, so X bends into a
pincushion and Y into a barrel. Liao & Chen give where the spot really lands (:func:`landing`),
the angle corrections that put it where it was asked (:func:`exact_compensation`) and a
polynomial fitted to them (:func:`polynomial_compensation`), with eight points in their Table 1.

Two findings from reproducing Table 1 (docs/user/correction.md):

* the exact-formula columns (Δφ'x, Δφ'y) are reproduced to the 4 digits printed;
* with the coefficients as printed (−3.242e−8, −1.024e−7, 6.515e−8, −1.222e−5; x, y in mm) the
  polynomial is ten times too large at 150 mm. With the two cubic coefficients and the Y linear
  one ten times smaller (:data:`PAPER_COEFFICIENTS`) all sixteen residuals equal the table's to
  every printed digit but one: at (−100, −100) the table prints Δφy = 0.000059 where the
  formula, and the table's own symmetry (its (100, −100) entry), give 0.000089. A least-squares
  fit of the same four terms over ±150 mm (:func:`fit_polynomial`) gives nearly the corrected
  values, so the printed exponents are taken to be typesetting slips.

Lengths in mm, angles in radians (mechanical mirror angles, as Liao & Chen use).
"""

import numpy as np


__all__ = ["PAPER_FOCAL_MM", "PRINTED_COEFFICIENTS", "PAPER_COEFFICIENTS", "TABLE_1",
           "K_RANGE", "landing", "exact_compensation", "polynomial_compensation",
           "fit_polynomial", "table_1_rows"]


#: Liao & Chen's f-theta lens.
PAPER_FOCAL_MM = 300.0

#: (a, b, c, d) of Δφx = a·k·x·y² + b·k²·x, Δφy = c·k·x²·y + d·k²·y as Liao & Chen print them.
PRINTED_COEFFICIENTS = (-3.242e-8, -1.024e-7, 6.515e-8, -1.222e-5)

#: The same with the exponents that reproduce Liao & Chen's Table 1 (see the module docstring).
PAPER_COEFFICIENTS = (-3.242e-9, -1.024e-7, 6.515e-9, -1.222e-6)

#: The trim factor's range in Liao & Chen (k = 1 for f = 300 mm).
K_RANGE = (0.9706, 1.0306)

#: Liao & Chen's Table 1: X', Y' (mm); exact compensation Δφ'x, Δφ'y; residual after the
#: polynomial Δφx, Δφy (rad).
TABLE_1 = [
    (150, 150, -0.0114, 0.0218, -0.000404, -0.000043),
    (100, 100, -0.0032, 0.0063, 0.000044, -0.000089),
    (-100, -100, 0.0032, -0.0063, -0.000044, 0.000059),
    (-150, -150, 0.0114, -0.0218, 0.000404, 0.000043),
    (-150, 150, 0.0114, 0.0218, 0.000404, -0.000043),
    (-100, 100, 0.0032, 0.0063, -0.000044, -0.000089),
    (100, -100, -0.0032, -0.0063, 0.000044, 0.000089),
    (150, -150, -0.0114, -0.0218, -0.000404, 0.000043),
]


def landing(phi_x, phi_y, focal_mm=PAPER_FOCAL_MM):
    """Where the spot lands (mm) for mirror angles ``phi_x``, ``phi_y`` (rad): Liao & Chen's
    formula."""
    phi_x = np.asarray(phi_x, dtype=float)
    phi_y = np.asarray(phi_y, dtype=float)
    cx, cy = np.cos(2 * phi_x), np.cos(2 * phi_y)
    cc = np.clip(cx * cy, -1.0, 1.0)
    theta = np.arccos(cc)                       # angle of the beam from the lens axis
    sine = np.sqrt(np.maximum(1.0 - cc * cc, 0.0))
    # theta / sin(theta) → 1 on the axis.
    ratio = np.where(sine > 1e-12, theta / np.where(sine > 1e-12, sine, 1.0), 1.0)
    return focal_mm * np.sin(2 * phi_x) * ratio, focal_mm * np.sin(2 * phi_y) * cx * ratio


def exact_compensation(x, y, focal_mm=PAPER_FOCAL_MM):
    """Liao & Chen's exact angle corrections (rad) for the spot to land at ``x``, ``y`` (mm)."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    r = np.hypot(x, y)
    safe = np.where(r > 1e-12, r, 1.0)
    # sin(r/f)/r and tan(r/f)/r → 1/f on the axis.
    sin_ratio = np.where(r > 1e-12, np.sin(r / focal_mm) / safe, 1.0 / focal_mm)
    tan_ratio = np.where(r > 1e-12, np.tan(r / focal_mm) / safe, 1.0 / focal_mm)
    dx = 0.5 * np.arcsin(np.clip(x * sin_ratio, -1.0, 1.0)) - x / (2 * focal_mm)
    dy = 0.5 * np.arctan(y * tan_ratio) - y / (2 * focal_mm)
    return dx, dy


def polynomial_compensation(x, y, k=1.0, coefficients=PAPER_COEFFICIENTS):
    """Liao & Chen's fitted corrections (rad) at ``x``, ``y`` (mm) with trim factor ``k``."""
    a, b, c, d = coefficients
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    return a * k * x * y * y + b * k * k * x, c * k * x * x * y + d * k * k * y


def fit_polynomial(half_field_mm=150.0, focal_mm=PAPER_FOCAL_MM, samples=61):
    """Least-squares (a, b, c, d) of Liao & Chen's four-term polynomial against the exact
    formula."""
    grid = np.linspace(-half_field_mm, half_field_mm, samples)
    x, y = (v.ravel() for v in np.meshgrid(grid, grid))
    ex, ey = exact_compensation(x, y, focal_mm)
    (a, b), *_ = np.linalg.lstsq(np.c_[x * y * y, x], ex, rcond=None)
    (c, d), *_ = np.linalg.lstsq(np.c_[x * x * y, y], ey, rcond=None)
    return float(a), float(b), float(c), float(d)


def table_1_rows(coefficients=PAPER_COEFFICIENTS, focal_mm=PAPER_FOCAL_MM):
    """Table 1 recomputed: for each of its points, (x, y, exact Δφx, Δφy, residual x, y)."""
    rows = []
    for x, y, *_ in TABLE_1:
        ex, ey = exact_compensation(x, y, focal_mm)
        px, py = polynomial_compensation(x, y, 1.0, coefficients)
        rows.append((x, y, float(ex), float(ey), float(ex - px), float(ey - py)))
    return rows
