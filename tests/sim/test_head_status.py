"""The scan head's status through the pins of the system top (#38), on both simulated
backends: the board's head (galvoscan/sim/head.py) answers each frame on ``xy2_status``, the
host reads ``head``, ``head_state`` and ``head_bad`` through the real link, and a head that
grows hot mid-job turns every laser output off, latched, as an open interlock does."""

import pytest

from galvoscan.gateware.host.regmap import HeadState, HeadStatus, STATUS_BITS
from galvoscan.link.client import HostClient
from galvoscan.sim.board import LASER_PINS, SimTransport, SimulatedBoard
from galvoscan.sim.head import HEALTHY_HEAD
from galvoscan.gateware.phy.xy2_100 import FRAME_BITS

from sim_board import QUICK_SIM_BOARD


BUILD = dict(QUICK_SIM_BOARD, head_status=True, head_check=True)
TEMP_OK = 1 << HeadStatus["temp_ok"].offset
POWER_OK = 1 << HeadStatus["power_ok"].offset
MISSING = 1 << HeadState["missing"].offset
FAULT = 1 << HeadState["fault"].offset
FRAME_S = 10e-6


def enable_changes(board):
    """(clock, level) of each change of laser_enable (the first of the recorded laser pins)."""
    assert LASER_PINS[0] == "laser_enable"
    return [(clock, pins[0]) for clock, pins in board.laser_changes]


def run(backend):
    """A host's session: the head read, the laser armed and emitting in the spiral, the head's
    Temp OK dropped, the fault read, cleared while hot (refused), the head well again, cleared,
    re-armed. Returns the readings and the board."""
    board = SimulatedBoard(backend=backend, **BUILD)
    client = HostClient(SimTransport(board))
    readings = {"head": client.read("head"), "state": client.read("head_state"),
                "check": client.read("head_check")}
    bad_at_start = client.read("head_bad")
    client.write("laser_prr", 500)
    client.write("watchdog", 5000)
    client.write("arm", 1)
    board.run_for(0.6e-3)                   # past the MO lead: the spiral marks
    assert board.pulses, "no pulse before the head's fault"
    readings["armed"] = client.read("status")
    hot_from = len(board.sync_rises)
    board.head_word = HEALTHY_HEAD & ~TEMP_OK
    board.run_for(4 * FRAME_S)
    readings["hot"] = (client.read("head"), client.read("head_state"), client.read("status"))
    client.write("fault_clear", 1)          # still hot: the fault stays
    readings["cleared_hot"] = client.read("head_state")
    board.head_word = HEALTHY_HEAD
    board.run_for(3 * FRAME_S)
    client.write("fault_clear", 1)
    readings["cleared"] = client.read("head_state")
    client.write("arm", 0)
    client.write("arm", 1)
    board.run_for(0.1e-3)
    readings["rearmed"] = client.read("status")
    readings["bad"] = client.read("head_bad") - bad_at_start
    return readings, board, hot_from


@pytest.fixture(scope="module")
def sessions():
    """:func:`run` on each backend, once for the module's tests (in one xdist group, so that
    one worker runs them)."""
    return {backend: run(backend) for backend in ("compiled", "python")}


@pytest.mark.xdist_group("head_sessions")
@pytest.mark.parametrize("backend", ["compiled", "python"])
def test_a_head_that_grows_hot_stops_the_laser_latched(sessions, backend):
    readings, board, hot_from = sessions[backend]
    assert readings["head"] == HEALTHY_HEAD and readings["state"] == 0
    assert readings["check"] == 1
    assert readings["armed"] >> STATUS_BITS["laser_ready"] & 1
    word, state, status = readings["hot"]
    assert word == HEALTHY_HEAD & ~TEMP_OK
    assert state == FAULT, "the head fault is latched, the head not missing"
    assert status >> STATUS_BITS["armed"] & 1 and not status >> STATUS_BITS["laser_enable"] & 1
    assert readings["cleared_hot"] == FAULT, "a clear while the head is hot clears nothing"
    assert readings["cleared"] == 0
    assert readings["rearmed"] >> STATUS_BITS["laser_enable"] & 1
    assert readings["bad"] == 0, "a head's good frames are never counted as refused"
    # The bound: the first frame with the word the head sends hot begins at a SYNC rise; its
    # parity bit is the last, sampled a bit's clocks into the next frame; two synchroniser
    # clocks, one to take the frame: laser_enable falls within a frame and one bit and 4 clocks
    # of that SYNC rise.
    clocks_per_bit = int(BUILD["clk_freq"] / 2e6)
    first_hot = board.sync_rises[hot_from]      # (the head sends a word from the next frame)
    fall = next(clock for clock, level in enable_changes(board) if level == 0 and
                clock >= first_hot)
    assert fall - first_hot <= (FRAME_BITS + 1) * clocks_per_bit + 4, fall - first_hot
    # And every laser output low from that clock on, until the re-arm.
    after = [pins for clock, pins in board.laser_changes if fall <= clock]
    assert not any(after[0]), dict(zip(LASER_PINS, after[0]))


@pytest.mark.parametrize("backend", ["compiled", "python"])
def test_no_head_reads_missing_and_the_laser_stays_off(backend):
    board = SimulatedBoard(backend=backend, head_word=None, **BUILD)
    client = HostClient(SimTransport(board))
    assert client.read("head") == 0
    assert client.read("head_state") == MISSING
    refused = client.read("head_bad")
    assert refused >= 1, "frames with the line low are counted as refused"
    client.write("arm", 1)
    board.run_for(0.2e-3)
    assert client.read("head_state") == MISSING | FAULT
    assert not client.read("status") >> STATUS_BITS["laser_enable"] & 1
    assert not board.pulses
    assert client.read("head_bad") > refused


def test_with_the_check_off_the_head_is_only_reported():
    # (The build's check on at power-up, written off: the model the other tests use.)
    board = SimulatedBoard(backend="compiled", head_word=HEALTHY_HEAD & ~POWER_OK, **BUILD)
    client = HostClient(SimTransport(board))
    client.write("head_check", 0)
    assert client.read("head_check") == 0
    assert client.read("head") == HEALTHY_HEAD & ~POWER_OK
    client.write("laser_prr", 500)
    client.write("arm", 1)
    board.run_for(0.6e-3)
    assert client.read("head_state") == 0
    assert client.read("status") >> STATUS_BITS["laser_ready"] & 1


@pytest.mark.xdist_group("head_sessions")
def test_both_backends_keep_the_same_records(sessions):
    (a, compiled, _), (b, python, _) = sessions["compiled"], sessions["python"]
    assert a == b
    for name in ("frames", "sync_rises", "pulses", "laser_changes"):
        assert getattr(compiled, name) == getattr(python, name), name
