"""Correction tables from measured points (after Zhu & Zhang's vision-assisted correction).

A calibration marks an ``n × n`` grid of points (n = 3 … 11) over the calibrated square, and
their landed positions are measured (a camera, :mod:`.photo`, or by hand). The error at each
grid point is ``measured − commanded``. Between grid points the error is estimated either by
bilinear interpolation of the grid (Zhu & Zhang's better method), or by a least-squares
polynomial (their "curve fit"). The table's node offsets then solve ``q + d + E(q + d) = q``
for each node ``q`` by fixed-point iteration: the spot is sent to where it must be aimed for it
to land on ``q``.

Positions are galvo units throughout.
"""

import csv

import numpy as np

from ..gateware.field.correction_table import OFFSET_MAX, OFFSET_MIN, CorrectionTable
from .model import FIELD_CENTRE


__all__ = ["METHODS", "GRID_SIZES", "MeasurementError", "read_pairs", "calibration_grid", "error_model",
           "table_from_measurement", "residuals"]


#: How the error between grid points is estimated.
METHODS = ("bilinear", "polynomial")

#: Calibration grids Zhu & Zhang tried.
GRID_SIZES = (3, 5, 7, 9, 11)

#: Zhu & Zhang's calibrated square, in galvo units.
DEFAULT_SPAN = 50_000


class MeasurementError(ValueError):
    """Measured points that cannot make a table; the message says why."""


def read_pairs(path):
    """Commanded and measured grids ``(cx, cy, mx, my)``, each n × n, from a CSV of
    ``cmd_x, cmd_y, meas_x, meas_y`` rows (galvo units; a header line and ``#`` comments are
    skipped). Rows may come in any order: the grid is sorted by commanded Y, then X."""
    rows = []
    try:
        with open(path, newline="", encoding="utf-8") as file:
            for number, row in enumerate(csv.reader(file), start=1):
                if not row or row[0].strip().startswith("#"):
                    continue
                try:
                    values = [float(v) for v in row]
                except ValueError:
                    if number == 1:
                        continue                     # a header line
                    raise MeasurementError(f"{path}, line {number}: not four numbers: {row!r}")
                if len(values) != 4:
                    raise MeasurementError(f"{path}, line {number}: {len(values)} values; a row "
                                           f"is cmd_x, cmd_y, meas_x, meas_y")
                if not np.all(np.isfinite(values)):
                    raise MeasurementError(f"{path}, line {number}: not finite numbers: {row!r}")
                rows.append(values)
    except UnicodeDecodeError:
        raise MeasurementError(f"{path}: not UTF-8 text") from None
    except OSError as error:
        raise MeasurementError(f"{path}: {error.strerror or error}") from None
    n = round(len(rows) ** 0.5)
    if n < 2 or n * n != len(rows):
        raise MeasurementError(f"{path}: {len(rows)} points do not make a square grid")
    data = np.array(sorted(rows, key=lambda r: (r[1], r[0])))
    return [data[:, k].reshape(n, n) for k in range(4)]


def calibration_grid(n, span=DEFAULT_SPAN, centre=FIELD_CENTRE):
    """Commanded positions ``(x, y)`` of an ``n × n`` grid, arrays indexed ``[row][column]``
    (row = Y), spread over a ``span``-unit square around ``centre``, rounded to units."""
    if not isinstance(n, int) or isinstance(n, bool) or not 2 <= n <= 65:
        raise MeasurementError(f"a calibration grid has 2 to 65 points a side, not {n!r}")
    if not 0 < span <= 65535 or centre - span / 2 < 0 or centre + span / 2 > 65535:
        raise MeasurementError(f"a {span}-unit square around {centre} leaves the field")
    line = np.round(np.linspace(centre - span / 2, centre + span / 2, n)).astype(np.int64)
    return np.meshgrid(line, line)


def _grid_axes(cx, cy):
    """The X and Y lines of a commanded grid, checked to be one."""
    cx = np.asarray(cx, dtype=float)
    cy = np.asarray(cy, dtype=float)
    if cx.ndim != 2 or cx.shape != cy.shape or cx.shape[0] != cx.shape[1] or cx.shape[0] < 2:
        raise MeasurementError(f"commanded points must form a square grid, not {cx.shape}")
    xs, ys = cx[0], cy[:, 0]
    if not (np.allclose(cx, xs[None, :]) and np.allclose(cy, ys[:, None])):
        raise MeasurementError("commanded points are not on a grid of rows and columns")
    if np.any(np.diff(xs) <= 0) or np.any(np.diff(ys) <= 0):
        raise MeasurementError("grid columns must increase in X and rows in Y")
    return xs, ys


