"""ULX3S (Lattice ECP5 LFE5U-25F, or the 12F/45F/85F): every feature in one bitstream.

The iCEBreaker's UP5K holds the system only with features left out; the ECP5 on the ULX3S holds
all of it with room to spare (``galvoscan build --board ulx3s``): the spiral with its
interpolator, raster, vector mode with the RTC delays and the wobble stage, the correction
stage with a 33 × 33 table, the job player, the scan head's status, marking on the fly (two
encoder inputs), XY2-100's Z channel (a focus shifter), and both host links, the SPI target and the UART on the board's FT231X at
3 Mbaud (the player's machine lines have pins of their own here).

The clock: 24 MHz, the PLL's CLKOS from the 25 MHz crystal (25 MHz is no whole, even multiple
of XY2-100's 2 MHz bit rate). 24 MHz is the slowest clock that gives XY2-100 a whole, even
number of clocks a bit (12), the UART 3 Mbaud exactly (8 clocks a bit), and the RTC delays
their whole µs; it is the iCEBreaker marker's clock, so every core counts the same there and
here; and the ECP5 meets it more than twice over, which leaves the room for more features.

Pins, on the GPIO header J1 (``GPn`` / ``GNn``: the pair's two pins, 3.3 V LVCMOS, **not 5 V
tolerant**). The table is :data:`ULX3S_PINS`; the README's wiring table is checked against it.

XY2-100 goes through an RS-422 driver (AM26LV31, SN75C1168) run from 3.3 V or 5 V, whose inputs
take 3.3 V logic. The laser's DB25 lines want 5 V TTL: drive them through a 74HCT245 or
74AHCT125 run from 5 V, output enable from ``laser_enable`` pulled down to its off level, each
laser line pulled down behind it. Inputs from the laser or a PLC (24 V) come through
optocouplers or a divider to 3.3 V: never straight to the header.

Before and while the ECP5 configures, nothing drives its user pins: they are tri-stated, held
at most by the I/O's weak default pull, which must not be counted on either way. The external
pull-down on ``laser_enable`` keeps the buffers off then, as on the iCEBreaker, and a pull-down
behind each buffer holds its laser line low. From configuration on, every laser line and the
bus leave through the I/O cells' output flip-flops, which start low.

LED 0 lights once frames are going out; LED 1 is the player's (lit while busy, blinking after
it refused an image). The FIRE 1 button starts the job player, as the start input does.
"""

from amaranth.build import Attrs, Pins, Resource, Subsignal
from amaranth.hdl import ClockDomain, Elaboratable, Instance, Module
from amaranth.lib import io
from amaranth_boards.ulx3s import (ULX3S_12F_Platform, ULX3S_25F_Platform, ULX3S_45F_Platform,
                                   ULX3S_85F_Platform)

from ..gateware.build_config import BuildConfig, LINKS, MODES
from ..gateware.clocking import XY2_100_BIT_RATE, check_clocks, default_baud
from ..gateware.field.correction_table import CorrectionTable
from ..gateware.top import GalvoScanTop
from .pads import (player_pins, plain_inputs, plain_outputs, registered_outputs,
                   running_led)
from .pll import ECP5PLL, ecp5_pll_settings


__all__ = ["ULX3SScanner", "ulx3s_platform", "ULX3S_DEVICES", "ULX3S_CLOCK_HZ",
           "ULX3S_CRYSTAL_HZ", "ULX3S_BAUD", "ULX3S_CORRECTION_NODES", "ULX3S_PINS",
           "wiring_table"]


#: The board's oscillator.
ULX3S_CRYSTAL_HZ = 25_000_000
#: The system clock, from the PLL (why 24 MHz: the module's docstring).
ULX3S_CLOCK_HZ = 24_000_000
#: The host serial port's rate: 3 Mbaud, the FT231X's fastest, 8 system clocks a bit; it
#: carries some 25,000 vector segments a second (1 Mbaud: 8,300).
ULX3S_BAUD = 3_000_000
#: The correction table's nodes per axis (the iCEBreaker's 17 leave 4 times the error between
#: nodes; block RAM is no constraint here).
ULX3S_CORRECTION_NODES = 33

#: The ECP5 a ULX3S carries → its amaranth-boards platform.
ULX3S_DEVICES = {"12F": ULX3S_12F_Platform, "25F": ULX3S_25F_Platform,
                 "45F": ULX3S_45F_Platform, "85F": ULX3S_85F_Platform}

