"""The start input (gateware/player/start_input.py): debounced presses of active-low pins."""

import pytest
from amaranth.sim import Simulator

from galvoscan.gateware.player.start_input import StartInput, debounce_ticks


def presses(levels, *, debounce_ms=1, inputs=2):
    """Drive ``levels`` (one value of ``start_n`` per 10 µs tick) and return the ticks on
    which ``pressed`` was high."""
    dut = StartInput(inputs=inputs, debounce_ms=debounce_ms)
    seen = []

    async def testbench(ctx):
        for k, level in enumerate(levels):
            ctx.set(dut.start_n, level)
            for clock in range(4):              # a tick every fourth clock
                ctx.set(dut.tick, clock == 0)
                await ctx.tick()
                if ctx.get(dut.pressed):
                    seen.append(k)

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(testbench)
    sim.run()
    return seen


def test_a_press_counts_once_after_the_debounce():
    levels = [0b11] * 10 + [0b10] * 250 + [0b11] * 150
    seen = presses(levels)
    # 1 ms = 100 ticks after the press (plus the synchroniser's clocks): once.
    assert len(seen) == 1 and 100 <= seen[0] - 10 <= 102


def test_bounce_shorter_than_the_debounce_is_ignored():
    bouncing = ([0b10] * 30 + [0b11] * 5) * 5
    assert presses([0b11] * 5 + bouncing + [0b11] * 200) == []


def test_either_pin_starts_and_a_held_press_starts_once():
    assert len(presses([0b11] * 5 + [0b01] * 400 + [0b11] * 120 + [0b00] * 120)) == 2


@pytest.mark.parametrize("ms", [0, 1024, 2.5, True])
def test_debounce_is_checked(ms):
    with pytest.raises(ValueError, match="debounce"):
        debounce_ticks(ms, 10)
