"""The scan settings a system starts with: what its host-writable scan registers reset to."""

from .host.regmap import Mode, register_map


__all__ = ["ScanSettings"]


#: The default build's registers: where the scan settings' defaults and ranges come from.
_DEFAULT_MAP = register_map()


def _check_register_value(name, value):
    reg = _DEFAULT_MAP[name]
    if not isinstance(value, int) or isinstance(value, bool) or \
            not reg.low <= value <= reg.high:
        raise ValueError(f"{name} must be an integer from {reg.low} to {reg.high} "
                         f"({reg.unit}), not {value!r}")


class ScanSettings:
    """The scan settings the system starts with: what the host-writable registers reset to
    (the register map's defaults unless given).

    Parameters
    ----------
    dwell : int
        Frames each spiral point is held, in the ``dwell`` register's range. At 2 Mbit/s a
        frame is 10 µs, so the default 3 gives the paper's 30 µs between points.
    amp_x, amp_y : int
        Amplitude, unsigned Q1.15 (32768 = the table's full swing reaches the field edge).
    center_x, center_y : int
        Pattern centre in galvo units (32768 = field centre).
    x_range, y_range : tuple of int
        ``(first, last)`` ROM addresses walked by each axis, inclusive. The paper's
        ``(0, 127)`` and ``(1, 126)`` (the default, for the default 128-point table) make the
        ellipse precess.
    spiral_interp : int
        Between spiral points: 0 = hold, 1 = linear interpolation (the ``spiral_interp``
        register).
    run : bool
        Start sweeping out of reset.
    mode : str or :class:`Mode`
        Scan mode out of reset: ``"spiral"``, ``"raster"`` or ``"vector"``.
    """

    def __init__(self, *, dwell=_DEFAULT_MAP["dwell"].reset,
                 amp_x=_DEFAULT_MAP["amp_x"].reset, amp_y=_DEFAULT_MAP["amp_y"].reset,
                 center_x=_DEFAULT_MAP["center_x"].reset, center_y=_DEFAULT_MAP["center_y"].reset,
                 x_range=(_DEFAULT_MAP["x_first"].reset, _DEFAULT_MAP["x_last"].reset),
                 y_range=(_DEFAULT_MAP["y_first"].reset, _DEFAULT_MAP["y_last"].reset),
                 spiral_interp=_DEFAULT_MAP["spiral_interp"].reset,
                 run=True, mode=Mode(_DEFAULT_MAP["mode"].reset).label):
        self.mode = Mode.named(mode).label
        for name, value in (("dwell", dwell), ("amp_x", amp_x), ("amp_y", amp_y),
                            ("center_x", center_x), ("center_y", center_y),
                            ("spiral_interp", spiral_interp)):
            _check_register_value(name, value)
        self.dwell = dwell
        self.amp_x, self.amp_y = amp_x, amp_y
        self.center_x, self.center_y = center_x, center_y
        self.spiral_interp = spiral_interp
        self.x_range = tuple(x_range)
        self.y_range = tuple(y_range)
        self.run = bool(run)

    def register_resets(self):
        """Reset values of the registers these settings set."""
        return {
            "mode": Mode.named(self.mode).value, "run": int(self.run), "dwell": self.dwell,
            "amp_x": self.amp_x, "amp_y": self.amp_y,
            "center_x": self.center_x, "center_y": self.center_y,
            "x_first": self.x_range[0], "x_last": self.x_range[1],
            "y_first": self.y_range[0], "y_last": self.y_range[1],
            "spiral_interp": self.spiral_interp,
        }

    def check_ranges(self, points):
        """Raise if the address ranges do not fit a table of ``points`` samples."""
        for name, rng in (("x_range", self.x_range), ("y_range", self.y_range)):
            if len(rng) != 2 or not all(isinstance(v, int) for v in rng) or \
                    not 0 <= rng[0] <= rng[1] < points:
                raise ValueError(f"{name} must be (first, last) with 0 <= first <= last < "
                                 f"{points} (the table size), not {rng!r}")
