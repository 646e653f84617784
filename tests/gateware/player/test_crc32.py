# amaranth: UnusedElaboratable=no
"""The CRC-32 core (gateware/player/crc32.py) against zlib.crc32."""

import zlib

from amaranth.sim import Simulator
from hypothesis import given, settings, strategies as st

from galvoscan.gateware.player.crc32 import CRC32


def crc_of(chunks, gaps, bits_per_clock=1):
    """The core's CRC after each chunk (a clear between chunks), bytes ``gaps`` clocks apart
    (once the last is in)."""
    dut = CRC32(bits_per_clock=bits_per_clock)
    results = []

    async def testbench(ctx):
        for chunk in chunks:
            ctx.set(dut.clear, 1)
            await ctx.tick()
            ctx.set(dut.clear, 0)
            assert ctx.get(dut.crc) == 0
            for k, byte in enumerate(chunk):
                while ctx.get(dut.busy):
                    await ctx.tick()
                ctx.set(dut.data, byte)
                ctx.set(dut.strobe, 1)
                await ctx.tick()
                ctx.set(dut.strobe, 0)
                for _ in range(gaps[k % len(gaps)]):
                    await ctx.tick()
            while ctx.get(dut.busy):
                await ctx.tick()
            results.append(ctx.get(dut.crc))

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(testbench)
    sim.run()
    return results


@settings(max_examples=30, deadline=None)
@given(st.lists(st.binary(max_size=40), min_size=1, max_size=3),
       st.lists(st.integers(0, 20), min_size=1, max_size=5), st.sampled_from([1, 2, 4, 8]))
def test_matches_zlib(chunks, gaps, bits_per_clock):
    assert crc_of(chunks, gaps, bits_per_clock) == [zlib.crc32(chunk) for chunk in chunks]


def test_known_value():
    # The CRC-32 check value of "123456789".
    assert crc_of([b"123456789"], [0]) == [0xCBF43926]


def test_bits_per_clock_is_checked():
    import pytest
    with pytest.raises(ValueError, match="1, 2, 4 or 8"):
        CRC32(bits_per_clock=3)
