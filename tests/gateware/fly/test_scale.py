# amaranth: UnusedElaboratable=no
"""The fly offset (gateware/fly/scale.py): the shift-and-add product against Python's own
integers, rounded down and held within the offset's range, renewed in its time."""

from amaranth.sim import Simulator
from hypothesis import given, settings, strategies as st

from galvoscan.gateware.fly.encoder import COUNT_BITS
from galvoscan.gateware.fly.scale import (OFFSET_LIMIT, SCALE_BITS, SCALE_FRACTION, FlyScale)


def offsets(cases, *, enable=True):
    """Each ``(count_x, scale_x, count_y, scale_y)`` of ``cases`` held for two renewals: the
    offsets after the second, and the clocks between renewals."""
    dut = FlyScale()
    seen, gaps = [], []

    async def testbench(ctx):
        ctx.set(dut.enable, enable)
        last = None
        clock = 0
        for count_x, scale_x, count_y, scale_y in cases:
            ctx.set(dut.count_x, count_x)
            ctx.set(dut.scale_x, scale_x)
            ctx.set(dut.count_y, count_y)
            ctx.set(dut.scale_y, scale_y)
            renewals = 0
            while renewals < 2:
                await ctx.tick()
                clock += 1
                if ctx.get(dut.renewed):
                    renewals += 1
                    if last is not None:
                        gaps.append(clock - last)
                    last = clock
            seen.append((ctx.get(dut.offset_x), ctx.get(dut.offset_y)))

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(testbench)
    sim.run()
    return seen, gaps


def expected(count, scale):
    """What the offset must be: the exact product in galvo units (scale in 2^-16 units a
    count) rounded down, and past the range held at its end."""
    exact = count * scale / 2 ** SCALE_FRACTION
    floor = int(exact // 1)
    return max(-OFFSET_LIMIT, min(OFFSET_LIMIT, floor))


COUNTS = st.integers(-2 ** (COUNT_BITS - 1), 2 ** (COUNT_BITS - 1) - 1)
SCALES = st.integers(-2 ** (SCALE_BITS - 1), 2 ** (SCALE_BITS - 1) - 1)
EDGES = [0, 1, -1, 2 ** (COUNT_BITS - 1) - 1, -2 ** (COUNT_BITS - 1)]
SCALE_EDGES = [0, 1, -1, 2 ** (SCALE_BITS - 1) - 1, -2 ** (SCALE_BITS - 1), 1 << 16]


def test_the_edges_of_counts_and_scales():
    # Each pair on X, and another on Y.
    cases = [(c, s, EDGES[(i + 1) % len(EDGES)], SCALE_EDGES[(j + 2) % len(SCALE_EDGES)])
             for i, c in enumerate(EDGES) for j, s in enumerate(SCALE_EDGES)]
    seen, gaps = offsets(cases)
    assert seen == [(expected(cx, sx), expected(cy, sy)) for cx, sx, cy, sy in cases]
    # Both axes renewed every 2 × (24 + 1) clocks.
    assert set(gaps) == {2 * FlyScale.CLOCKS_PER_AXIS}


@settings(max_examples=25, deadline=None)
@given(st.lists(st.tuples(COUNTS, SCALES, COUNTS, SCALES), min_size=1, max_size=4))
def test_any_count_and_scale(cases):
    seen, _ = offsets(cases)
    assert seen == [(expected(cx, sx), expected(cy, sy)) for cx, sx, cy, sy in cases]


@settings(max_examples=25, deadline=None)
@given(st.lists(st.tuples(st.integers(-200_000, 200_000), st.integers(-2 ** 20, 2 ** 20)),
                min_size=1, max_size=4))
def test_a_belts_counts_at_its_scales(cases):
    # The range a job works in: the offsets within the field, exact to the unit below.
    seen, _ = offsets([(c, s, c, -s) for c, s in cases])
    assert seen == [(expected(c, s), expected(c, -s)) for c, s in cases]


def test_0_001_mm_a_count_on_a_110_mm_field():
    # 65,536 units on 110 mm: 595.78 units a mm, 0.59578 a count; after 100,000 counts
    # (100 mm of belt) the offset is 59,578 units, off by the scale's rounding (half of
    # 2^-16 a count) and the unit the offset rounds down.
    scale = round(65536 / 110 * 0.001 * 2 ** SCALE_FRACTION)
    [(x, y)], _ = offsets([(100_000, scale, -100_000, scale)])
    within = 1 + 100_000 / 2 ** (SCALE_FRACTION + 1)
    assert abs(x - 65536 / 110 * 100) < within and abs(y + 65536 / 110 * 100) < within


def test_disabled_the_offsets_are_0():
    seen, _ = offsets([(1000, 1 << 16, -1000, 1 << 16)], enable=False)
    assert seen == [(0, 0)]
