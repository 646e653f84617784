"""The spiral's two angle tables, computed at elaboration time (Dai & Tang 2020).

One period of a sine is sampled at ``points`` steps, the same time apart. Sampled *uniformly in
phase*, the mirror rushes through the centre and lingers at the edges: the mesh it draws is sparse
in the middle and dense at the edges. The paper instead spaces the sampled *angles* like a
Gaussian around the centre angle, so more of the points sit near the middle of the swing.

Here that is done exactly: within each quarter period the k-th of ``q = points / 4`` steps goes to
the amplitude ``a(k / q)``, where ``a`` is the quantile function of a half-normal distribution of
width σ truncated to the half-swing ``[0, 1]``. The quarters are visited in the order of one sine
period (centre → +edge → centre → −edge). The Y table is the X table a quarter period on (cosine).

σ is in units of the half-swing: small σ crowds the points into the centre, large σ spaces them
evenly (a triangle wave). Tables are plain integers, so the same table feeds the gateware ROMs,
the simulation models and the analysis.
"""

from statistics import NormalDist
import math

from ..limits import DEFAULT_TABLE_POINTS, MAX_POINTS, MIN_POINTS


__all__ = ["SpiralTable", "SAMPLINGS", "DEFAULT_SIGMA", "OFFSET_FULL_SCALE", "DEFAULT_POINTS",
           "MIN_POINTS", "MAX_POINTS"]

#: Samples per sine period: the paper's 128 by default; a multiple of 4 from MIN_POINTS to
#: MAX_POINTS (declared with the other limits in :mod:`galvoscan.gateware.limits`).
DEFAULT_POINTS = DEFAULT_TABLE_POINTS


#: Sampling kinds: ``"triangle"`` spaces the amplitudes evenly (the mirror swept at constant
#: speed), the limit of the Gaussian sampling as σ grows.
SAMPLINGS = ("gaussian", "uniform", "triangle")

#: Default σ of the Gaussian sampling, in half-swings, chosen by the scan analysis's σ sweep
#: (``galvoscan analyze --sweep``, README "Choice of σ"): on the paper's 50 × 20 mm field with the
#: galvo model of Wan et al. 2018 and linear interpolation between points, the dose averaged over
#: 1 mm blocks varies less and less as σ grows and levels off from σ ≈ 2 (CV 0.12, against 0.11
#: at σ = 5 and for the triangle wave, 0.34 at σ = 0.8 and 1.07 for uniform sampling). The
#: triangle (σ → ∞) is a little better on every count but one: 2 is the smallest σ within 10 %
#: of the best, and it keeps the edges slightly below the centre (edge/centre dose 0.79, the
#: triangle's 0.89), as the paper reports.
DEFAULT_SIGMA = 2.0

#: Table value of a full half-swing; tables hold signed 16-bit offsets from the centre.
OFFSET_FULL_SCALE = 32767


class SpiralTable:
    """X and Y angle tables for the precessing spiral.

    Parameters
    ----------
    points : int
        Samples per sine period, a multiple of 4 from :data:`MIN_POINTS` to :data:`MAX_POINTS`.
        The paper uses 128.
    sampling : str
        ``"gaussian"`` (the paper's choice), ``"uniform"`` (equal phase steps) or
        ``"triangle"`` (equal amplitude steps: σ → ∞).
    sigma : float
        Width of the Gaussian sampling in half-swings, from 0.05 to 100. Ignored for uniform
        sampling.

    Attributes
    ----------
    x, y : list of int
        Signed 16-bit offsets from the field centre, ``±OFFSET_FULL_SCALE`` at the edges.
    """

    def __init__(self, *, points=DEFAULT_POINTS, sampling="gaussian", sigma=DEFAULT_SIGMA):
        if not isinstance(points, int) or isinstance(points, bool) or \
                points % 4 != 0 or not MIN_POINTS <= points <= MAX_POINTS:
            raise ValueError(f"points must be a multiple of 4 from {MIN_POINTS} to {MAX_POINTS}, "
                             f"not {points!r}")
        if sampling not in SAMPLINGS:
            raise ValueError(f"sampling must be one of {', '.join(SAMPLINGS)}, not {sampling!r}")
        if not isinstance(sigma, (int, float)) or not math.isfinite(sigma) or \
                not 0.05 <= sigma <= 100:
            raise ValueError(f"sigma must be a number from 0.05 to 100 half-swings, not {sigma!r}")
        self.points = points
        self.sampling = sampling
        self.sigma = float(sigma)

        quarter = points // 4
        amplitudes = [self._amplitude(k / quarter) for k in range(quarter + 1)]
        x = []
        for i in range(points):
            half_period_step = i % (2 * quarter)
            k = min(half_period_step, 2 * quarter - half_period_step)  # steps from the centre
            sign = 1 if i < 2 * quarter else -1
            x.append(sign * round(amplitudes[k] * OFFSET_FULL_SCALE))
        self.x = x
        self.y = x[quarter:] + x[:quarter]

    def _amplitude(self, level):
        """Amplitude (0 … 1 half-swings) reached after ``level`` of a quarter period."""
        if self.sampling == "uniform":
            return math.sin(math.pi / 2 * level)
        if self.sampling == "triangle":
            return level
        if level >= 1:
            return 1.0
        normal = NormalDist(0, self.sigma)
        # Quantile of |N(0, σ)| truncated to [0, 1].
        return normal.inv_cdf(0.5 + level * (normal.cdf(1) - 0.5))

    def __repr__(self):
        sigma = f", sigma={self.sigma:g}" if self.sampling == "gaussian" else ""
        return f"SpiralTable(points={self.points}, sampling={self.sampling!r}{sigma})"
