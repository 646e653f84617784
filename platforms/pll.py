"""The iCE40 PLL: a faster system clock from the board's crystal (``galvoscan build --clock``).

The sysCLOCK PLL makes ``f_out = f_in × (DIVF + 1) / ((DIVR + 1) × 2^DIVQ)`` within limits
(Lattice TN1251): the phase detector runs at 10 … 133 MHz, the VCO at 533 … 1066 MHz, the
output at 16 … 275 MHz. :func:`pll_settings` searches all divider settings for the closest
output, the way icepll does.
"""

from dataclasses import dataclass

from amaranth.hdl import Elaboratable, Instance, Module, Signal
from amaranth.lib.cdc import ResetSynchronizer


__all__ = ["PLLSettings", "pll_settings", "ICE40PLL", "ECP5PLLSettings", "ecp5_pll_settings",
           "ECP5PLL"]


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


@dataclass(frozen=True)
class ECP5PLLSettings:
    """The EHXPLLL's dividers for one output (Lattice TN1263, "ECP5 sysCLOCK PLL/DLL Design
    and Usage Guide"): the reference divider ``clki_div`` feeds the phase detector, the VCO runs
    at ``f_pfd × clkfb_div × clkop_div`` (the feedback taken from CLKOP), and the system clock
    is CLKOS, the VCO divided by ``clkos_div``."""
    clki_div: int
    clkfb_div: int
    clkop_div: int
    clkos_div: int
    f_in: float
    f_out: float            # the frequency these dividers give (CLKOS), Hz

    @property
    def f_pfd(self):
        return self.f_in / self.clki_div

    @property
    def f_vco(self):
        return self.f_pfd * self.clkfb_div * self.clkop_div

    @property
    def f_clkop(self):
        return self.f_vco / self.clkop_div


def ecp5_pll_settings(f_in, f_out):
    """The EHXPLLL dividers that make exactly ``f_out`` from ``f_in`` (both Hz), the VCO
    nearest 600 MHz (the middle of its range, where ecppll puts it too).

    The limits (ECP5 data sheet DS1044, sysCLOCK PLL timing): phase detector 3.125 … 400 MHz,
    VCO 400 … 800 MHz, outputs 3.125 … 400 MHz; dividers 1 … 128, feedback 1 … 80. Raises
    ``ValueError`` if ``f_out`` is outside them or no setting makes it exactly.
    """
    if not 3.125e6 <= f_out <= 400e6:
        raise ValueError(f"the ECP5 PLL makes 3.125 to 400 MHz, not {f_out / 1e6:g} MHz")
    best = None
    for clki_div in range(1, 129):
        f_pfd = f_in / clki_div
        if f_pfd < 3.125e6:
            break
        if f_pfd > 400e6:
            continue
        for clkfb_div in range(1, 81):
            for clkop_div in range(1, 129):
                f_vco = f_pfd * clkfb_div * clkop_div
                if f_vco > 800e6:
                    break
                if f_vco < 400e6 or not 3.125e6 <= f_vco / clkop_div <= 400e6:
                    continue
                clkos_div = round(f_vco / f_out)
                if not 1 <= clkos_div <= 128 or abs(f_vco / clkos_div - f_out) > 1e-3:
                    continue
                if best is None or abs(f_vco - 600e6) < abs(best.f_vco - 600e6):
                    best = ECP5PLLSettings(clki_div, clkfb_div, clkop_div, clkos_div, f_in,
                                           f_vco / clkos_div)
    if best is None:
        raise ValueError(f"the ECP5 PLL cannot make exactly {f_out / 1e6:g} MHz from "
                         f"{f_in / 1e6:g} MHz")
    return best


class ECP5PLL(Elaboratable):
    """Drives a clock domain from an EHXPLLL on the crystal's clock (:class:`ICE40PLL`'s
    counterpart): the domain's clock is CLKOS, its reset held until the PLL has locked.

    Parameters
    ----------
    clk_in : Signal, the crystal's clock (from its input buffer)
    settings : :class:`ECP5PLLSettings`
    domain : :class:`~amaranth.hdl.ClockDomain`
    """

    def __init__(self, clk_in, settings, domain):
        self.clk_in = clk_in
        self.settings = settings
        self.domain = domain

    def elaborate(self, platform):
        m = Module()
        locked = Signal()
        feedback = Signal()
        s = self.settings
        m.submodules.pll = Instance(
            "EHXPLLL",
            # nextpnr derives the output's timing constraint from these (in MHz).
            a_FREQUENCY_PIN_CLKI=f"{s.f_in / 1e6:g}",
            a_FREQUENCY_PIN_CLKOS=f"{s.f_out / 1e6:g}",
            # The loop filter as ecppll and Lattice's tools set it for these VCO rates.
            a_ICP_CURRENT="12", a_LPF_RESISTOR="8", a_MFG_ENABLE_FILTEROPAMP="1",
            a_MFG_GMCREF_SEL="2",
            p_PLLRST_ENA="DISABLED", p_INTFB_WAKE="DISABLED", p_STDBY_ENABLE="DISABLED",
            p_DPHASE_SOURCE="DISABLED", p_OUTDIVIDER_MUXA="DIVA", p_OUTDIVIDER_MUXB="DIVB",
            p_FEEDBK_PATH="CLKOP",
            p_CLKI_DIV=s.clki_div, p_CLKFB_DIV=s.clkfb_div,
            p_CLKOP_ENABLE="ENABLED", p_CLKOP_DIV=s.clkop_div,
            p_CLKOP_CPHASE=s.clkop_div - 1, p_CLKOP_FPHASE=0,
            p_CLKOS_ENABLE="ENABLED", p_CLKOS_DIV=s.clkos_div,
            p_CLKOS_CPHASE=s.clkos_div - 1, p_CLKOS_FPHASE=0,
            i_CLKI=self.clk_in, i_CLKFB=feedback, i_RST=0, i_STDBY=0,
            i_PHASESEL0=0, i_PHASESEL1=0, i_PHASEDIR=1, i_PHASESTEP=1, i_PHASELOADREG=1,
            i_PLLWAKESYNC=0, i_ENCLKOP=0,
            o_CLKOP=feedback, o_CLKOS=self.domain.clk, o_LOCK=locked)
        m.submodules.reset_sync = ResetSynchronizer(~locked, domain=self.domain.name)
        return m
