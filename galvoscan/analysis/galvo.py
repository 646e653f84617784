"""A model of a galvo mirror following XY2-100 frames (the JD1403 galvo of Wan et al. 2018).

A scan head's servo does not jump to each commanded position. Two things shape the path the spot
really takes:

* a **speed limit**: a large step is crossed at the mirror's top speed (its 10 % step takes longer
  than its 1 % step);
* a **closed loop response** that rounds every corner: modelled as a critically damped second
  order low-pass (the fastest response without overshoot, which is how galvo servos are tuned).

Here the commanded position first passes a rate limiter (at most ``v_max`` galvo units per second)
and then the second-order filter with natural frequency ``omega_n``. Both numbers are set from two
small-step response times, as galvo data sheets give them: a step of 1 % of the range settles in
0.3 ms and a step of 10 % in 0.7 ms (Wan et al. 2018). "Settled" means within
:data:`SETTLE_BAND` of the step size for good.

Positions are galvo units (65536 = full range, whatever the lens); time is seconds. The model is
evaluated on a grid of ``substeps`` samples per 10 µs frame: the rate limiter exactly (it is a
ramp within a frame), the filter by convolution with its exact step-invariant kernel.
"""

from functools import lru_cache
import math

import numpy as np


__all__ = ["FRAME_PERIOD", "FULL_RANGE", "SETTLE_BAND", "GalvoModel", "MirrorPath"]


#: One XY2-100 frame: 20 bits at 2 Mbit/s.
FRAME_PERIOD = 10e-6

#: Galvo units across the full range.
FULL_RANGE = 65536

#: A step has settled once it stays within this share of its size of the target.
SETTLE_BAND = 0.01


class MirrorPath:
    """Where the mirrors point, sampled on a regular time grid.

    Attributes
    ----------
    dt : float
        Sample spacing, seconds.
    x, y : numpy.ndarray of float
        Mirror positions in galvo units; sample ``n`` is at time ``n * dt`` from the first frame.
    """

    def __init__(self, dt, x, y):
        self.dt = dt
        self.x = x
        self.y = y

    @property
    def duration(self):
        """Time covered, seconds."""
        return (len(self.x) - 1) * self.dt

    def at(self, times):
        """Positions at the given times (seconds), linearly interpolated: ``(x, y)`` arrays."""
        grid = np.arange(len(self.x)) * self.dt
        return np.interp(times, grid, self.x), np.interp(times, grid, self.y)

    def velocity(self):
        """Per-axis velocity, galvo units per second, ``(vx, vy)`` one sample shorter."""
        return np.diff(self.x) / self.dt, np.diff(self.y) / self.dt

    def acceleration(self):
        """Per-axis acceleration, galvo units per second², ``(ax, ay)`` two samples shorter."""
        return np.diff(self.x, 2) / self.dt ** 2, np.diff(self.y, 2) / self.dt ** 2


