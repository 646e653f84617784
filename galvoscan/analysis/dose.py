"""Laser pulses along the mirror path, the dose they leave, and how even it is.

Every pulse deposits a Gaussian spot (1/e² diameter ``spot_mm``) of fluence
``F(r) = 2E/(πw²)·exp(−2r²/w²)``, ``w = spot_mm/2``, ``E = power/prr``. The dose map is the sum of
all spots on a square grid (default cell: a quarter of the spot diameter), in J/cm².

Metrics (over the cells of the field rectangle; *inner* is its central 80 % × 80 %, *edge* the
band within :data:`EDGE_MM` of its border):

``cv``, ``cv_inner``
    Coefficient of variation (standard deviation / mean) of the dose.
``cv_1mm``
    Coefficient of variation of the dose averaged over 1 mm × 1 mm blocks: how even the
    pattern is at the scale of heat flow and of a cleaned patch, not of single spot tracks.
``min_max``
    Smallest over largest dose.
``edge_centre``
    Mean dose of the edge band over the mean of the inner part (> 1: edges burn harder).
``edge_peak``
    99th percentile of the dose in the edge band over that of the inner part: the hottest
    spots along the border against the hottest inside (a raster's turn-arounds show here).
``fill``
    Share of the field within the 1/e² radius of at least one pulse.
``overlap50``
    Share within the 1/e² radius of at least two pulses: there neighbouring spots overlap by
    at least 50 % (spot spacing ≤ half a diameter).
``revisit_*``
    Revisit intervals: for each point the pattern reaches, the shortest time from the last pulse
    of one pass near it (default: within 0.1 mm, about how far heat spreads in steel in 0.2 ms)
    to the first of the next (a new pass starts after a gap of more than ``pass_gap``), with
    the pattern repeating. Short intervals mean heat builds up: p5 and
    median over the cells in ms, and the share of cells revisited within 1 ms.
"""

import math

import numpy as np

from .galvo import FRAME_PERIOD


__all__ = ["Laser", "Region", "Pulses", "pulses_along", "DoseMap", "dose_map", "revisit_intervals",
           "INNER_SHARE", "EDGE_MM"]


#: The inner part is this share of the field in each direction.
INNER_SHARE = 0.8

#: Width of the edge band, mm: about where a raster's turn-arounds (mirror lag ≈ 0.4 mm at
#: 5 m/s) put their extra dose.
EDGE_MM = 1.0


class Laser:
    """Pulsed laser settings.

    Parameters
    ----------
    power_w : float
        Average power, W (Dai & Tang 2020: 50 W).
    prr_hz : float
        Pulse repetition rate, Hz (Dai & Tang 2020: 100 kHz).
    spot_mm : float
        Spot 1/e² diameter on the work piece, mm. Default 0.05 mm: a 7 mm, M² 1.5 beam at
        1064 nm through Dai & Tang's f = 160 mm lens.
    """

    def __init__(self, *, power_w=50.0, prr_hz=100e3, spot_mm=0.05):
        for name, value, low, high in (("power_w", power_w, 1e-3, 1e5),
                                       ("prr_hz", prr_hz, 1.0, 100e6),
                                       ("spot_mm", spot_mm, 1e-3, 100.0)):
            if not isinstance(value, (int, float)) or not low <= value <= high:
                raise ValueError(f"{name} must be a number from {low:g} to {high:g}, "
                                 f"not {value!r}")
        self.power_w = float(power_w)
        self.prr_hz = float(prr_hz)
        self.spot_mm = float(spot_mm)

    @property
    def pulse_energy_j(self):
        return self.power_w / self.prr_hz

    @property
    def peak_fluence_j_cm2(self):
        """Peak fluence of one pulse, J/cm²."""
        w_cm = self.spot_mm / 20
        return 2 * self.pulse_energy_j / (math.pi * w_cm ** 2)

    def __repr__(self):
        return (f"Laser(power_w={self.power_w:g}, prr_hz={self.prr_hz:g}, "
                f"spot_mm={self.spot_mm:g})")