#: Every signal on the GPIO header: name → (header pin, direction, where it goes). Pins marked
#: "spare" are kept for what is still to come: wire them now and a later bitstream uses them.
ULX3S_PINS = {
    "xy2_clk": ("GP0", "o", "RS-422 driver → head CLOCK±"),
    "xy2_sync": ("GN0", "o", "RS-422 driver → head SYNC±"),
    "xy2_x": ("GP1", "o", "RS-422 driver → head CHAN1± (X)"),
    "xy2_y": ("GN1", "o", "RS-422 driver → head CHAN2± (Y)"),
    "xy2_z": ("GP2", "o", "RS-422 driver → head CHAN3± (Z, a focus shifter)"),
    "xy2_status": ("GN2", "i", "RS-422 receiver ← head STATUS± (fail-safe: no head reads as missing)"),
    "laser_power[0]": ("GP3", "o", "5 V buffer → DB25 1"),
    "laser_power[1]": ("GN3", "o", "5 V buffer → DB25 2"),
    "laser_power[2]": ("GP4", "o", "5 V buffer → DB25 3"),
    "laser_power[3]": ("GN4", "o", "5 V buffer → DB25 4"),
    "laser_power[4]": ("GP5", "o", "5 V buffer → DB25 5"),
    "laser_power[5]": ("GN5", "o", "5 V buffer → DB25 6"),
    "laser_power[6]": ("GP6", "o", "5 V buffer → DB25 7"),
    "laser_power[7]": ("GN6", "o", "5 V buffer → DB25 8"),
    "laser_latch": ("GP7", "o", "5 V buffer → DB25 9"),
    "laser_mo": ("GN7", "o", "5 V buffer → DB25 18"),
    "laser_am": ("GP8", "o", "5 V buffer → DB25 19"),
    "laser_prr": ("GN8", "o", "5 V buffer → DB25 20"),
    "laser_enable": ("GP9", "o", "the 5 V buffers' output enable (pulled down: off)"),
    "laser_guide": ("GN9", "o", "own 5 V buffer → DB25 22 on IPG (pulled down)"),
    "interlock_open": ("GP10", "i", "interlock loop to GND (pulled up: a broken loop reads open)"),
    "laser_alarm[0]": ("GN10", "i", "optocoupler ← laser alarm (pulled up: 1 = alarm)"),
    "laser_alarm[1]": ("GP11", "i", "optocoupler ← laser alarm (pulled up: 1 = alarm)"),
    "spi_cs_n": ("GP14", "i", "host SPI chip select (pulled up)"),
    "spi_copi": ("GN14", "i", "host SPI data in"),
    "spi_cipo": ("GP15", "o", "host SPI data out"),
    "spi_sck": ("GN15", "i", "host SPI clock"),
    "start_n": ("GP16", "i", "optocoupler ← foot switch or PLC start, to GND (pulled up)"),
    "busy": ("GN16", "o", "optocoupler → PLC: a job is checked or played"),
    "ready": ("GP17", "o", "optocoupler → PLC: armed and past the MO lead"),
    "io_in[0]": ("GN17", "i", "optocoupler ← part sensor (I/O in the queue, input 0)"),
    "io_in[1]": ("GN11", "i", "optocoupler ← a second input (input 1)"),
    "io_out[0]": ("GP12", "o", "optocoupler → PLC (I/O in the queue, output 0)"),
    "io_out[1]": ("GN12", "o", "optocoupler → PLC (output 1)"),
    "encoder_x_a": ("GP18", "i", "RS-422 receiver ← ENCODER X A (marking on the fly)"),
    "encoder_x_b": ("GN18", "i", "RS-422 receiver ← ENCODER X B"),
    "encoder_y_a": ("GP19", "i", "RS-422 receiver ← ENCODER Y A"),
    "encoder_y_b": ("GN19", "i", "RS-422 receiver ← ENCODER Y B"),
}


def _pin(name):
    """The header pin's name in the amaranth-boards connector: ``GP3`` → ``3+``."""
    header = ULX3S_PINS[name][0]
    return f"{header[2:]}{'+' if header[1] == 'P' else '-'}"


def _pins(*names, direction):
    return Pins(" ".join(_pin(name) for name in names), dir=direction, conn=("gpio", 0))


def _subsignals(names, **attrs):
    return [Subsignal(name.split("_", 1)[1], _pins(name, direction=ULX3S_PINS[name][1]),
                      Attrs(**attrs)) for name in names]