class GalvoModel:
    """Rate-limited, critically damped second-order galvo.

    Parameters
    ----------
    omega_n : float
        Natural frequency of the closed loop, rad/s. ``math.inf`` makes the filter transparent.
    v_max : float
        Speed limit, galvo units per second. ``math.inf`` removes it.

    Use :meth:`from_step_times` to set both from data-sheet step times, :meth:`ideal` for a
    mirror that is exactly where it is told (for known-answer checks).
    """

    def __init__(self, *, omega_n, v_max):
        for name, value in (("omega_n", omega_n), ("v_max", v_max)):
            if not isinstance(value, (int, float)) or math.isnan(value) or value <= 0:
                raise ValueError(f"{name} must be a positive number, not {value!r}")
        self.omega_n = float(omega_n)
        self.v_max = float(v_max)

    @classmethod
    def ideal(cls):
        """A mirror with no speed limit and no lag: it follows the frames exactly."""
        return cls(omega_n=math.inf, v_max=math.inf)

    @classmethod
    def from_step_times(cls, *, small_step=0.01, small_time=0.3e-3, large_step=0.1,
                        large_time=0.7e-3):
        """The model whose ``small_step`` and ``large_step`` (shares of the full range) settle
        in ``small_time`` and ``large_time`` seconds. Defaults: the JD1403 galvo of Wan et al.
        2018."""
        if not 0 < small_step < large_step <= 1:
            raise ValueError("need 0 < small_step < large_step <= 1 (shares of the range)")
        if not 0 < small_time < large_time:
            raise ValueError("need 0 < small_time < large_time (seconds)")
        return _calibrated(small_step, small_time, large_step, large_time)

    def __repr__(self):
        return f"GalvoModel(omega_n={self.omega_n:.6g}, v_max={self.v_max:.6g})"

    # -- evaluation ------------------------------------------------------------------------

    def follow(self, frames_x, frames_y, *, substeps=10, start=None):
        """The mirror path for commanded frames (galvo units, one per 10 µs frame).

        Parameters
        ----------
        frames_x, frames_y : array-like
            Commanded positions, one per frame; frame ``k`` is commanded from ``k * 10 µs``.
        substeps : int
            Samples per frame of the returned path.
        start : (float, float), optional
            Where the mirrors rest before the first frame (default: the first frame's position).

        Returns
        -------
        MirrorPath
            ``len(frames) * substeps + 1`` samples, from the start of the first frame to the end
            of the last.
        """
        if not isinstance(substeps, int) or substeps < 1:
            raise ValueError(f"substeps must be a positive integer, not {substeps!r}")
        frames_x = np.asarray(frames_x, dtype=float)
        frames_y = np.asarray(frames_y, dtype=float)
        if frames_x.shape != frames_y.shape or frames_x.ndim != 1 or len(frames_x) == 0:
            raise ValueError("frames_x and frames_y must be equally long, non-empty sequences")
        if start is None:
            start = (frames_x[0], frames_y[0])
        dt = FRAME_PERIOD / substeps
        kernel = self._kernel(dt)
        axes = []
        for frames, rest in ((frames_x, start[0]), (frames_y, start[1])):
            reference = self._rate_limited(frames, float(rest), substeps)
            axes.append(self._filtered(reference, float(rest), kernel))
        return MirrorPath(dt, *axes)

    def _rate_limited(self, frames, rest, substeps):
        """Rate-limited reference on the sub-grid (value at each sub-interval's middle)."""
        if math.isinf(self.v_max):
            starts = np.concatenate(([rest], frames[:-1]))
            steps = np.repeat(frames - starts, substeps)
            levels = np.repeat(starts, substeps) + steps          # jumps at once
            return levels
        step_max = self.v_max * FRAME_PERIOD
        starts = np.empty_like(frames)
        level = rest
        for k, target in enumerate(frames.tolist()):              # sequential by nature
            starts[k] = level
            move = target - level
            level = target if abs(move) <= step_max else level + math.copysign(step_max, move)
        reach = self.v_max * (np.arange(substeps) + 0.5) * (FRAME_PERIOD / substeps)
        moves = (frames - starts)[:, None]
        return (starts[:, None] + np.clip(moves, -reach, reach)).ravel()

    def _kernel(self, dt):
        """Exact response of the filter to a one-sample pulse held ``dt`` (step-invariant)."""
        if math.isinf(self.omega_n):
            return None
        length = int(math.ceil(40 / (self.omega_n * dt))) + 1     # e^-40: nothing left
        t = np.arange(length + 1) * dt * self.omega_n
        step = 1 - (1 + t) * np.exp(-t)
        return np.diff(step)

    @staticmethod
    def _filtered(reference, rest, kernel):
        """Output samples 0 … len(reference): the filter's state at each sub-interval's start
        (for the ideal mirror, its position during the sub-interval)."""
        deviation = reference - rest
        if kernel is None:
            # No lag: during sub-interval n the mirror is at its reference.
            return rest + np.concatenate((deviation, deviation[-1:]))
        size = len(deviation) + len(kernel)
        fft_size = 1 << (size - 1).bit_length()
        response = np.fft.irfft(np.fft.rfft(deviation, fft_size) * np.fft.rfft(kernel, fft_size),
                                fft_size)
        # Output n is the response to inputs 0 … n-1: shift by one sample.
        return rest + np.concatenate(([0.0], response[:len(deviation)]))

    def step_time(self, step, *, band=SETTLE_BAND, substeps=10):
        """Seconds a step of ``step`` galvo units takes to settle within ``band`` of its size."""
        frames = int(math.ceil(5e-3 / FRAME_PERIOD)) + int(
            math.ceil(abs(step) / (self.v_max * FRAME_PERIOD))) if math.isfinite(self.v_max) \
            else int(math.ceil(5e-3 / FRAME_PERIOD))
        path = self.follow(np.full(frames, float(step)), np.zeros(frames), substeps=substeps,
                           start=(0.0, 0.0))
        outside = np.nonzero(np.abs(path.x - step) > band * abs(step))[0]
        return 0.0 if len(outside) == 0 else (outside[-1] + 1) * path.dt


def _bisect(function, low, high, target, *, increasing, iterations=60):
    """x in [low, high] (geometric bisection) with function(x) = target."""
    for _ in range(iterations):
        middle = math.sqrt(low * high)
        if (function(middle) < target) == increasing:
            low = middle
        else:
            high = middle
    return math.sqrt(low * high)


@lru_cache(maxsize=8)
def _calibrated(small_step, small_time, large_step, large_time):
    small = small_step * FULL_RANGE
    large = large_step * FULL_RANGE

    def fitted(v_max):
        # The natural frequency that makes the small step take small_time at this speed limit.
        omega_n = _bisect(lambda w: GalvoModel(omega_n=w, v_max=v_max).step_time(small),
                          1e2, 1e7, small_time, increasing=False, iterations=40)
        return GalvoModel(omega_n=omega_n, v_max=v_max)

    # A lower speed limit slows the large step far more than the small one.
    v_max = _bisect(lambda v: fitted(v).step_time(large), large / large_time, 1e4 * large / large_time,
                    large_time, increasing=False, iterations=40)
    return fitted(v_max)
