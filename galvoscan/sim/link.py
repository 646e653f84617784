"""The host's side of the simulated board: a clock counter beside the design, and SPI frames
clocked into its pins as a host at the link's top speed sends them."""

from amaranth.hdl import Elaboratable, Module, Signal


__all__ = ["Timed", "spi_transfer"]


class Timed(Elaboratable):
    """A design with a clock counter beside it, so that events can be put in order."""

    def __init__(self, top):
        self.top = top
        self.cycles = Signal(48)

    def elaborate(self, platform):
        m = Module()
        m.submodules.top = self.top
        m.d.sync += self.cycles.eq(self.cycles + 1)
        return m


async def spi_transfer(ctx, top, frame, clk_freq):
    """Clock one frame into the top's SPI pins, as a host at the link's top speed does
    (SCK = clk / 12, mode 0, ``cs_n`` high for four half periods after); return the bits
    that came back on CIPO, as one number (the answer to the frame before, in the first six
    bytes)."""
    half_sck = 6 / clk_freq
    bits = [(byte >> (7 - i)) & 1 for byte in frame for i in range(8)]
    ctx.set(top.spi_cs_n, 0)
    answer = 0
    for bit in bits:
        ctx.set(top.spi_copi, bit)
        await ctx.delay(half_sck)
        ctx.set(top.spi_sck, 1)
        answer = (answer << 1) | ctx.get(top.spi_cipo)
        await ctx.delay(half_sck)
        ctx.set(top.spi_sck, 0)
    await ctx.delay(half_sck)
    ctx.set(top.spi_cs_n, 1)
    await ctx.delay(4 * half_sck)
    return answer
