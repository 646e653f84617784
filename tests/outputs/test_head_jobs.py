"""Jobs and the scan head's status (#38): the real job streamer, through the real link, into a
simulated board with the head status receiver and a head on its STATUS line
(galvoscan/sim/head.py). A head that reports a fault refuses the job before anything is
armed; one that grows hot mid-job stops it, laser off, in one line; a missing head stops a
job only when the laser is to obey it."""

import pytest

from galvoscan.gateware.host.regmap import HeadStatus, STATUS_BITS
from galvoscan.link.client import HostClient
from galvoscan.outputs.queue_words import job_segments
from galvoscan.outputs.stream import JobAborted, JobStreamer
from galvoscan.sim.board import SimTransport, SimulatedBoard
from galvoscan.sim.head import HEALTHY_HEAD

from sim_board import QUICK_SIM_BOARD, VECTOR_BOARD


# (A short queue: the streamer reports progress, where the test acts, as it drains.)
HEAD_BOARD = dict(VECTOR_BOARD, **QUICK_SIM_BOARD, head_status=True, vector_queue_depth=8)
TEMP_OK = 1 << HeadStatus["temp_ok"].offset
# A square, marked round and round: long enough to be stopped in the middle.
SQUARE = [("jump", 30000, 30000)] + [
    ("mark", x, y) for _ in range(6)
    for x, y in ((35000, 30000), (35000, 35000), (30000, 35000), (30000, 30000))]
REGISTERS = {"pitch": 40, "pulses_per_point": 1, "laser_prr": 500, "laser_power": 100,
             "jump_delay": 20}


def board_and_streamer(**kwargs):
    board = SimulatedBoard(backend="compiled", **HEAD_BOARD, **kwargs)
    return board, JobStreamer(HostClient(SimTransport(board)), poll_s=50e-6)


def never_armed(board):
    """No laser pin ever rose (laser_enable first among them)."""
    return not any(any(pins) for _, pins in board.laser_changes[1:])


def test_a_hot_head_refuses_the_job_before_anything_is_armed():
    board, streamer = board_and_streamer(head_word=HEALTHY_HEAD & ~TEMP_OK)
    with pytest.raises(JobAborted) as refused:
        streamer.run_vector(SQUARE, REGISTERS)
    message = str(refused.value)
    assert "Temp OK low" in message and "not starting" in message and "\n" not in message
    assert never_armed(board) and not board.pulses


def test_a_missing_head_refuses_a_job_that_obeys_it_and_not_one_that_does_not():
    board, streamer = board_and_streamer(head_word=None)
    with pytest.raises(JobAborted) as refused:
        streamer.run_vector(SQUARE, dict(REGISTERS, head_check=1))
    assert "no answer on its STATUS line" in str(refused.value)
    assert never_armed(board)
    # head_check 0: a head without the line; the job marks.
    report = streamer.run_vector(SQUARE, dict(REGISTERS, head_check=0))
    assert report.segments == len(job_segments(SQUARE)) and report.pulses and board.pulses


def test_a_head_that_grows_hot_mid_job_stops_it_laser_off():
    board, streamer = board_and_streamer()
    client = streamer.board

    def grow_hot(taken):
        if len(board.pulses) > 200 and board.head_word == HEALTHY_HEAD:
            board.head_word = HEALTHY_HEAD & ~TEMP_OK
    streamer.progress = grow_hot
    with pytest.raises(JobAborted) as stopped:
        streamer.run_vector(SQUARE, dict(REGISTERS, head_check=1))
    message = str(stopped.value)
    assert "scan head reported a fault (Temp OK low)" in message, message
    assert "the part is not done" in message
    assert board.pulses, "the job marked before the head grew hot"
    status = client.read("status")
    assert not status >> STATUS_BITS["laser_enable"] & 1 and not status >> STATUS_BITS["armed"] & 1
    # Nothing emitted after the frame that took the hot word, and the fault latched.
    assert client.read("head_state") == 0b10


def test_head_check_on_a_board_that_cannot_read_the_head_is_refused():
    board = SimulatedBoard(backend="compiled", **VECTOR_BOARD, **QUICK_SIM_BOARD)
    streamer = JobStreamer(HostClient(SimTransport(board)), poll_s=50e-6)
    with pytest.raises(JobAborted) as refused:
        streamer.run_vector(SQUARE, dict(REGISTERS, head_check=1))
    assert "--head-status" in str(refused.value)
    assert never_armed(board)
    # head_check 0 is not written (there is no register) and the job runs.
    assert streamer.run_vector(SQUARE[:3], dict(REGISTERS, head_check=0)).segments == \
        len(job_segments(SQUARE[:3]))
