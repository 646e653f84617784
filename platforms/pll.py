"""The iCE40 PLL: a faster system clock from the board's crystal (``galvoscan build --clock``).

The sysCLOCK PLL makes ``f_out = f_in × (DIVF + 1) / ((DIVR + 1) × 2^DIVQ)`` within limits
(Lattice TN1251): the phase detector runs at 10 … 133 MHz, the VCO at 533 … 1066 MHz, the
output at 16 … 275 MHz. :func:`pll_settings` searches all divider settings for the closest
output, the way icepll does.
"""

from dataclasses import dataclass

from amaranth.hdl import Elaboratable, Instance, Module, Signal
from amaranth.lib.cdc import ResetSynchronizer


__all__ = ["PLLSettings", "pll_settings", "ICE40PLL"]


@dataclass(frozen=True)
class PLLSettings:
    divr: int
    divf: int
    divq: int
    filter_range: int
    f_in: float
    f_out: float            # the frequency these dividers give, Hz

    @property
    def f_pfd(self):
        return self.f_in / (self.divr + 1)

    @property
    def f_vco(self):
        return self.f_pfd * (self.divf + 1)


def _filter_range(f_pfd):
    # Loop filter setting by phase detector frequency (as icepll chooses it).
    for limit, value in ((17e6, 1), (26e6, 2), (44e6, 3), (66e6, 4), (101e6, 5)):
        if f_pfd < limit:
            return value
    return 6


def pll_settings(f_in, f_out, *, tolerance=0.0):
    """The divider settings that come closest to ``f_out`` from ``f_in`` (both Hz).

    Raises ``ValueError`` if ``f_out`` is outside the PLL's range, or no setting is within
    ``tolerance`` (a fraction; 0 = exactly) of it.
    """
    if not 16e6 <= f_out <= 275e6:
        raise ValueError(f"the iCE40 PLL makes 16 to 275 MHz, not {f_out / 1e6:g} MHz")
    if not 10e6 <= f_in <= 133e6:
        raise ValueError(f"the iCE40 PLL takes 10 to 133 MHz in, not {f_in / 1e6:g} MHz")
    best = None
    for divr in range(16):
        f_pfd = f_in / (divr + 1)
        if not 10e6 <= f_pfd <= 133e6:
            continue
        for divf in range(128):
            f_vco = f_pfd * (divf + 1)
            if not 533e6 <= f_vco <= 1066e6:
                continue
            for divq in range(1, 7):
                out = f_vco / 2 ** divq
                if best is None or abs(out - f_out) < abs(best.f_out - f_out):
                    best = PLLSettings(divr, divf, divq, _filter_range(f_pfd), f_in, out)
    if best is None or abs(best.f_out - f_out) > tolerance * f_out + 1e-3:
        got = f"; the closest is {best.f_out / 1e6:.4f} MHz" if best else ""
        raise ValueError(f"the PLL cannot make {f_out / 1e6:g} MHz from {f_in / 1e6:g} MHz"
                         f"{got}")
    return best


class ICE40PLL(Elaboratable):
    """Drives a clock domain from the PLL on the crystal's input pad.

    The module above defines the domain (Amaranth wants a domain defined where it is used, or
    above); this one drives its clock and holds its reset until the PLL has locked. The build
    gives nextpnr the frequency to meet (``--freq``: a constraint on the domain's clock signal
    names a net that synthesis renames).

    Parameters
    ----------
    pad : the crystal's input pin, requested with ``dir="-"``
    settings : :class:`PLLSettings`
    domain : :class:`~amaranth.hdl.ClockDomain`
    """

    def __init__(self, pad, settings, domain):
        self.pad = pad
        self.settings = settings
        self.domain = domain

    def elaborate(self, platform):
        m = Module()
        locked = Signal()
        s = self.settings
        m.submodules.pll = Instance(
            "SB_PLL40_PAD",
            p_FEEDBACK_PATH="SIMPLE",
            p_DIVR=s.divr, p_DIVF=s.divf, p_DIVQ=s.divq, p_FILTER_RANGE=s.filter_range,
            i_PACKAGEPIN=self.pad.io,
            i_RESETB=1, i_BYPASS=0,
            o_PLLOUTGLOBAL=self.domain.clk,
            o_LOCK=locked)
        m.submodules.reset_sync = ResetSynchronizer(~locked, domain=self.domain.name)
        return m
