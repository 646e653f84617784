# amaranth: UnusedElaboratable=no
# (the signature check builds a DDA without elaborating it)

"""The line DDA alone, against the exact model (tests/support/vector_model.py), on many lines."""

import random

import pytest

from amaranth.hdl import Value
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out
from amaranth.sim import Simulator
from hypothesis import given, settings, strategies as st

from galvoscan.gateware.points import FieldPoint
from galvoscan.gateware.sources.dda import LineDDA, Segment

from vector_model import dda


def test_signature():
    assert LineDDA().signature.members == wiring.SignatureMembers({
        "segment": In(stream.Signature(Segment)),
        "pitch": In(16),
        "points": Out(stream.Signature(FieldPoint)),
        "busy": Out(1),
        "last": Out(1),
    })


def step_lines(lines):
    """Points the DDA gives for each (x0, y0, x1, y1, pitch), with a stalling consumer.

    One wait on every clock edge for the whole run (a new wait each clock costs more than the
    DDA itself): each line is offered until the edge that takes it, then the consumer, ready
    on a random 70 % of clocks, takes points until the DDA is no longer busy."""
    dut = LineDDA()
    results = []

    async def testbench(ctx):
        stall = random.Random(7)
        todo = list(lines)

        def offer():
            x0, y0, x1, y1, pitch = todo.pop(0)
            ctx.set(dut.pitch, pitch)
            ctx.set(dut.segment.payload, {"x0": x0, "y0": y0, "x1": x1, "y1": y1})
            ctx.set(dut.segment.valid, 1)

        if not todo:
            return
        offer()
        points = None                   # None: the line is offered, not taken yet
        ready = False
        # The point as its raw bits, x low (one signal sampled, not two slices of it: the
        # simulator evaluates a slice the slow way, on every clock).
        payload = Value.cast(dut.points.payload)
        assert [name for name, _ in FieldPoint] == ["x", "y"]
        async for _, _, taken, valid, point, busy in ctx.tick().sample(
                dut.segment.ready, dut.points.valid, payload, dut.busy):
            if points is None:
                if not taken:
                    continue
                ctx.set(dut.segment.valid, 0)
                points = []
            else:
                if valid and ready:
                    points.append((point & 0xFFFF, point >> 16))
                if not busy:
                    results.append(points)
                    points = None
                    if not todo:
                        return
                    offer()
                    continue
            now = stall.random() < 0.7
            if now != ready:            # (setting a signal costs, even to what it holds)
                ctx.set(dut.points.ready, now)
                ready = now

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(testbench)
    sim.run()
    return results


def check(lines):
    for line, got in zip(lines, step_lines(lines)):
        x0, y0, x1, y1, pitch = line
        assert got == dda((x0, y0), (x1, y1), max(pitch, 1)), line


def test_special_lines():
    check([
        (100, 100, 700, 100, 60),         # 0°, a whole number of pitches
        (700, 100, 100, 100, 60),         # 180°
        (100, 100, 100, 1000, 60),        # 90°
        (1000, 1000, 1424, 1424, 60),     # 45°
        (5000, 5000, 5030, 5400, 60),     # steep
        (40000, 30000, 30000, 31000, 60),  # negative, shallow
        (300, 300, 300, 300, 60),         # zero length: nothing
        (10, 10, 20, 10, 60),             # shorter than the pitch: the end only
        (10, 10, 70, 10, 60),             # exactly one pitch: the end only
        (0, 0, 65535, 65535, 1000),       # corner to corner
        (65535, 0, 0, 65535, 0),          # pitch 0 is taken as 1
        (3, 4, 303, 404, 100),            # a 3-4-5 triangle: exact multiples of the pitch
    ])


def test_random_lines():
    rng = random.Random(2026)
    lines = []
    for _ in range(40):
        x0, y0 = rng.randrange(65536), rng.randrange(65536)
        x1 = min(65535, max(0, x0 + rng.randrange(-6000, 6000)))
        y1 = min(65535, max(0, y0 + rng.randrange(-6000, 6000)))
        lines.append((x0, y0, x1, y1, rng.choice([7, 30, 60, 61, 997])))
    check(lines)