class Region:
    """The field rectangle to dose, mm, in galvo coordinates (``centre`` in mm from 0 units)."""

    def __init__(self, centre_mm, size_mm):
        if min(size_mm) <= 0:
            raise ValueError(f"region size must be positive, not {size_mm!r}")
        self.centre = tuple(float(c) for c in centre_mm)
        self.size = tuple(float(s) for s in size_mm)

    @property
    def low(self):
        return tuple(c - s / 2 for c, s in zip(self.centre, self.size))

    @property
    def high(self):
        return tuple(c + s / 2 for c, s in zip(self.centre, self.size))


class Pulses:
    """Laser pulses: times (s) and positions (mm)."""

    def __init__(self, t, x, y):
        self.t, self.x, self.y = t, x, y

    def __len__(self):
        return len(self.t)


def pulses_along(path, frames, laser, head, *, t0=0.0, t1=None):
    """Pulses at the PRR from ``t0`` to ``t1`` (default: end of the frames) that fall in frames
    with the laser enabled; positions from the mirror path, converted to mm.

    The pulse train is taken half a pulse period after the frame grid (pulse ``k`` at
    ``t0 + (k + ½)/prr``): at 100 kHz each pulse falls mid-frame, never on the instant a
    new position is commanded.
    """
    t1 = len(frames) * FRAME_PERIOD if t1 is None else t1
    count = int(math.floor((t1 - t0) * laser.prr_hz + 1e-9))
    t = t0 + (np.arange(count) + 0.5) / laser.prr_hz
    frame = np.minimum((t / FRAME_PERIOD + 1e-9).astype(np.int64), len(frames) - 1)
    t = t[frames.laser[frame]]
    x, y = path.at(t)
    return Pulses(t, head.mm(x), head.mm(y))


class DoseMap:
    """Dose on a square grid of cells covering the region and a one-spot margin.

    Attributes
    ----------
    dose : numpy.ndarray, shape (nx, ny)
        J/cm² at the cell centres (index ``[i, j]``: x, y).
    hits : numpy.ndarray of int
        Pulses whose 1/e² radius reaches each cell centre.
    x, y : numpy.ndarray
        Cell centre coordinates, mm.
    inside, inner : numpy.ndarray of bool
        Cells within the region / its inner part.
    outside_energy : float
        Share of pulse energy that landed off the grid.
    """

    def metrics(self):
        field = self.dose[self.inside]
        inner = self.dose[self.inner]
        edge = self.dose[self.inside & self.edge]
        mean = field.mean()
        hits = self.hits[self.inside]
        return {
            "dose_mean_j_cm2": float(mean),
            "dose_p1_j_cm2": float(np.percentile(field, 1)),
            "cv": float(field.std() / mean) if mean > 0 else math.inf,
            "cv_inner": float(inner.std() / inner.mean()) if inner.mean() > 0 else math.inf,
            "cv_1mm": self._block_cv(1.0),
            "min_max": float(field.min() / field.max()) if field.max() > 0 else 0.0,
            "edge_centre": float(edge.mean() / inner.mean()) if inner.mean() > 0 else math.inf,
            "edge_peak": float(np.percentile(edge, 99) / np.percentile(inner, 99))
            if np.percentile(inner, 99) > 0 else math.inf,
            "fill": float(np.mean(hits >= 1)),
            "overlap50": float(np.mean(hits >= 2)),
        }


    def blocks(self, block_mm=1.0):
        """The field's dose averaged over ``block_mm`` squares (whole blocks only)."""
        rows = np.nonzero(self.inside.any(axis=1))[0]
        cols = np.nonzero(self.inside.any(axis=0))[0]
        field = self.dose[rows[0]:rows[-1] + 1, cols[0]:cols[-1] + 1]
        size = max(1, int(round(block_mm / self.cell)))
        bx, by = field.shape[0] // size, field.shape[1] // size
        return field[:bx * size, :by * size].reshape(bx, size, by, size).mean(axis=(1, 3))

    def _block_cv(self, block_mm):
        blocks = self.blocks(block_mm)
        if blocks.size < 2:
            return None
        return float(blocks.std() / blocks.mean()) if blocks.mean() > 0 else math.inf


