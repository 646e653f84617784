"""The system top's ports wired to a board's pins: what every board file does alike.

The bus and the laser lines leave through the I/O cells' own flip-flops (which come out of
configuration low), so the lines change together, whatever the placement, and no logic glitch
reaches them. Everything else goes through plain buffers: the cores synchronise their inputs.
"""

from amaranth.hdl import Cat, Signal
from amaranth.lib import io


__all__ = ["registered_outputs", "plain_outputs", "plain_inputs", "running_led",
           "player_pins"]


def registered_outputs(m, scanner, ports):
    """Each of ``ports`` (the scanner's output name → the pin) through an output flip-flop."""
    for name, port in ports.items():
        m.submodules[f"{name}_pad"] = pad = io.FFBuffer("o", port)
        m.d.comb += pad.o.eq(getattr(scanner, name))


def plain_outputs(m, scanner, ports):
    """Each of ``ports`` (the scanner's output name → the pin) through a plain buffer."""
    for name, port in ports.items():
        m.submodules[f"{name}_pad"] = pad = io.Buffer("o", port)
        m.d.comb += pad.o.eq(getattr(scanner, name))


def plain_inputs(m, scanner, ports):
    """Each of ``ports`` (the scanner's input name → the pin) through a plain buffer."""
    for name, port in ports.items():
        m.submodules[f"{name}_pad"] = pad = io.Buffer("i", port)
        m.d.comb += getattr(scanner, name).eq(pad.i)


def running_led(m, scanner, port):
    """``port``'s LED lights once frames are going out (the first SYNC), and stays lit."""
    running = Signal()
    with m.If(scanner.xy2_sync):
        m.d.sync += running.eq(1)
    m.submodules.led_pad = led = io.Buffer("o", port)
    m.d.comb += led.o.eq(running)


def player_pins(m, scanner, *, flash, machine, button, led):
    """The job player's pins: the configuration flash (``flash``: the board's SPI flash
    resource, with a ``clk`` where the board reaches it as a pin; where it has none, the board
    drives ``scanner.flash_clk`` its own way), the start input and the PLC's busy and ready
    lines (``machine``), a button that starts too (its buffer reads 1 while pressed) and the
    player's LED."""
    # The flash's lines straight from the reader's flip-flops (an output flip-flop would put
    # SCK a clock behind the moment the reader samples CIPO); WP and HOLD held high.
    lines = {"cs_n": flash.cs, "copi": flash.copi, "wp": flash.wp, "hold": flash.hold}
    if hasattr(flash, "clk"):
        lines["clk"] = flash.clk
    for name, port in lines.items():
        m.submodules[f"flash_{name}_pad"] = pad = io.Buffer("o", port)
        if name in ("wp", "hold"):
            m.d.comb += pad.o.eq(0)         # (active-low pins: 0 = high, inactive)
        elif name == "cs_n":
            m.d.comb += pad.o.eq(~scanner.flash_cs_n)     # (the resource is active low)
        else:
            m.d.comb += pad.o.eq(getattr(scanner, f"flash_{name}"))
    m.submodules.flash_cipo_pad = cipo = io.Buffer("i", flash.cipo)
    m.d.comb += scanner.flash_cipo.eq(cipo.i)
    m.submodules.start_pad = start = io.Buffer("i", machine.start_n)
    m.submodules.button_pad = pressed = io.Buffer("i", button)
    m.d.comb += scanner.start_n.eq(Cat(start.i, ~pressed.i))
    registered_outputs(m, scanner, {"busy": machine.busy, "ready": machine.ready})
    m.submodules.player_led_pad = player_led = io.Buffer("o", led)
    m.d.comb += player_led.o.eq(scanner.player_led)