def ulx3s_platform(device="25F"):
    """The ULX3S platform for ``device`` with the galvoscan resources on the GPIO header.

    A build needs only Yosys, nextpnr-ecp5 and ecppack (from PyPI): amaranth-boards' ULX3S
    also asks for openFPGALoader, which only programs, so that is left out of the tools a build
    checks for (``galvoscan flash`` programs the board)."""
    if device not in ULX3S_DEVICES:
        raise ValueError(f"unknown ULX3S device {device!r}; known: {', '.join(ULX3S_DEVICES)}")
    base = ULX3S_DEVICES[device]

    class Platform(base):
        @property
        def required_tools(self):
            return [name for name in base.required_tools.fget(self)
                    if name != "openFPGALoader"]

    Platform.__name__ = Platform.__qualname__ = f"GalvoScan{base.__name__}"
    platform = Platform()
    lvcmos = {"IO_TYPE": "LVCMOS33"}
    power = [f"laser_power[{bit}]" for bit in range(8)]
    alarms = [name for name in ULX3S_PINS if name.startswith("laser_alarm")]
    platform.add_resources([
        Resource("xy2", 0, *_subsignals(["xy2_clk", "xy2_sync", "xy2_x", "xy2_y"]),
                 Attrs(**lvcmos, DRIVE="8")),
        Resource("xy2_z", 0, _pins("xy2_z", direction="o"), Attrs(**lvcmos, DRIVE="8")),
        Resource("laser", 0,
                 Subsignal("power", _pins(*power, direction="o")),
                 *_subsignals(["laser_latch", "laser_mo", "laser_am", "laser_prr",
                               "laser_enable", "laser_guide"]),
                 Attrs(**lvcmos, DRIVE="8")),
        Resource("host_spi", 0,
                 *_subsignals(["spi_cs_n"], PULLMODE="UP"),
                 *_subsignals(["spi_copi", "spi_cipo", "spi_sck"]),
                 Attrs(**lvcmos)),
        # Pulled up: a broken loop, an unconnected alarm or start input is open, alarm, no press.
        Resource("interlock", 0, _pins("interlock_open", direction="i"),
                 Attrs(**lvcmos, PULLMODE="UP")),
        Resource("laser_alarm", 0, _pins(*alarms, direction="i"),
                 Attrs(**lvcmos, PULLMODE="UP")),
        # Pulled down: with nothing on it the line is low, and the head reads as missing.
        Resource("head_status", 0, _pins("xy2_status", direction="i"),
                 Attrs(**lvcmos, PULLMODE="DOWN")),
        Resource("encoder", 0,
                 *(Subsignal(f"{axis}_{line}", _pins(f"encoder_{axis}_{line}", direction="i"))
                   for axis in "xy" for line in "ab"),
                 Attrs(**lvcmos)),
        # Pulled down: an unconnected input reads low (no part).
        Resource("io_in", 0, _pins("io_in[0]", "io_in[1]", direction="i"),
                 Attrs(**lvcmos, PULLMODE="DOWN")),
        Resource("io_out", 0, _pins("io_out[0]", "io_out[1]", direction="o"), Attrs(**lvcmos)),
        Resource("machine", 0,
                 Subsignal("start_n", _pins("start_n", direction="i"), Attrs(PULLMODE="UP")),
                 Subsignal("busy", _pins("busy", direction="o")),
                 Subsignal("ready", _pins("ready", direction="o")),
                 Attrs(**lvcmos)),
    ])
    return platform


