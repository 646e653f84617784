"""The simulated line's part sensor (galvoscan/sim/board.py's PartSensor): the moments it comes
to a part or leaves it, against its own description (a part first_s after it was set, then
one every every_s, each seen seen_s), sampled; and a board stepped in one long step (a host's
poll) still sees a part that came and went inside it."""

import math

from hypothesis import given, strategies as st

from galvoscan.sim.board import PartSensor, SimulatedBoard

from sim_board import IO_BOARD


#: Times in whole µs, as a board's are (a clock is 0.04 … 0.125 µs).
_us = st.integers


@given(_us(0, 50_000), _us(100, 10_000), st.one_of(st.none(), _us(11_000, 50_000)),
       _us(0, 1_000_000), _us(0, 200_000))
def test_the_sensor_changes_where_it_says(start_us, seen_us, every_us, first_us, now_us):
    start_s, seen_s, first_s, now = start_us / 1e6, seen_us / 1e6, first_us / 1e6, now_us / 1e6
    every_s = None if every_us is None else every_us / 1e6
    sensor = PartSensor(first_s=first_s, every_s=every_s, seen_s=seen_s, start_s=start_s)
    change = sensor.next_change(now)
    assert change > now or math.isclose(change, now, abs_tol=1e-12)
    if math.isinf(change):
        # Never again: the one part has gone by.
        assert every_s is None and now >= start_s + first_s + seen_s - 1e-12
        return
    # The same all the way to the change (a little inside it), the other just after.
    seen = sensor.seen(now + 1e-9)
    for k in range(1, 10):
        at = now + (change - now) * k / 10
        if change - at > 1e-9:
            assert sensor.seen(at) == seen
    assert sensor.seen(change + 1e-9) != seen


def test_a_long_step_still_sees_the_part():
    """One 20 ms step (a host's status poll) over a part seen for 2 ms of it: the board's
    input was high for it, as its io register's wait shows: a wait for the part ends."""
    board = SimulatedBoard(backend="compiled", **IO_BOARD)
    changes = []
    board.parts_arrive(input=0, first_s=5e-3, seen_s=2e-3)
    start = board.now
    original = board.engine.run_until

    def run_until(when):
        changes.append((round((when - start) * 1e3, 6), board.io_inputs))
        return original(when)
    board.engine.run_until = run_until
    board.run_for(20e-3)
    assert changes == [(5.0, 0), (7.0, 1), (20.0, 0)]
