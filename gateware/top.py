"""The galvoscan system, independent of any board (SPEC §3).

Its ports are plain one-bit wires with fixed names, so the exported Verilog drops into other
designs: ``clk``, ``rst`` (synchronous, active high) and ``xy2_clk``, ``xy2_sync``, ``xy2_x``,
``xy2_y``.
"""

from amaranth.hdl import Module
from amaranth.lib import wiring
from amaranth.lib.wiring import Out, connect

from .field.scale import GAIN_ONE, ScaleOffset
from .phy.xy2_100 import XY2Transmitter, clocks_per_bit
from .points import FIELD_CENTRE
from .sources.spiral import SpiralSequencer
from .sources.spiral_table import SpiralTable


__all__ = ["GalvoScanTop", "ScanSettings"]


def _check_int(name, value, low, high, unit=""):
    if not isinstance(value, int) or isinstance(value, bool) or not low <= value <= high:
        raise ValueError(f"{name} must be an integer from {low} to {high}{unit}, not {value!r}")


class ScanSettings:
    """The scan settings the system starts with: what the host-writable registers reset to.

    Parameters
    ----------
    dwell : int
        Frames each spiral point is held, 1 … 65535. At 2 Mbit/s a frame is 10 µs, so the
        default 3 gives the paper's 30 µs between points.
    gain_x, gain_y : int
        Amplitude, unsigned Q1.15 (32768 = the table's full swing reaches the field edge).
    centre_x, centre_y : int
        Pattern centre in galvo units (32768 = field centre).
    x_range, y_range : tuple of int
        ``(first, last)`` ROM addresses walked by each axis, inclusive. The paper's
        ``(0, 127)`` and ``(1, 126)`` make the ellipse precess.
    run : bool
        Start sweeping out of reset.
    """

    def __init__(self, *, dwell=3, gain_x=GAIN_ONE, gain_y=GAIN_ONE,
                 centre_x=FIELD_CENTRE, centre_y=FIELD_CENTRE,
                 x_range=(0, 127), y_range=(1, 126), run=True):
        _check_int("dwell", dwell, 1, 0xFFFF, " frames")
        for name, value in (("gain_x", gain_x), ("gain_y", gain_y)):
            _check_int(name, value, 0, 0xFFFF, " (Q1.15, 32768 = 1.0)")
        for name, value in (("centre_x", centre_x), ("centre_y", centre_y)):
            _check_int(name, value, 0, 0xFFFF, " galvo units")
        self.dwell = dwell
        self.gain_x, self.gain_y = gain_x, gain_y
        self.centre_x, self.centre_y = centre_x, centre_y
        self.x_range = tuple(x_range)
        self.y_range = tuple(y_range)
        self.run = bool(run)

    def check_ranges(self, points):
        """Raise if the address ranges do not fit a table of ``points`` samples."""
        for name, rng in (("x_range", self.x_range), ("y_range", self.y_range)):
            if len(rng) != 2 or not all(isinstance(v, int) for v in rng) or \
                    not 0 <= rng[0] <= rng[1] < points:
                raise ValueError(f"{name} must be (first, last) with 0 <= first <= last < "
                                 f"{points} (the table size), not {rng!r}")


class GalvoScanTop(wiring.Component):
    """Stand-alone spiral scanner: spiral sequencer → scale/offset → XY2-100 transmitter.

    Parameters
    ----------
    clk_freq : int or float
        Frequency of ``clk`` in Hz.
    bit_rate : int or float
        XY2 bit rate in Hz (2 MHz: XY2-100). ``clk_freq / bit_rate`` must be an even integer.
    table : :class:`SpiralTable`
        Spiral angle tables (default: 128 Gaussian-sampled points).
    settings : :class:`ScanSettings`
        Dwell, gain, centre, address ranges and run at reset.

    Interface attributes
    --------------------
    xy2_clk, xy2_sync, xy2_x, xy2_y : ``Out(1)``
        XY2-100 bus to the scan head, single-ended (add an RS-422 driver).
    """

    xy2_clk: Out(1)
    xy2_sync: Out(1)
    xy2_x: Out(1)
    xy2_y: Out(1)

    def __init__(self, *, clk_freq, bit_rate=2_000_000, table=None, settings=None):
        self.table = SpiralTable() if table is None else table
        self.settings = ScanSettings() if settings is None else settings
        if not isinstance(self.table, SpiralTable):
            raise TypeError(f"table must be a SpiralTable, not {self.table!r}")
        if not isinstance(self.settings, ScanSettings):
            raise TypeError(f"settings must be ScanSettings, not {self.settings!r}")
        self.settings.check_ranges(self.table.points)
        # Checked here so that a bad clock shows at construction, not deep in elaboration.
        clocks_per_bit(clk_freq, bit_rate)
        self.clk_freq = clk_freq
        self.bit_rate = bit_rate
        super().__init__()

    def elaborate(self, platform):
        m = Module()
        settings = self.settings

        m.submodules.spiral = spiral = SpiralSequencer(self.table)
        m.submodules.scale = scale = ScaleOffset()
        m.submodules.phy = phy = XY2Transmitter(clk_freq=self.clk_freq, bit_rate=self.bit_rate)

        # The register file will drive these; until then they are the settings at reset.
        m.d.comb += [
            spiral.run.eq(settings.run),
            spiral.dwell.eq(settings.dwell),
            spiral.x_first.eq(settings.x_range[0]),
            spiral.x_last.eq(settings.x_range[1]),
            spiral.y_first.eq(settings.y_range[0]),
            spiral.y_last.eq(settings.y_range[1]),
            spiral.frame_strobe.eq(phy.frame_strobe),
            scale.gain_x.eq(settings.gain_x),
            scale.gain_y.eq(settings.gain_y),
            scale.centre_x.eq(settings.centre_x),
            scale.centre_y.eq(settings.centre_y),
        ]
        connect(m, spiral.points, scale.offsets)
        connect(m, scale.positions, phy.position)

        m.d.comb += [
            self.xy2_clk.eq(phy.xy2_clk),
            self.xy2_sync.eq(phy.xy2_sync),
            self.xy2_x.eq(phy.xy2_x),
            self.xy2_y.eq(phy.xy2_y),
        ]
        return m
