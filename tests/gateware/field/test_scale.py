# amaranth: UnusedElaboratable=no
# (signature checks build components without elaborating them)

import pytest
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out
from amaranth.sim import Simulator
from hypothesis import given, settings, strategies as st

from galvoscan.gateware.field.scale import ScaleOffset
from galvoscan.gateware.points import FieldPoint, OffsetPoint

from spiral_model import scaled


def test_signature():
    assert ScaleOffset().signature.members == wiring.SignatureMembers({
        "offsets": In(stream.Signature(OffsetPoint)),
        "positions": Out(stream.Signature(FieldPoint)),
        "amp_x": In(16), "amp_y": In(16), "center_x": In(16), "center_y": In(16),
        "clipped": Out(1),
    })


def run_points(vectors, *, sink_stalls=0, multiplier="dsp"):
    """Push (ox, oy, gx, gy, cx, cy) vectors through; return (x, y, clipped) for each."""
    dut = ScaleOffset(multiplier=multiplier)
    sim = Simulator(dut)
    sim.add_clock(1e-6)
    results = []
    clipped_seen = []

    async def source(ctx):
        for ox, oy, gx, gy, cx, cy in vectors:
            ctx.set(dut.amp_x, gx)
            ctx.set(dut.amp_y, gy)
            ctx.set(dut.center_x, cx)
            ctx.set(dut.center_y, cy)
            ctx.set(dut.offsets.payload.x, ox)
            ctx.set(dut.offsets.payload.y, oy)
            ctx.set(dut.offsets.valid, 1)
            clipped, = await ctx.tick().sample(dut.clipped).until(dut.offsets.ready)
            clipped_seen.append(clipped)
            ctx.set(dut.offsets.valid, 0)
            # Registers change after the point was taken: it must not change the point.
            ctx.set(dut.amp_x, 0)
            ctx.set(dut.center_x, 0)

    async def sink(ctx):
        for _ in vectors:
            if sink_stalls:
                await ctx.tick().repeat(sink_stalls)
            ctx.set(dut.positions.ready, 1)
            x, y = await ctx.tick().sample(
                dut.positions.payload.x, dut.positions.payload.y).until(dut.positions.valid)
            ctx.set(dut.positions.ready, 0)
            results.append((x, y))

    sim.add_testbench(source)
    sim.add_testbench(sink)
    sim.run()
    return [(x, y, c) for (x, y), c in zip(results, clipped_seen)]


def model(ox, oy, gx, gy, cx, cy):
    x, y = scaled(ox, gx, cx), scaled(oy, gy, cy)
    clip = (cx + ox * gx // 32768) != x or (cy + oy * gy // 32768) != y
    return x, y, int(clip)


def test_unity_gain_full_swing_reaches_the_edges():
    vectors = [(32767, -32767, 32768, 32768, 32768, 32768),
               (0, 0, 32768, 32768, 32768, 32768)]
    assert run_points(vectors) == [(65535, 1, 0), (32768, 32768, 0)]


def test_saturates_and_flags_instead_of_wrapping():
    vectors = [(32767, -32768, 65535, 65535, 32768, 32768),   # gain ≈ 2: both axes clip
               (100, 0, 32768, 32768, 65500, 0)]              # centre near the edge
    assert run_points(vectors) == [(65535, 0, 1), (65535, 0, 1)]


offsets = st.integers(-32768, 32767)
words = st.integers(0, 65535)


@settings(max_examples=25, deadline=None)
@given(st.lists(st.tuples(offsets, offsets, words, words, words, words), min_size=1,
                max_size=12),
       st.integers(0, 3))
def test_matches_model(vectors, sink_stalls):
    assert run_points(vectors, sink_stalls=sink_stalls) == [model(*v) for v in vectors]


@settings(max_examples=25, deadline=None)
@given(st.lists(st.tuples(offsets, offsets, words, words, words, words), min_size=1,
                max_size=12),
       st.integers(0, 3))
def test_serial_multiplier_matches_model(vectors, sink_stalls):
    assert run_serial(vectors, sink_stalls=sink_stalls) == [model(*v) for v in vectors]


def test_serial_multiplier_edges():
    vectors = [(32767, -32768, 65535, 65535, 32768, 32768), (-32768, 32767, 65535, 1, 0, 65535),
               (-1, 1, 1, 1, 0, 65535), (32767, -32767, 32768, 32768, 32768, 32768)]
    assert run_serial(vectors) == [model(*v) for v in vectors]


def run_serial(vectors, *, sink_stalls=0):
    """As run_points, for the serial multiplier: its clipped pulse comes when the point is
    made, the clock before it is presented, so pulses are matched to outputs by time."""
    dut = ScaleOffset(multiplier="serial")
    sim = Simulator(dut)
    sim.add_clock(1e-6)
    outputs, pulses = [], []

    async def source(ctx):
        for ox, oy, gx, gy, cx, cy in vectors:
            for name, value in (("amp_x", gx), ("amp_y", gy), ("center_x", cx),
                                ("center_y", cy)):
                ctx.set(getattr(dut, name), value)
            ctx.set(dut.offsets.payload.x, ox)
            ctx.set(dut.offsets.payload.y, oy)
            ctx.set(dut.offsets.valid, 1)
            await ctx.tick().until(dut.offsets.ready)
            ctx.set(dut.offsets.valid, 0)
            ctx.set(dut.amp_x, 0)                   # must not change the point
            ctx.set(dut.center_x, 0)

    async def watch(ctx):
        clock = 0
        async for _, _, clipped, valid, ready, x, y in ctx.tick().sample(
                dut.clipped, dut.positions.valid, dut.positions.ready,
                dut.positions.payload.x, dut.positions.payload.y):
            clock += 1
            if clipped:
                pulses.append(clock)
            if valid and ready:
                outputs.append((clock, x, y))

    async def sink(ctx):
        while len(outputs) < len(vectors):
            if sink_stalls:
                await ctx.tick().repeat(sink_stalls)
            ctx.set(dut.positions.ready, 1)
            await ctx.tick()
            ctx.set(dut.positions.ready, 0)

    sim.add_testbench(source)
    sim.add_testbench(sink)
    sim.add_testbench(watch, background=True)
    sim.run()
    results, before = [], 0
    for clock, x, y in outputs:
        results.append((x, y, int(any(before < p < clock for p in pulses))))
        before = clock
    return results


def test_scale_rejects_bad_parameters():
    with pytest.raises(ValueError, match="multiplier must be dsp or serial"):
        ScaleOffset(multiplier="lut")
    with pytest.raises(ValueError, match="always buffered"):
        ScaleOffset(multiplier="serial", buffered=False)
