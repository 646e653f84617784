"""The tests' simulated board itself (tests/support/sim_board.py): what it records is what the pins did."""

import random

import pytest

from galvoscan.link.client import HostClient

from sim_board import SimBoard, SimUARTTransport


@pytest.mark.parametrize("backend", ["python", "compiled"])
def test_laser_pins_recorded_by_changes_equal_a_sample_on_every_clock(backend):
    """The laser pins are recorded as they change and made into one entry a clock; a board that
    samples them on every clock instead (slower) sees the same, clock for clock, through
    arming, emission, the interlock and the alarms changing between clock edges, and runs that
    end anywhere in a clock. (Sampled on Amaranth's simulator; recorded by changes on either
    backend.)"""
    boards = []
    for record in ("every clock", True):
        rng = random.Random(5)
        # (The spiral-only build with a 0.1 ms lead: the laser fuzz's, whose compiled model
        # this shares; the spiral makes the armed laser emit.)
        board = SimBoard(mo_lead=100e-6, record_laser=record, backend=backend,
                         modes=("spiral",), correction=None)
        client = HostClient(SimUARTTransport(board))
        client.write("laser_prr", 2000)
        client.write("arm", 1)
        lengths = []
        for _ in range(10):
            if rng.random() < 0.4:
                board.interlock_closed = not board.interlock_closed
            if rng.random() < 0.2:
                board.alarms_clear = not board.alarms_clear
            if rng.random() < 0.4:
                client.write(*rng.choice([("arm", 1), ("fault_clear", 1), ("guide", 1),
                                          ("arm", 0), ("keepalive", 1)]))
            board.run_for(rng.random() * 20e-6 + rng.choice([0, 0.1e-6, 0.5 / board.clk_freq]))
            lengths.append(len(board.laser_pins))
        boards.append((board, lengths))
    (sampled, sampled_lengths), (recorded, recorded_lengths) = boards
    assert recorded.laser_pins == sampled.laser_pins
    assert recorded.sync_pins == sampled.sync_pins
    assert recorded_lengths == sampled_lengths
    # The run did what is worth recording: emission, and the interlock open and closed.
    assert any(pins[1] for pins in sampled.laser_pins)
    assert {pins[3] for pins in sampled.laser_pins} == {0, 1}
