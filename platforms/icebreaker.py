"""iCEBreaker (Lattice iCE40UP5K, 12 MHz): the galvoscan system with the XY2-100 bus on PMOD1A.

PMOD1A pin → signal (3.3 V LVCMOS outputs; an RS-422 driver such as an AM26LV31 or
SN75C1168 makes the differential pairs the scan head expects):

====  ========  =========
PMOD  FPGA pin  signal
====  ========  =========
1     4         xy2_clk
2     2         xy2_sync
3     47        xy2_x
4     45        xy2_y
5, 11 —         GND
6, 12 —         3.3 V
====  ========  =========

The host link: the board's USB serial port (FTDI channel B, FPGA pins 6 = rx, 9 = tx), and an
SPI target on PMOD1B in the usual PMOD SPI order:

====  ========  ===========
PMOD  FPGA pin  signal
====  ========  ===========
1     43        spi_cs_n (pulled up: a loose header reads as deselected)
2     38        spi_copi
3     34        spi_cipo
4     31        spi_sck
====  ========  ===========

The red LED lights once frames are going out. The four bus lines leave through the I/O cells'
output flip-flops, one system clock after the PHY's own registers.
"""

from amaranth.build import Attrs, Pins, Resource, Subsignal
from amaranth.hdl import Elaboratable, Module, Signal
from amaranth.lib import io
from amaranth_boards.icebreaker import ICEBreakerPlatform

from ..gateware.top import GalvoScanTop


__all__ = ["ICEBreakerScanner", "icebreaker_platform", "XY2_PMOD_PINS", "SPI_PMOD_PINS"]


#: PMOD1A pin of each XY2-100 signal (the README's table is checked against these).
XY2_PMOD_PINS = {"clk": 1, "sync": 2, "x": 3, "y": 4}
#: PMOD1B pin of each host SPI signal, and its direction.
SPI_PMOD_PINS = {"cs_n": (1, "i"), "copi": (2, "i"), "cipo": (3, "o"), "sck": (4, "i")}


def icebreaker_platform():
    """The iCEBreaker platform with the XY2-100 bus added as a resource."""
    platform = ICEBreakerPlatform()
    platform.add_resources([
        Resource("xy2", 0,
                 *(Subsignal(name, Pins(str(pin), dir="o", conn=("pmod", 0)))
                   for name, pin in XY2_PMOD_PINS.items()),
                 Attrs(IO_STANDARD="SB_LVCMOS")),
        Resource("host_spi", 0,
                 *(Subsignal(name, Pins(str(pin), dir=direction, conn=("pmod", 1)),
                             Attrs(PULLUP=1) if name == "cs_n" else Attrs())
                   for name, (pin, direction) in SPI_PMOD_PINS.items()),
                 Attrs(IO_STANDARD="SB_LVCMOS")),
    ])
    return platform


class ICEBreakerScanner(Elaboratable):
    """The system top on the iCEBreaker's 12 MHz clock.

    Parameters
    ----------
    table, settings
        As for :class:`~galvoscan.gateware.top.GalvoScanTop`.
    """

    def __init__(self, *, table=None, settings=None):
        self.table = table
        self.settings = settings

    def elaborate(self, platform):
        m = Module()
        m.submodules.scanner = scanner = GalvoScanTop(
            clk_freq=int(platform.default_clk_frequency), table=self.table,
            settings=self.settings)

        # All four lines leave through the I/O cells' own flip-flops, so they change within
        # the pads' skew of each other, whatever the placement.
        xy2 = platform.request("xy2", 0, dir="-")
        for name in XY2_PMOD_PINS:
            m.submodules[f"xy2_{name}_pad"] = pad = io.FFBuffer("o", getattr(xy2, name))
            m.d.comb += pad.o.eq(getattr(scanner, f"xy2_{name}"))

        # Host link. The cores synchronise their inputs, so plain buffers here.
        uart = platform.request("uart", 0, dir="-")
        spi = platform.request("host_spi", 0, dir="-")
        inputs = {"uart_rx": uart.rx, "spi_sck": spi.sck, "spi_cs_n": spi.cs_n,
                  "spi_copi": spi.copi}
        outputs = {"uart_tx": uart.tx, "spi_cipo": spi.cipo}
        for name, port in inputs.items():
            m.submodules[f"{name}_pad"] = pad = io.Buffer("i", port)
            m.d.comb += getattr(scanner, name).eq(pad.i)
        for name, port in outputs.items():
            m.submodules[f"{name}_pad"] = pad = io.Buffer("o", port)
            m.d.comb += pad.o.eq(getattr(scanner, name))

        running = Signal()
        with m.If(scanner.xy2_sync):
            m.d.sync += running.eq(1)
        m.submodules.led_pad = led = io.Buffer("o", platform.request("led_r", 0, dir="-"))
        m.d.comb += led.o.eq(running)
        return m