def test_whole_number_lengths():
    """Lines whose length is a whole number (dx² + dy² a perfect square): a point falls exactly
    one pitch short of the end when the pitch divides the length, and must not be given."""
    lines = []
    for a, b, c in [(3, 4, 5), (5, 12, 13), (8, 15, 17), (20, 21, 29), (65, 72, 97),
                    (119, 120, 169), (2772, 2665, 3845)]:
        for scale in (1, 7):
            dx, dy, length = a * scale, b * scale, c * scale
            for pitch in {length, length - 1, length + 1, max(1, length // 3),
                          max(1, length // 4), max(1, length // 4 + 1)}:
                if length <= 40000:
                    lines.append((20000, 30000, 20000 + dx, 30000 - dy, pitch))
                    lines.append((20000 + dy, 30000, 20000, 30000 + dx, pitch))
    check(lines)


@settings(max_examples=25, deadline=None)
@given(st.tuples(st.integers(0, 65535), st.integers(0, 65535), st.integers(0, 65535),
                 st.integers(0, 65535), st.integers(200, 65535)))
def test_any_line(line):
    check([line])


@pytest.mark.parametrize("direction", [False, True])
def test_set_up_takes_the_clocks_the_planner_counts_on(direction):
    """From the clock a segment is taken to its first point: what the host's planner divides
    the board's clock by (SETUP_CLOCKS, DIRECTED_SETUP_CLOCKS), counted here on the core."""
    from galvoscan.gateware.sources.dda import DIRECTED_SETUP_CLOCKS, SETUP_CLOCKS
    dut = LineDDA(direction=direction)
    counted = []

    async def testbench(ctx):
        ctx.set(dut.pitch, 60)
        ctx.set(dut.points.ready, 1)
        ctx.set(dut.segment.payload, {"x0": 1000, "y0": 2000, "x1": 41000, "y1": 33000})
        ctx.set(dut.segment.valid, 1)
        await ctx.tick().until(dut.segment.ready)
        ctx.set(dut.segment.valid, 0)
        clocks = 1          # the clock that took the segment is the set-up's first
        while not ctx.get(dut.points.valid):
            await ctx.tick()
            clocks += 1
        counted.append(clocks)

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(testbench)
    sim.run()
    assert counted == [DIRECTED_SETUP_CLOCKS if direction else SETUP_CLOCKS]


@pytest.mark.parametrize("direction", [False, True])
def test_short_lines_set_up_within_a_frame(direction):
    """A line no longer than the pitch (a flattened curve's short piece) gives its end point
    sooner than a frame at 12 MHz and XY2-100 (120 clocks), so a run of them never makes the
    mirrors wait; a zero-length one is done sooner still."""
    dut = LineDDA(direction=direction)
    counted = {}

    async def testbench(ctx):
        ctx.set(dut.points.ready, 1)
        for name, end, pitch in [("short", (1050, 2040), 65), ("one pitch", (1039, 2052), 65),
                                 ("zero", (1000, 2000), 65)]:
            ctx.set(dut.pitch, pitch)
            ctx.set(dut.segment.payload, {"x0": 1000, "y0": 2000, "x1": end[0], "y1": end[1]})
            ctx.set(dut.segment.valid, 1)
            await ctx.tick().until(dut.segment.ready)
            ctx.set(dut.segment.valid, 0)
            clocks, points = 1, []
            while ctx.get(dut.busy):
                if ctx.get(dut.points.valid):
                    points.append((ctx.get(dut.points.payload.x), ctx.get(dut.points.payload.y)))
                    counted.setdefault(name, clocks)
                await ctx.tick()
                clocks += 1
            counted.setdefault(name, clocks)
            assert points == ([] if name == "zero" else [end]), name

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(testbench)
    sim.run()
    assert counted["short"] < 120 and counted["one pitch"] < 120, counted
    assert counted["zero"] < 10, counted
