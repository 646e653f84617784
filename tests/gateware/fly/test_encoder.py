# amaranth: UnusedElaboratable=no
"""The encoders (gateware/fly/encoder.py): ×4 decoding against a belt modelled here, illegal
transitions counted and never a step, saturation, and the simulated encoder read back by an
independent decoder."""

import random

import pytest
from amaranth.sim import Simulator
from hypothesis import given, settings, strategies as st

from galvoscan.gateware.fly.encoder import (COUNT_BITS, ILLEGAL_BITS, QuadratureDecoder,
                                            SimulatedEncoder)


def lines(position):
    """The A/B lines of an encoder ``position`` edges from its zero (A leads B forward): the
    disc's quarter-period pattern, written out."""
    quarter = position % 4
    return int(quarter in (1, 2)), int(quarter in (2, 3))


def decode(positions, *, clear_at=()):
    """Drive the lines of ``positions`` (one a clock), clearing on the clocks in
    ``clear_at``: the decoder's ``(count, illegal)`` after each clock."""
    dut = QuadratureDecoder()
    seen = []

    async def testbench(ctx):
        for clock, position in enumerate(positions):
            a, b = lines(position)
            ctx.set(dut.a, a)
            ctx.set(dut.b, b)
            ctx.set(dut.clear, clock in clear_at)
            await ctx.tick()
            seen.append((ctx.get(dut.count), ctx.get(dut.illegal)))

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(testbench)
    sim.run()
    return seen


#: Clocks from a line's change on the pins to the count's: two synchroniser flip-flops, then
#: the count's register.
LATENCY = 3


def expected(positions, *, clear_at=()):
    """The belt model: the count follows the position by :data:`LATENCY` clocks, moving by
    the steps of one edge; a step of two edges (both lines changed) is not counted but is an
    illegal transition, and a step of three is one edge the other way (as the lines see it)."""
    count = illegal = 0
    out = []
    for clock in range(len(positions)):
        seen_now = clock - LATENCY + 1
        if clock in clear_at:
            # (A clear acts on the clock it is set on; the step seen then is lost.)
            count = illegal = 0
        elif seen_now >= 1:
            step = (positions[seen_now] - positions[seen_now - 1]) % 4
            count += {0: 0, 1: 1, 2: 0, 3: -1}[step]
            illegal += step == 2
        out.append((count, illegal))
    return out


def test_a_belt_forward_then_back_is_counted_edge_for_edge():
    positions = [0] * 5 + list(range(0, 400)) + [399] * 4 + list(range(399, -150, -1)) + \
        [-150] * 5
    got = decode(positions)
    assert got == expected(positions)
    assert got[-1] == (-150, 0)


def test_slow_steps_and_a_standing_belt():
    positions = [k // 7 for k in range(300)] + [42] * 20
    assert decode(positions) == expected(positions)


@settings(max_examples=20, deadline=None)
@given(st.lists(st.sampled_from([-1, 0, 0, 1, 1, 2, -2]), min_size=20, max_size=120),
       st.sets(st.integers(0, 119), max_size=3))
def test_noise_counts_illegal_transitions_and_never_a_jump(steps, clear_at):
    positions = [0]
    for step in steps:
        positions.append(positions[-1] + step)
    got = decode(positions, clear_at=clear_at)
    assert got == expected(positions, clear_at=clear_at)
    # Never more than one edge a clock, whatever the lines do (but where cleared).
    counts = [count for count, _ in got]
    assert all(abs(counts[k] - counts[k - 1]) <= 1 for k in range(1, len(counts))
               if k not in clear_at)


def test_the_count_saturates_and_never_wraps():
    dut = QuadratureDecoder()
    top = 2 ** (COUNT_BITS - 1) - 1
    seen = []

    async def testbench(ctx):
        # Start 3 below the top (the count's register set directly), then run forward.
        ctx.set(dut.count, top - 3)
        for position in range(12):
            ctx.set(dut.a, lines(position)[0])
            ctx.set(dut.b, lines(position)[1])
            await ctx.tick()
            seen.append(ctx.get(dut.count))

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(testbench)
    sim.run()
    assert seen[-1] == top and max(seen) == top and sorted(seen) == seen


def test_the_illegal_count_saturates():
    positions = [2 * k for k in range(2 ** 8)]
    dut = QuadratureDecoder()

    async def testbench(ctx):
        ctx.set(dut.illegal, 2 ** ILLEGAL_BITS - 3)
        for position in positions:
            ctx.set(dut.a, lines(position)[0])
            ctx.set(dut.b, lines(position)[1])
            await ctx.tick()
        assert ctx.get(dut.illegal) == 2 ** ILLEGAL_BITS - 1
        assert ctx.get(dut.count) == 0

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(testbench)
    sim.run()


@pytest.mark.parametrize("period, reverse", [(2, False), (5, False), (3, True), (0, False)])
def test_the_simulated_encoder_steps_one_edge_a_period(period, reverse):
    dut = SimulatedEncoder()
    states = []

    async def testbench(ctx):
        ctx.set(dut.period, period)
        ctx.set(dut.reverse, reverse)
        ctx.set(dut.enable, 1)
        for _ in range(200):
            await ctx.tick()
            states.append((ctx.get(dut.a), ctx.get(dut.b)))
        ctx.set(dut.enable, 0)
        for _ in range(20):
            await ctx.tick()
            states.append((ctx.get(dut.a), ctx.get(dut.b)))

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(testbench)
    sim.run()
    # Read back through lines(): each change is one edge in the asked direction, every
    # max(period, 2) clocks, and the lines stand still once disabled.
    inverse = {lines(p): p for p in range(4)}
    changes = [k for k in range(1, len(states)) if states[k] != states[k - 1]]
    for k in changes:
        step = (inverse[states[k]] - inverse[states[k - 1]]) % 4
        assert step == (3 if reverse else 1)
    gaps = {b - a for a, b in zip(changes, changes[1:])}
    assert gaps == {max(period, 2)}
    assert changes[-1] < 200 + 2


@pytest.mark.parametrize("bits", [1, 33, 8.0, True])
def test_the_simulated_encoders_period_width_is_checked(bits):
    with pytest.raises(ValueError, match="period_bits"):
        SimulatedEncoder(period_bits=bits)


@pytest.mark.parametrize("bits", [1, 65, 32.0, True])
def test_the_decoders_count_width_is_checked(bits):
    with pytest.raises(ValueError, match="count_bits"):
        QuadratureDecoder(count_bits=bits)
