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

The fiber laser's DB25 signals (3.3 V here: the laser wants 5 V TTL, so buffer them with a
74HCT245 or 74AHCT125 run from 5 V, whose inputs take 3.3 V logic; remove the iCEBreaker's
button/LED snap-off board from PMOD2):

=============  ========  =================  =========
PMOD pin       FPGA pin  signal             DB25 pin
=============  ========  =================  =========
PMOD2 1-4      27 25 21 19  laser_power[0:4]   1-4
PMOD2 7-10     26 23 20 18  laser_power[4:8]   5-8
PMOD1A 7       3         laser_latch        9
PMOD1A 8       48        laser_mo           18
PMOD1A 9       46        laser_am           19
PMOD1A 10      44        laser_prr          20
PMOD1B 8       36        laser_enable       (the buffers' output enable; pull it down)
PMOD1B 10      28        laser_guide        22 on IPG (differs between lasers; pull it down)
PMOD1B 7       42        interlock_open     (loop; pulled up: a broken loop reads open)
PMOD1B 9       32        laser_alarm[0]     (laser's alarm outputs, OR-ed: 1 = alarm; pulled up)
=============  ========  =================  =========

The gateware treats every alarm input alike (any one active is an alarm), so a laser's several
alarm outputs share the one input through a wired OR (open-collector outputs in parallel, or
a diode OR), and the last PMOD pin is left for the guide laser.

Before and while the FPGA configures, its pins float with weak pull-ups: the buffers must be
off then (``laser_enable`` pulled down, so the buffers' outputs are disabled) and the laser
lines held low by pull-downs behind them (README "Wiring").

A stand-alone build (``galvoscan build --preset marker``: the job player, no SPI link) takes the
four SPI pins of PMOD1B for the machine's lines, and reads the job from the board's own
configuration flash after configuration:

====  ========  ===========
PMOD  FPGA pin  signal
====  ========  ===========
1     43        start_n (foot switch or PLC to GND; pulled up); the board's button starts too
2     38        busy (a job is being checked or played)
3     34        ready (armed and past the MO lead: marking emits)
4     31        xy2_status (the head's STATUS line through an RS-422 receiver), with
                ``--head-status`` (which does not fit beside the correction stage)
====  ========  ===========

The green LED lights while the player is busy and blinks after it refused an image.

The red LED lights once frames are going out. The four bus lines and every laser line leave
through the I/O cells' output flip-flops, one system clock after the core's own logic.
"""

from amaranth.build import Attrs, Pins, Resource, Subsignal
from amaranth.hdl import ClockDomain, Elaboratable, Module
from amaranth_boards.icebreaker import ICEBreakerPlatform

from ..gateware.clocking import DEFAULT_BAUD, check_clocks
from ..gateware.build_config import LINKS, MODES, BuildConfig
from ..gateware.top import GalvoScanTop
from .pads import (player_pins, plain_inputs, plain_outputs, registered_outputs,
                   running_led)
from .pll import ICE40PLL, pll_settings


#: The iCEBreaker's crystal.
CRYSTAL_HZ = 12_000_000

__all__ = ["CRYSTAL_HZ", "ICEBreakerScanner", "system_clock", "icebreaker_platform", "XY2_PMOD_PINS", "SPI_PMOD_PINS",
           "LASER_PMOD_PINS", "INTERLOCK_PMOD_PIN", "ALARM_PMOD_PINS",
           "MACHINE_PMOD_PINS", "HEAD_STATUS_PMOD_PIN"]


#: PMOD1A pin of each XY2-100 signal (the README's table is checked against these).
XY2_PMOD_PINS = {"clk": 1, "sync": 2, "x": 3, "y": 4}
#: PMOD1B pin of each host SPI signal, and its direction.
SPI_PMOD_PINS = {"cs_n": (1, "i"), "copi": (2, "i"), "cipo": (3, "o"), "sck": (4, "i")}
#: Laser signals: name → (PMOD number, PMOD pins, DB25 pins).
LASER_PMOD_PINS = {
    "power": (2, "1 2 3 4 7 8 9 10", "1-8"),
    "latch": (0, "7", "9"),
    "mo": (0, "8", "18"),
    "am": (0, "9", "19"),
    "prr": (0, "10", "20"),
    "enable": (1, "8", "-"),     # to the buffers' output enable, not to the DB25
    # The guide (red pointer) laser: on while disarmed when asked, so through a buffer of its
    # own that laser_enable does not gate; the DB25 pin differs between lasers.
    "guide": (1, "10", "22"),
}
#: The stand-alone build's machine lines on PMOD1B (the SPI link's pins): name → (pin,
#: direction).
MACHINE_PMOD_PINS = {"start_n": (1, "i"), "busy": (2, "o"), "ready": (3, "o")}
#: The interlock loop input: (PMOD number, PMOD pin).
INTERLOCK_PMOD_PIN = (1, "7")
#: The laser alarm inputs: (PMOD number, PMOD pins); as many alarms as pins.
ALARM_PMOD_PINS = (1, "9")
#: The scan head's STATUS line (an RS-422 receiver's output): (PMOD number, PMOD pin), the SPI
#: link's SCK, free in the job player's build (its machine lines take the other three).
HEAD_STATUS_PMOD_PIN = (1, "4")


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
        Resource("laser", 0,
                 *(Subsignal(name, Pins(pins, dir="o", conn=("pmod", pmod)))
                   for name, (pmod, pins, _) in LASER_PMOD_PINS.items()),
                 Attrs(IO_STANDARD="SB_LVCMOS")),
        Resource("interlock", 0,
                 Pins(INTERLOCK_PMOD_PIN[1], dir="i", conn=("pmod", INTERLOCK_PMOD_PIN[0])),
                 Attrs(IO_STANDARD="SB_LVCMOS", PULLUP=1)),
        # The stand-alone build's: start pulled up (an open switch is no press).
        Resource("machine", 0,
                 *(Subsignal(name, Pins(str(pin), dir=direction, conn=("pmod", 1)),
                             Attrs(PULLUP=1) if direction == "i" else Attrs())
                   for name, (pin, direction) in MACHINE_PMOD_PINS.items()),
                 Attrs(IO_STANDARD="SB_LVCMOS")),
        # Pulled up: an unconnected alarm input reads as an alarm, and the laser stays off.
        Resource("head_status", 0,
                 Pins(HEAD_STATUS_PMOD_PIN[1], dir="i", conn=("pmod", HEAD_STATUS_PMOD_PIN[0])),
                 Attrs(IO_STANDARD="SB_LVCMOS")),
        Resource("laser_alarm", 0,
                 Pins(ALARM_PMOD_PINS[1], dir="i", conn=("pmod", ALARM_PMOD_PINS[0])),
                 Attrs(IO_STANDARD="SB_LVCMOS", PULLUP=1)),
    ])
    return platform


def system_clock(clock, bit_rate, baud=DEFAULT_BAUD):
    """``(clk_freq, pll_settings or None)`` for a requested system clock (None: the crystal).

    Raises ``ValueError`` if the PLL cannot make ``clock`` or
    :func:`~galvoscan.gateware.clocking.check_clocks` refuses it (the XY2 bit rate or the
    UART baud rate); called before anything is built, so the error comes first.
    """
    pll = None if clock is None else pll_settings(CRYSTAL_HZ, clock)
    clk_freq = CRYSTAL_HZ if clock is None else clock
    check_clocks(clk_freq, bit_rate, baud)
    return clk_freq, pll


class ICEBreakerScanner(Elaboratable):
    """The system top on the iCEBreaker (crystal 12 MHz, or a clock from its PLL).

    Parameters
    ----------
    config : :class:`~galvoscan.gateware.build_config.BuildConfig`
        The build (:meth:`config` makes one that fits the UP5K).
    table, settings, correction
        As for :class:`~galvoscan.gateware.top.GalvoScanTop` (``correction`` ``"identity"``:
        the default identity table).
    """

    def __init__(self, config, *, table=None, settings=None, correction="identity"):
        self.config = config
        self.table = table
        self.settings = settings
        self.correction = correction
        self.clk_freq, self.pll = system_clock(
            None if config.clk_freq == CRYSTAL_HZ else config.clk_freq, config.bit_rate,
            config.baud)

    @staticmethod
    def config(*, modes=None, correction="identity", clock=None, bit_rate=2_000_000,
               baud=DEFAULT_BAUD, wobble=False, interpolation=False, delays=False,
               pixel_lines=False, player=False, head_status=False):
        """The :class:`~galvoscan.gateware.build_config.BuildConfig` of an iCEBreaker
        bitstream with these options; ``ValueError`` for one the UP5K cannot hold (checked
        before anything is built).

        ``modes`` None: all three; ``correction``: the table the correction stage starts with
        (None: no correction stage); ``clock``: the
        system clock in Hz (None: the 12 MHz crystal; else from the PLL, which must reach it
        exactly); ``interpolation`` the spiral's interpolator and ``delays`` vector mode's RTC
        delays (off by default: beside all three modes neither fits the UP5K); ``player`` the
        job player (the flash read after configuration, the machine's lines on PMOD1B in place
        of the SPI link); ``pixel_lines`` vector mode's pixel lines (with the delays, and
        beside one scan mode at most: vector alone fits).
        """
        clk_freq, _ = system_clock(None if clock == CRYSTAL_HZ else clock, bit_rate, baud)
        modes = MODES if modes is None else tuple(modes)
        if wobble and len(set(modes)) == len(MODES):
            raise ValueError("the wobble stage does not fit the UP5K beside all three scan "
                             "modes: leave one out with --modes (spiral,vector fits)")
        if delays and "vector" not in modes:
            raise ValueError("the delays are vector mode's: build them with the vector mode")
        if delays and len(set(modes)) == len(MODES):
            raise ValueError("vector mode's delays do not fit the UP5K beside all three scan "
                             "modes: leave one out with --modes (spiral,vector fits)")
        if interpolation and len(set(modes)) == len(MODES):
            raise ValueError("the spiral's interpolator does not fit the UP5K beside all three "
                             "scan modes: leave one out with --modes (spiral,vector fits)")
        if interpolation and "spiral" not in modes:
            raise ValueError("the interpolator is the spiral's: build it with the spiral mode")
        if pixel_lines and not (delays and "vector" in modes):
            raise ValueError("pixel lines are vector mode's, with its delays: build them with "
                             "--modes vector and --delays")
        if pixel_lines and len(set(modes)) > 1:
            raise ValueError("pixel lines do not fit the UP5K beside another scan mode: build "
                             "them with --modes vector")
        if pixel_lines and player:
            raise ValueError("pixel lines do not fit the UP5K beside the job player")
        if player and "vector" not in modes:
            raise ValueError("the job player plays vector jobs: build it with the vector mode")
        if head_status and not player:
            raise ValueError("the head's STATUS line takes PMOD1B pin 4, the SPI link's SCK: "
                             "build it with the job player (--preset marker), whose machine "
                             "lines leave that pin free")
        if head_status and correction is not None:
            raise ValueError("the head status receiver does not fit the UP5K beside the "
                             "marker's correction stage (5,274 of 5,280 logic cells): build it "
                             "with --no-correction")
        return BuildConfig(
            modes=modes, clk_freq=clk_freq, bit_rate=bit_rate, baud=baud,
            correction=correction is not None, laser_alarms=len(ALARM_PMOD_PINS[1].split()),
            wobble=wobble, spiral_interpolation=interpolation, vector_delays=delays,
            pixel_lines=pixel_lines,
            # The SPI link's pins are the player's machine lines.
            player=player, links=("uart",) if player else LINKS, head_status=head_status)

    def elaborate(self, platform):
        m = Module()
        if self.pll is not None:
            m.domains.sync = sync = ClockDomain()
            crystal = platform.request(platform.default_clk, dir="-")
            m.submodules.pll = ICE40PLL(crystal, self.pll, sync)
        m.submodules.scanner = scanner = GalvoScanTop(
            self.config, table=self.table, settings=self.settings, correction=self.correction)

        # The bus and the laser through the I/O cells' output flip-flops (platforms/pads.py).
        xy2 = platform.request("xy2", 0, dir="-")
        laser = platform.request("laser", 0, dir="-")
        registered_outputs(m, scanner, {
            **{f"xy2_{name}": getattr(xy2, name) for name in XY2_PMOD_PINS},
            **{f"laser_{name}": getattr(laser, name) for name in LASER_PMOD_PINS}})

        # The host link, and the machine's inputs.
        uart = platform.request("uart", 0, dir="-")
        inputs = {"uart_rx": uart.rx,
                  "interlock_open": platform.request("interlock", 0, dir="-"),
                  "laser_alarm": platform.request("laser_alarm", 0, dir="-")}
        outputs = {"uart_tx": uart.tx}
        if self.config.player:
            # The SPI link's pins are the player's machine lines.
            player_pins(m, scanner, flash=platform.request("spi_flash_1x", 0, dir="-"),
                        machine=platform.request("machine", 0, dir="-"),
                        button=platform.request("button", 0, dir="-"),
                        led=platform.request("led_g", 0, dir="-"))
            if self.config.head_status:
                inputs["xy2_status"] = platform.request("head_status", 0, dir="-")
        else:
            spi = platform.request("host_spi", 0, dir="-")
            inputs.update({"spi_sck": spi.sck, "spi_cs_n": spi.cs_n, "spi_copi": spi.copi})
            outputs["spi_cipo"] = spi.cipo
        plain_inputs(m, scanner, inputs)
        plain_outputs(m, scanner, outputs)
        running_led(m, scanner, platform.request("led_r", 0, dir="-"))
        return m