class ULX3SScanner(Elaboratable):
    """The system top on the ULX3S: every feature, on the PLL's 24 MHz.

    Parameters
    ----------
    config : :class:`~galvoscan.gateware.build_config.BuildConfig`
        The build (:meth:`config`).
    table, settings
        As for :class:`~galvoscan.gateware.top.GalvoScanTop`.
    correction : :class:`~galvoscan.gateware.field.correction_table.CorrectionTable` or str
        The table the correction RAM starts with (``"identity"``: the identity of
        :data:`ULX3S_CORRECTION_NODES` nodes).
    """

    def __init__(self, config, *, table=None, settings=None, correction="identity"):
        self.config = config
        self.table = table
        self.settings = settings
        if isinstance(correction, str) and correction == "identity":
            correction = CorrectionTable.identity(ULX3S_CORRECTION_NODES)
        self.correction = correction
        self.pll = ecp5_pll_settings(ULX3S_CRYSTAL_HZ, config.clk_freq)

    @staticmethod
    def config(*, modes=None, correction="identity", clock=None, bit_rate=XY2_100_BIT_RATE,
               baud=None, wobble=True, interpolation=True, delays=True, pixel_lines=True,
               player=True, head_status=True, fly=True, z_axis=True, queue_io=True):
        """The :class:`~galvoscan.gateware.build_config.BuildConfig` of a ULX3S bitstream:
        with no options, every feature (all three modes, correction, the interpolator, the
        RTC delays, pixel lines, wobble, the job player, the head's status, marking on the fly,
        the Z channel, I/O in the queue, both links). ``clock`` in Hz (None: 24 MHz) must
        be one the PLL makes exactly from 25 MHz; ``baud`` None: :data:`ULX3S_BAUD` (3 Mbaud)
        where the clock carries it, else the fastest rate it does. A ``ValueError``
        for what cannot be built, before anything is built."""
        clock = ULX3S_CLOCK_HZ if clock is None else clock
        ecp5_pll_settings(ULX3S_CRYSTAL_HZ, clock)          # (raises for one it cannot make)
        if baud is None:
            baud = ULX3S_BAUD if clock >= 8 * ULX3S_BAUD else default_baud(clock)
        check_clocks(clock, bit_rate, baud)
        modes = MODES if modes is None else tuple(modes)
        return BuildConfig(
            modes=modes, clk_freq=clock, bit_rate=bit_rate, baud=baud,
            correction=correction is not None, laser_alarms=2,
            wobble=wobble and "vector" in modes,
            spiral_interpolation=interpolation, vector_delays=delays,
            pixel_lines=pixel_lines and delays and "vector" in modes,
            player=player and "vector" in modes, links=LINKS, head_status=head_status,
            fly=fly, z_axis=z_axis,
            queue_io=queue_io and pixel_lines and delays and "vector" in modes)

    def _encoder_pins(self, platform):
        """The encoders' lines, by the top's port names (none without marking on the fly)."""
        if not self.config.fly:
            return {}
        encoder = platform.request("encoder", 0, dir="-")
        return {f"encoder_{axis}_{line}": getattr(encoder, f"{axis}_{line}")
                for axis in "xy" for line in "ab"}

    def elaborate(self, platform):
        m = Module()
        m.domains.sync = sync = ClockDomain()
        crystal = platform.request(platform.default_clk, dir="-")
        m.submodules.crystal_pad = crystal_pad = io.Buffer("i", crystal)
        m.submodules.pll = ECP5PLL(crystal_pad.i, self.pll, sync)
        m.submodules.scanner = scanner = GalvoScanTop(
            self.config, table=self.table, settings=self.settings, correction=self.correction)

        # The bus and the laser through the I/O cells' output flip-flops (platforms/pads.py).
        xy2 = platform.request("xy2", 0, dir="-")
        laser = platform.request("laser", 0, dir="-")
        registered_outputs(m, scanner, {
            **{f"xy2_{name}": getattr(xy2, name) for name in ("clk", "sync", "x", "y")},
            **({"xy2_z": platform.request("xy2_z", 0, dir="-")} if self.config.z_axis else {}),
            **{f"laser_{name}": getattr(laser, name)
               for name in ("power", "latch", "mo", "am", "prr", "enable", "guide")}})

        # The links and the machine's inputs.
        uart = platform.request("uart", 0, dir="-")
        spi = platform.request("host_spi", 0, dir="-")
        plain_inputs(m, scanner, {
            "uart_rx": uart.rx, "spi_sck": spi.sck, "spi_cs_n": spi.cs_n, "spi_copi": spi.copi,
            "interlock_open": platform.request("interlock", 0, dir="-"),
            "laser_alarm": platform.request("laser_alarm", 0, dir="-"),
            **({"xy2_status": platform.request("head_status", 0, dir="-")}
               if self.config.head_status else {}),
            **self._encoder_pins(platform),
            **({"io_in": platform.request("io_in", 0, dir="-")} if self.config.queue_io else {})})
        plain_outputs(m, scanner, {"uart_tx": uart.tx, "spi_cipo": spi.cipo,
                                   **({"io_out": platform.request("io_out", 0, dir="-")}
                                      if self.config.queue_io else {})})
        running_led(m, scanner, platform.request("led", 0, dir="-"))
        if self.config.player:
            # The flash's clock pin is the configuration clock, reached after configuration
            # only through USRMCLK (its tristate held low: driven).
            m.submodules.flash_clk = Instance("USRMCLK", i_USRMCLKI=scanner.flash_clk,
                                              i_USRMCLKTS=0)
            # FIRE 1 starts the player too; LED 1 is the player's.
            player_pins(m, scanner, flash=platform.request("spi_flash", 0, dir="-"),
                        machine=platform.request("machine", 0, dir="-"),
                        button=platform.request("button_fire", 0, dir="-"),
                        led=platform.request("led", 1, dir="-"))
        return m


def wiring_table():
    """:data:`ULX3S_PINS` as the Markdown table the README and the wiring page show: header
    pin, the ECP5's ball (amaranth-boards' map of the header), signal, where it goes."""
    connector = ulx3s_platform().connectors["gpio", 0]
    lines = ["| J1 pin | ECP5 ball | signal | wire to |", "|---|---|---|---|"]
    for name, (header, direction, to) in ULX3S_PINS.items():
        ball = connector.mapping[_pin(name)]
        signal = f"`{name}`" if direction != "spare" else f"({name}: spare)"
        lines.append(f"| {header} | {ball} | {signal} | {to} |")
    return "\n".join(lines)
