# amaranth: UnusedElaboratable=no
"""The flash reader (gateware/flash/spi_flash.py) against the W25Q128JV model written from
its datasheet (galvoscan/sim/spi_flash.py), on the reader's pins."""

import random

import pytest
from amaranth.sim import Simulator
from hypothesis import given, settings, strategies as st

from galvoscan.gateware.flash.spi_flash import READ_DATA, RELEASE_POWER_DOWN, SPIFlashReader
from galvoscan.sim.spi_flash import FLASH_BYTES, SPIFlashModel


CLK_HZ = 12e6


def read_through(reader, flash, address, count, *, ready=lambda k: True, stop_after=None):
    """Start a read at ``address``, take ``count`` bytes (``ready(k)``: whether the consumer
    takes on its k-th clock), stop; returns the bytes and the clocks SCK stayed high or low
    at most (the fastest SCK edges)."""
    got = []
    edges = []

    async def flash_pins(ctx):
        async for cs_n, sck in ctx.changed(reader.cs_n, reader.sck):
            now = ctx.get(clock_count) / CLK_HZ
            ctx.set(reader.cipo, flash.pins(cs_n, sck, ctx.get(reader.copi), now))


    async def testbench(ctx):
        ctx.set(reader.address, address)
        ctx.set(reader.start, 1)
        await ctx.tick()
        ctx.set(reader.start, 0)
        k = 0
        last_sck, last_change = 0, 0
        while len(got) < count:
            take = ready(k)
            ctx.set(reader.data.ready, take)
            valid, payload = ctx.get(reader.data.valid), ctx.get(reader.data.payload)
            await ctx.tick()
            if valid and take:
                got.append(payload)
            sck = ctx.get(reader.sck)
            if sck != last_sck:
                edges.append(k - last_change)
                last_sck, last_change = sck, k
            k += 1
            assert k < 100 * (count + 10), "the reader gave no bytes"
            if stop_after is not None and len(got) == stop_after:
                break
        ctx.set(reader.stop, 1)
        await ctx.tick()
        ctx.set(reader.stop, 0)
        await ctx.tick()
        assert ctx.get(reader.cs_n) == 1 and ctx.get(reader.idle)

    from amaranth.hdl import Module, Signal
    m = Module()
    m.submodules.reader = reader
    clock_count = Signal(32)
    m.d.sync += clock_count.eq(clock_count + 1)
    sim = Simulator(m)
    sim.add_clock(1 / CLK_HZ)
    sim.add_testbench(testbench)
    sim.add_testbench(flash_pins, background=True)
    sim.run()
    return bytes(got), edges


def test_reads_from_deep_power_down():
    data = bytes(random.Random(1).randrange(256) for _ in range(64))
    flash = SPIFlashModel({0x100000: data}, powered_down=True)
    got, edges = read_through(SPIFlashReader(clk_freq=CLK_HZ), flash, 0x100000, 64)
    assert got == data
    # Released first, then read with the plain read: nothing ignored (tRES1 kept).
    assert flash.commands == [RELEASE_POWER_DOWN, READ_DATA]
    assert flash.ignored == []
    # SCK: never faster than half the clock.
    assert min(edges[1:]) >= 1


def test_reads_an_awake_flash_and_the_top_wraps():
    flash = SPIFlashModel({FLASH_BYTES - 4: b"\x01\x02\x03\x04", 0: b"\x05\x06"},
                          powered_down=False)
    got, _ = read_through(SPIFlashReader(clk_freq=CLK_HZ), flash, FLASH_BYTES - 4, 6)
    assert got == b"\x01\x02\x03\x04\x05\x06"


def test_erased_flash_reads_ff():
    got, _ = read_through(SPIFlashReader(clk_freq=CLK_HZ), SPIFlashModel(), 0x123456, 8)
    assert got == b"\xff" * 8


@settings(max_examples=25, deadline=None)
@given(address=st.integers(0, FLASH_BYTES - 1), count=st.integers(1, 24),
       seed=st.integers(0, 2**32 - 1), stop_after=st.none() | st.integers(1, 24))
def test_a_slow_consumer_loses_nothing(address, count, seed, stop_after):
    """SCK waits while a byte is not taken; a stop at any byte ends the read cleanly, and the
    next read starts afresh."""
    rng = random.Random(seed)
    contents = bytes(rng.randrange(256) for _ in range(count))
    start = min(address, FLASH_BYTES - count)
    flash = SPIFlashModel({start: contents}, powered_down=rng.random() < 0.5)
    pattern = [rng.random() < 0.4 for _ in range(64)]
    reader = SPIFlashReader(clk_freq=CLK_HZ)
    got, _ = read_through(reader, flash, start, count, ready=lambda k: pattern[k % 64],
                          stop_after=stop_after)
    expected = contents if stop_after is None else contents[:stop_after]
    assert got == expected[:len(got)] and len(got) == min(count, len(expected))
    assert flash.ignored == []


class ReaderWithoutWake(SPIFlashReader):
    """A broken reader: no release from power-down (the read is sent to a sleeping flash)."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.release_clocks = 1

    def elaborate(self, platform):
        import galvoscan.gateware.flash.spi_flash as module
        saved = module.RELEASE_POWER_DOWN
        module.RELEASE_POWER_DOWN = 0x00        # a no-op command instead of the release
        try:
            return super().elaborate(platform)
        finally:
            module.RELEASE_POWER_DOWN = saved


def test_a_reader_that_does_not_wake_the_flash_reads_nothing():
    data = b"\x12\x34\x56\x78"
    flash = SPIFlashModel({0: data}, powered_down=True)
    got, _ = read_through(ReaderWithoutWake(clk_freq=CLK_HZ), flash, 0, 4)
    assert got != data and flash.ignored


def test_too_early_after_the_release_is_ignored():
    """The model holds the reader to tRES1: a reader that waits too little is caught."""
    class Hasty(SPIFlashReader):
        def __init__(self, **kwargs):
            super().__init__(**kwargs)
            self.release_clocks = 4             # 0.4 µs, not 3
    flash = SPIFlashModel({0: b"\xaa\x55"}, powered_down=True)
    got, _ = read_through(Hasty(clk_freq=CLK_HZ), flash, 0, 2)
    assert got != b"\xaa\x55" and [c for _, c in flash.ignored] == [READ_DATA]


def test_parameters_are_checked():
    with pytest.raises(ValueError, match="positive frequency"):
        SPIFlashReader(clk_freq=0)