def _grid_axis(low, high, cell, margin):
    start = low - margin
    count = int(math.ceil((high - low + 2 * margin) / cell))
    return start + (np.arange(count) + 0.5) * cell


def _disc_offsets(radius_cells):
    r = int(math.floor(radius_cells))
    return [(i, j) for i in range(-r, r + 1) for j in range(-r, r + 1)
            if i * i + j * j <= radius_cells ** 2 + 1e-9]


def _shifted_sum(grid, offsets, weights=None):
    """Σ weight · grid shifted by each offset (zero outside)."""
    out = np.zeros_like(grid)
    nx, ny = grid.shape
    for k, (di, dj) in enumerate(offsets):
        w = 1 if weights is None else weights[k]
        xs, xd = (slice(0, nx - di), slice(di, nx)) if di >= 0 else (slice(-di, nx), slice(0, nx + di))
        ys, yd = (slice(0, ny - dj), slice(dj, ny)) if dj >= 0 else (slice(-dj, ny), slice(0, ny + dj))
        out[xd, yd] += w * grid[xs, ys]
    return out


def _convolve_axis(grid, kernel, axis):
    half = len(kernel) // 2
    offsets = [((m - half), 0) if axis == 0 else (0, (m - half)) for m in range(len(kernel))]
    return _shifted_sum(grid, offsets, kernel)


def dose_map(pulses, laser, region, *, cell_mm=None):
    """The dose the pulses leave, on a grid over ``region``."""
    cell = laser.spot_mm / 4 if cell_mm is None else float(cell_mm)
    if not 0 < cell <= laser.spot_mm:
        raise ValueError(f"cell must be positive and at most the spot diameter, not {cell!r}")
    w = laser.spot_mm / 2
    gx = _grid_axis(region.low[0], region.high[0], cell, laser.spot_mm)
    gy = _grid_axis(region.low[1], region.high[1], cell, laser.spot_mm)
    nx, ny = len(gx), len(gy)

    # Energy to the four nearest cell centres (cloud in cell), then a separable Gaussian.
    fx = (pulses.x - gx[0]) / cell
    fy = (pulses.y - gy[0]) / cell
    ix, iy = np.floor(fx).astype(np.int64), np.floor(fy).astype(np.int64)
    wx, wy = fx - ix, fy - iy
    energy = np.zeros(nx * ny)
    landed = 0.0
    for di, dj, weight in ((0, 0, (1 - wx) * (1 - wy)), (1, 0, wx * (1 - wy)),
                           (0, 1, (1 - wx) * wy), (1, 1, wx * wy)):
        i, j = ix + di, iy + dj
        ok = (i >= 0) & (i < nx) & (j >= 0) & (j < ny)
        energy += np.bincount(i[ok] * ny + j[ok], weights=weight[ok], minlength=nx * ny)
        landed += weight[ok].sum()
    energy = energy.reshape(nx, ny) * laser.pulse_energy_j
    reach = int(math.ceil(2.5 * w / cell))
    kernel = np.exp(-2 * (np.arange(-reach, reach + 1) * cell) ** 2 / w ** 2)
    dose = _convolve_axis(_convolve_axis(energy, kernel, 0), kernel, 1)
    dose *= 2 / (math.pi * (w / 10) ** 2)           # J per cm² (w in cm)

    # Hits: pulses (snapped to the nearest cell) within the 1/e² radius of each cell centre.
    ni, nj = np.rint(fx).astype(np.int64), np.rint(fy).astype(np.int64)
    ok = (ni >= 0) & (ni < nx) & (nj >= 0) & (nj < ny)
    counts = np.bincount(ni[ok] * ny + nj[ok], minlength=nx * ny).reshape(nx, ny)
    hits = _shifted_sum(counts, _disc_offsets(w / cell))

    result = DoseMap()
    result.dose, result.hits, result.x, result.y, result.cell = dose, hits, gx, gy, cell
    in_x = (gx >= region.low[0]) & (gx <= region.high[0])
    in_y = (gy >= region.low[1]) & (gy <= region.high[1])
    result.inside = in_x[:, None] & in_y[None, :]
    margin = [(1 - INNER_SHARE) / 2 * s for s in region.size]
    inner_x = (gx >= region.low[0] + margin[0]) & (gx <= region.high[0] - margin[0])
    inner_y = (gy >= region.low[1] + margin[1]) & (gy <= region.high[1] - margin[1])
    result.inner = inner_x[:, None] & inner_y[None, :]
    edge_x = (gx < region.low[0] + EDGE_MM) | (gx > region.high[0] - EDGE_MM)
    edge_y = (gy < region.low[1] + EDGE_MM) | (gy > region.high[1] - EDGE_MM)
    result.edge = edge_x[:, None] | edge_y[None, :]
    result.outside_energy = 1 - landed / len(pulses) if len(pulses) else 0.0
    return result


