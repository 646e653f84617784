"""iCEstick (Lattice iCE40HX1K, 12 MHz): the largest galvoscan that fits 1280 logic cells.

The HX1K has no DSP blocks and a quarter of the UP5K's logic, so this build is the spiral
scanner under host control and nothing else: spiral mode, the scale stage with serial
(shift-and-add) multipliers, the host link over the on-board FTDI serial port (channel B,
115 200 baud, one reply at a time), **no laser controller** (drive the laser from another controller, gated by the
scan head's own status if you must), no SPI, no raster or vector mode, no distortion
correction. ``galvoscan build --board icestick`` reports what it uses.

The XY2-100 bus is on the PMOD header J2, in the same order as on the iCEBreaker (an RS-422
driver such as an AM26LV31 makes the pairs):

====  ========  =========
PMOD  FPGA pin  signal
====  ========  =========
1     78        xy2_clk
2     79        xy2_sync
3     80        xy2_x
4     81        xy2_y
5, 11 —         GND
6, 12 —         3.3 V
====  ========  =========

The green LED (D5) lights once frames are going out.
"""

from amaranth.build import Attrs, Pins, Resource, Subsignal
from amaranth.hdl import Elaboratable, Module, Signal
from amaranth.lib import io
from amaranth_boards.icestick import ICEStickPlatform

from ..gateware.clocking import DEFAULT_BAUD, check_clocks
from ..gateware.build_config import BuildConfig
from ..gateware.top import GalvoScanTop
from .icebreaker import XY2_PMOD_PINS


__all__ = ["ICEStickScanner", "icestick_platform", "icestick_check", "ICESTICK_MODES",
           "ICESTICK_CRYSTAL_HZ"]


#: The scan modes that fit.
ICESTICK_MODES = ("spiral",)

#: The iCEstick's oscillator.
ICESTICK_CRYSTAL_HZ = 12_000_000


def icestick_platform():
    """The iCEstick platform with the XY2-100 bus on PMOD J2."""
    platform = ICEStickPlatform()
    platform.add_resources([
        Resource("xy2", 0,
                 *(Subsignal(name, Pins(str(pin), dir="o", conn=("pmod", 0)))
                   for name, pin in XY2_PMOD_PINS.items()),
                 Attrs(IO_STANDARD="SB_LVCMOS")),
    ])
    return platform


def icestick_clock(clock, bit_rate, baud=DEFAULT_BAUD):
    """The iCEstick runs on its 12 MHz oscillator (no PLL option here: its HX1K build has no
    timing to spare for one and no use for one)."""
    if clock not in (None, ICESTICK_CRYSTAL_HZ):
        raise ValueError("the iCEstick build runs on its 12 MHz oscillator only")
    check_clocks(ICESTICK_CRYSTAL_HZ, bit_rate, baud)
    return ICESTICK_CRYSTAL_HZ, None


def icestick_check(*, modes=None, correction=None, clock=None, bit_rate=2_000_000,
                   baud=DEFAULT_BAUD):
    """Raise ``ValueError`` for anything the iCEstick build cannot hold: checked before any
    build starts."""
    if modes is not None and tuple(modes) != ICESTICK_MODES:
        raise ValueError(f"the iCEstick holds the spiral mode only, not {', '.join(modes)}")
    if correction is not None and not (isinstance(correction, str) and
                                       correction == "identity"):
        raise ValueError("the iCEstick has no room for the correction stage: build without "
                         "a correction table")
    return icestick_clock(clock, bit_rate, baud)


class ICEStickScanner(Elaboratable):
    """The spiral scanner on the iCEstick (see the module).

    Parameters
    ----------
    config : :class:`~galvoscan.gateware.build_config.BuildConfig`
        The build (:meth:`config` makes one that fits the HX1K).
    table, settings
        As for :class:`~galvoscan.gateware.top.GalvoScanTop`.
    """

    def __init__(self, config, *, table=None, settings=None):
        self.config = config
        self.table = table
        self.settings = settings

    @staticmethod
    def config(*, modes=None, correction="identity", clock=None, bit_rate=2_000_000,
               baud=DEFAULT_BAUD, wobble=False, interpolation=False, delays=False,
               player=False):
        """The :class:`~galvoscan.gateware.build_config.BuildConfig` of an iCEstick
        bitstream, taking the iCEBreaker's options so that one call serves both; anything
        but spiral mode without correction on the 12 MHz oscillator raises ``ValueError``
        (checked before anything is built). ``correction`` may be ``"identity"`` (the
        default table, which the build leaves out) or None."""
        if wobble:
            raise ValueError("the iCEstick has no room for the wobble stage")
        if interpolation:
            raise ValueError("the iCEstick has no room for the spiral's interpolator")
        clk_freq, _ = icestick_check(modes=modes, correction=correction, clock=clock,
                                     bit_rate=bit_rate, baud=baud)
        if delays:
            raise ValueError("the delays are vector mode's: build them with the vector mode")
        if player:
            raise ValueError("the job player reads the iCEBreaker's flash: build it for the "
                             "iCEBreaker")
        return BuildConfig(modes=ICESTICK_MODES, clk_freq=clk_freq, bit_rate=bit_rate,
                           baud=baud, correction=False, multiplier="serial", links=("uart",),
                           laser=False, register_reads="mux", spiral_interpolation=False)

    def elaborate(self, platform):
        m = Module()
        m.submodules.scanner = scanner = GalvoScanTop(self.config, table=self.table,
                                                      settings=self.settings)

        xy2 = platform.request("xy2", 0, dir="-")
        for name in XY2_PMOD_PINS:
            m.submodules[f"xy2_{name}_pad"] = pad = io.FFBuffer("o", getattr(xy2, name))
            m.d.comb += pad.o.eq(getattr(scanner, f"xy2_{name}"))

        uart = platform.request("uart", 0, dir="-")
        m.submodules.uart_rx_pad = rx = io.Buffer("i", uart.rx)
        m.submodules.uart_tx_pad = tx = io.Buffer("o", uart.tx)
        m.d.comb += [scanner.uart_rx.eq(rx.i), tx.o.eq(scanner.uart_tx)]

        running = Signal()
        with m.If(scanner.xy2_sync):
            m.d.sync += running.eq(1)
        m.submodules.led_pad = led = io.Buffer("o", platform.request("led", 4, dir="-"))
        m.d.comb += led.o.eq(running)
        return m
