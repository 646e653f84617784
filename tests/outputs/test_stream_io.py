"""The streamer's I/O steps (galvoscan/outputs/stream.py): refused, nothing written, by a board
whose ``caps`` lack I/O in the queue (or the fly, for the fly's steps); a job whose queue
starts the fly leaves the count and the fly to it; and on the simulated board with I/O, a wait
for a part that never comes stops the job at its time-out with every laser output off, the
queue flushed, so that the next job runs."""

import pytest

from galvoscan.gateware.fields import FlyControl, IOKind, pack
from galvoscan.geometry.segments import IOStep
from galvoscan.link.client import HostClient
from galvoscan.outputs.stream import JobAborted, JobRefused, JobStreamer
from galvoscan.sim.board import SimTransport, SimulatedBoard
from galvoscan.sim.contract import LASER_PINS

from fake_board import FakeBoard
from sim_board import IO_BOARD


#: ``caps`` bits as the registers page gives them: bit 13 fly, bit 15 io.
FLY_BIT, IO_BIT = 13, 15
WAIT = IOStep(IOKind.WAIT_INPUT, arg_x=2)           # 2 ms at most
DONE = IOStep(IOKind.SET_OUTPUT, arg_x=100)
SQUARE = [("jump", 30000, 30000), ("mark", 31000, 30000), ("mark", 31000, 31000)]


def fake(*bits):
    board = FakeBoard()
    for bit in bits:
        board.values["caps"] |= 1 << bit
    return board


@pytest.mark.parametrize("bits, steps, message", [
    ((), [WAIT], "no I/O in the queue"),
    ((), [DONE], "no I/O in the queue"),
    ((IO_BIT,), [IOStep(IOKind.FLY_START)], "no marking on the fly"),
    ((IO_BIT,), [IOStep(IOKind.WAIT_COUNT_UP, arg_x=5)], "no marking on the fly"),
])
def test_a_board_without_it_refuses_before_any_write(bits, steps, message):
    board = fake(*bits)
    with pytest.raises(JobRefused, match=message):
        JobStreamer(board, poll_s=0).run_vector([*steps, *SQUARE], {"pitch": 60}, timeout_s=5)
    assert board.log == []


def test_a_queued_fly_start_leaves_the_count_and_the_fly_to_the_queue():
    board = fake(IO_BIT, FLY_BIT)
    fly_off = pack(FlyControl, x_simulated=1)
    steps = [WAIT, IOStep(IOKind.FLY_START), *SQUARE, IOStep(IOKind.FLY_END), DONE]
    JobStreamer(board, poll_s=0).run_vector(steps, {"pitch": 60, "fly_ctrl": fly_off},
                                            timeout_s=5)
    names = [name for name, _ in board.log]
    assert "fly_clear" not in names
    # fly_ctrl written once with the fly off (the setting) and again off at the end; never on.
    assert [value for name, value in board.log if name == "fly_ctrl"] == [fly_off, fly_off]
    # The I/O words went in the queue, in order, around the segments.
    ops = [value for name, value in board.log if name == "vec_op"]
    assert ops[0] >> 9 == 1 and ops[1] >> 9 == 1 and ops[-1] >> 9 == 1
    # Ended by flushing the queue (a held wait dropped), after the laser was disarmed.
    assert names.index("vec_flush", names.index("arm", names.index("run"))) > 0


def test_a_part_that_never_comes_stops_the_job_and_the_next_one_runs():
    board = SimulatedBoard(backend="compiled", **IO_BOARD)
    client = HostClient(SimTransport(board))
    streamer = JobStreamer(client)
    with pytest.raises(JobAborted, match="no part came: input 0 was not high within 2 ms") \
            as stopped:
        streamer.run_vector([WAIT, *SQUARE, DONE], {"pitch": 60}, timeout_s=5)
    assert not stopped.value.complete and stopped.value.taken == 0
    # Every laser output off, no pulse, no output set.
    pins = dict(zip(LASER_PINS, board.laser_changes[-1][1]))
    assert not any(pins[name] for name in ("laser_enable", "laser_mo", "laser_am",
                                           "laser_guide"))
    assert board.pulses == [] and board.io_changes == []
    # The queue was flushed: the time-out cleared, the next job (no wait) marks whole.
    assert client.read("io") >> 4 == 0
    board.parts_arrive(first_s=0.5e-3, every_s=1e-3, seen_s=0.3e-3)
    report = streamer.run_vector([WAIT, *SQUARE, DONE], {"pitch": 60}, timeout_s=5)
    assert report.clean and report.pulses > 0
    assert [value for _, value in board.io_changes] == [1, 0]