def revisit_intervals(pulses, region, *, radius_mm, period, pass_gap=100e-6):
    """Shortest revisit interval (s) of every point of the field the pattern reaches.

    Points are the centres of a grid of ``radius_mm / 2`` cells over ``region``; a pulse reaches
    a point within ``radius_mm`` of it. A pass over a point is a run of pulses reaching it with
    no gap longer than ``pass_gap``; a revisit interval runs from the last pulse of one pass to
    the first pulse of the next. The pattern repeats every ``period`` seconds (cleaning repeats
    it until the part is clean), so the last pass is followed by the first one period later.
    """
    cell = radius_mm / 2
    gx = _grid_axis(region.low[0], region.high[0], cell, 0)
    gy = _grid_axis(region.low[1], region.high[1], cell, 0)
    nx, ny = len(gx), len(gy)
    ni = np.rint((pulses.x - gx[0]) / cell).astype(np.int64)
    nj = np.rint((pulses.y - gy[0]) / cell).astype(np.int64)
    cells, order = [], []
    for di, dj in _disc_offsets(2):
        i, j = ni + di, nj + dj
        valid = (i >= 0) & (i < nx) & (j >= 0) & (j < ny)
        cells.append(i[valid] * ny + j[valid])
        order.append(np.nonzero(valid)[0])
    cells = np.concatenate(cells)
    order = np.concatenate(order)
    if len(cells) == 0:
        return np.zeros(0)
    sort = np.lexsort((order, cells))
    cells, times = cells[sort], pulses.t[order[sort]]
    new_cell = np.concatenate(([True], cells[1:] != cells[:-1]))
    new_pass = new_cell | np.concatenate(([False], np.diff(times) > pass_gap))
    starts = np.nonzero(new_pass)[0]
    ends = np.concatenate((starts[1:] - 1, [len(times) - 1]))
    pass_start, pass_end = times[starts], times[ends]
    first_of_cell = new_cell[starts]
    # Index of each pass's cell's first pass, and whether the next pass is the same cell's.
    cell_first = np.maximum.accumulate(np.where(first_of_cell, np.arange(len(starts)), 0))
    same_next = np.concatenate((~first_of_cell[1:], [False]))
    next_start = np.where(same_next, np.concatenate((pass_start[1:], [0.0])),
                          pass_start[cell_first] + period)
    interval = next_start - pass_end
    return np.minimum.reduceat(interval, np.nonzero(first_of_cell)[0])


def revisit_metrics(shortest):
    """Summary of the cells' shortest revisit intervals."""
    if len(shortest) == 0:
        return {"revisit_p5_ms": None, "revisit_median_ms": None, "revisit_under_1ms": None}
    return {
        "revisit_p5_ms": float(np.percentile(shortest, 5) * 1e3),
        "revisit_median_ms": float(np.median(shortest) * 1e3),
        "revisit_under_1ms": float(np.mean(shortest < 1e-3)),
    }