def _bilinear(xs, ys, values):
    """Piecewise bilinear interpolation of ``values[row][col]`` on lines ``xs``, ``ys``,
    extended linearly beyond the outer cells."""
    def estimate(x, y):
        i = np.clip(np.searchsorted(xs, x, side="right") - 1, 0, len(xs) - 2)
        j = np.clip(np.searchsorted(ys, y, side="right") - 1, 0, len(ys) - 2)
        u = (x - xs[i]) / (xs[i + 1] - xs[i])
        v = (y - ys[j]) / (ys[j + 1] - ys[j])
        return ((1 - u) * (1 - v) * values[j, i] + u * (1 - v) * values[j, i + 1] +
                (1 - u) * v * values[j + 1, i] + u * v * values[j + 1, i + 1])
    return estimate


def _polynomial(cx, cy, values):
    """Least-squares tensor polynomial of degree min(n - 1, 3) in each axis."""
    n = cx.shape[0]
    degree = min(n - 1, 3)
    scale = max(np.ptp(cx), np.ptp(cy)) / 2
    middle_x, middle_y = cx.mean(), cy.mean()

    def basis(x, y):
        u, v = (x - middle_x) / scale, (y - middle_y) / scale
        return np.stack([u ** a * v ** b for a in range(degree + 1)
                         for b in range(degree + 1)], axis=-1)

    coefficients, *_ = np.linalg.lstsq(basis(cx.ravel(), cy.ravel()), values.ravel(),
                                       rcond=None)
    return lambda x, y: basis(np.asarray(x, dtype=float), np.asarray(y, dtype=float)) @ \
        coefficients


def error_model(cx, cy, mx, my, method="bilinear"):
    """A function ``E(x, y) → (ex, ey)``: the estimated landing error at any position."""
    if method not in METHODS:
        raise MeasurementError(f"method must be one of {', '.join(METHODS)}, not {method!r}")
    xs, ys = _grid_axes(cx, cy)
    cx, cy = np.asarray(cx, dtype=float), np.asarray(cy, dtype=float)
    mx, my = np.asarray(mx, dtype=float), np.asarray(my, dtype=float)
    if mx.shape != cx.shape or my.shape != cx.shape:
        raise MeasurementError(f"{cx.shape} commanded points but {mx.shape} measured")
    if not (np.all(np.isfinite(mx)) and np.all(np.isfinite(my))):
        raise MeasurementError("measured points must be finite numbers")
    ex, ey = mx - cx, my - cy
    spacing = min(np.diff(xs).min(), np.diff(ys).min())
    if np.abs(ex).max() >= spacing or np.abs(ey).max() >= spacing:
        raise MeasurementError(
            f"a measured point lies more than a grid spacing ({spacing:.0f} units) from where "
            f"it was commanded: the points are out of order or not from this grid")
    if method == "bilinear":
        fx, fy = _bilinear(xs, ys, ex), _bilinear(xs, ys, ey)
    else:
        fx, fy = _polynomial(cx, cy, ex), _polynomial(cx, cy, ey)
    return lambda x, y: (fx(x, y), fy(x, y))


def table_from_measurement(cx, cy, mx, my, *, nodes=17, method="bilinear", iterations=8):
    """The :class:`CorrectionTable` that puts the spot on the commanded points.

    ``cx``, ``cy`` are the commanded grid (``[row][column]``), ``mx``, ``my`` where each point
    landed. Offsets beyond ±32767 units are clipped.
    """
    errors = error_model(cx, cy, mx, my, method)
    identity = CorrectionTable.identity(nodes)
    qx, qy = np.meshgrid(identity.node_positions().astype(float),
                         identity.node_positions().astype(float))
    dx, dy = np.zeros_like(qx), np.zeros_like(qy)
    for _ in range(iterations):
        ex, ey = errors(qx + dx, qy + dy)
        dx, dy = -ex, -ey
    dx = np.clip(np.round(dx), OFFSET_MIN, OFFSET_MAX).astype(np.int64)
    dy = np.clip(np.round(dy), OFFSET_MIN, OFFSET_MAX).astype(np.int64)
    return CorrectionTable(dx, dy)


def residuals(land, table=None, *, span=DEFAULT_SPAN, samples=51):
    """Landing errors over a ``span``-unit square, before and after ``table``.

    ``land(x, y)`` gives where a commanded position lands (a scan head, real or modelled).
    Every target on a ``samples × samples`` grid is corrected by the gateware's own arithmetic
    (:meth:`CorrectionTable.apply`), sent to ``land`` and compared with the target. Returns
    ``{"before_max", "before_mean", "after_max", "after_mean", "removed"}`` in galvo units
    (``removed``: fraction of the mean error taken away).
    """
    line = np.round(np.linspace(FIELD_CENTRE - span / 2, FIELD_CENTRE + span / 2,
                                samples)).astype(np.int64)
    tx, ty = np.meshgrid(line, line)
    lx, ly = land(tx, ty)
    before = np.hypot(lx - tx, ly - ty)
    result = {"before_max": float(before.max()), "before_mean": float(before.mean())}
    if table is not None:
        cx, cy, _ = table.apply(tx, ty)
        lx, ly = land(cx, cy)
        after = np.hypot(lx - tx, ly - ty)
        result.update(after_max=float(after.max()), after_mean=float(after.mean()),
                      removed=float(1 - after.mean() / before.mean()))
    return result
