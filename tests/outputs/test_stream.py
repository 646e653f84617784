"""The job streamer (galvoscan/outputs/stream.py): against a fake board for its protocol, and
against the simulated board over a pseudo-terminal for what the laser pins do when a job is
stopped."""

import _thread
import signal
import threading
import time

import pytest

from galvoscan.link.client import ClientError, HostClient, SerialTransport
from galvoscan.gateware.host.regmap import BY_NAME
from galvoscan.outputs.stream import JobAborted, JobStreamer

# The simulated boards here run vector jobs alone (VECTOR_BOARD: vector mode only, no
# correction stage; the job's CPU 15-20 % less than on the default build, whose vector path the
# wobble mark, clean, job and link tests run).
from fake_board import FakeBoard, job
from link_codec import cobs_decode
from sim_board import QUICK_SIM_BOARD, VECTOR_BOARD


def test_every_segment_goes_in_order_and_the_queue_never_overflows():
    board = FakeBoard(drain=50)
    report = JobStreamer(board, batch=100, poll_s=0).run_vector(job(2000), {"pitch": 60},
                                                                    timeout_s=5)
    ops = [(board.log[i][1], board.log[i + 1][1], board.log[i + 2][1])
           for i, (name, _) in enumerate(board.log) if name == "vec_x"]
    expected = [(x, y) for _, x, y in job(2000)]
    assert [(x, y) for x, y, _ in ops][:2000] == expected
    # A job that ends on a mark gets a jump to where it ended.
    assert ops[-1] == (expected[-1][0], expected[-1][1], 0)
    assert report.segments == 2001
    names = [name for name, _ in board.log]
    # Parameters before the first segment, armed before run, disarmed at the end.
    assert names.index("pitch") < names.index("vec_x")
    assert names.index("arm") < names.index("run", names.index("arm"))
    assert board.log[-3:] == [("arm", 0), ("run", 0), ("guide", 0)]


def test_scaled_polygon_delay_rides_in_vec_op():
    """polygon_scaled: each mark after a mark carries its corner's hold, polygon_delay ×
    (1 - cos φ) in 10 µs frames rounded up, in vec_op bits 7:1; jumps and first marks none."""
    board = FakeBoard()
    square = [("jump", 30000, 30000), ("mark", 31000, 30000), ("mark", 32000, 30000),
              ("mark", 32000, 31000), ("mark", 32000, 30000), ("mark", 33000, 31000),
              ("mark", 33000, 31000), ("jump", 30000, 30000)]
    JobStreamer(board, poll_s=0).run_vector(square, {"polygon_delay": 100, "polygon_scaled": 1},
                                            timeout_s=5)
    ops = [value for name, value in board.log if name == "vec_op"]
    # straight on: 0; a right angle: 10 frames; a reversal: 20; 135°: 1.707 → 18; zero
    # length: 0.
    assert ops == [0, 1, 1 | 0 << 1, 1 | 10 << 1, 1 | 20 << 1, 1 | 18 << 1, 1, 0]
    board = FakeBoard()
    JobStreamer(board, poll_s=0).run_vector(square, {"polygon_delay": 100, "polygon_scaled": 0},
                                            timeout_s=5)
    assert [v for n, v in board.log if n == "vec_op"] == [0, 1, 1, 1, 1, 1, 1, 0]


def test_corner_frames_refuses_a_bad_delay_and_caps_at_the_field():
    from galvoscan.geometry.corners import corner_frames
    for bad in (-1, float("nan"), "100", True):
        with pytest.raises(ValueError):
            corner_frames([("mark", 1, 1)], bad)
    reversal = [("mark", 40000, 32768), ("mark", 32768, 32768)]
    assert corner_frames(reversal, 4095) == [0, 127]          # 819 frames, capped


def test_the_queue_depth_is_the_boards():
    """A board whose queue is shorter than the bitstream's 512 (a simulated one): the streamer
    reads its depth while it is empty, and never writes into a full queue."""
    board = FakeBoard(drain=10, depth=32)
    report = JobStreamer(board, poll_s=0).run_vector(job(300), {}, timeout_s=5)
    assert report.segments == 301
    assert sum(1 for name, _ in board.log if name == "vec_op") == 301


def test_a_board_with_segments_left_is_refused():
    board = FakeBoard()
    board.values["run"] = 0
    board.queue = 3                             # an earlier job's, not running
    with pytest.raises(JobAborted, match="still holds segments"):
        JobStreamer(board, poll_s=0).run_vector(job(10), {})
    assert board.log == []


def test_a_fault_mid_job_disarms_first():
    board = FakeBoard(drain=1)
    streamer = JobStreamer(board, batch=64, poll_s=0)
    original = board.read

    def read(name):
        if name == "fifo_free" and len(board.log) > 3 * 600:
            board.flags.add("fault_interlock")
        return original(name)
    board.read = read
    with pytest.raises(JobAborted, match="interlock"):
        streamer.run_vector(job(2000), {})
    assert board.log[-3:] == [("arm", 0), ("run", 0), ("guide", 0)]


def test_a_lost_link_still_tries_to_disarm():
    board = FakeBoard(fail_after=200)
    # The link's failure, and how far the job got, in one exception.
    with pytest.raises(JobAborted, match="no answer from the board; stopped at segment .* of "
                                         "1001: the part is not done") as stopped:
        JobStreamer(board, poll_s=0).run_vector(job(1000), {})
    assert isinstance(stopped.value.__cause__, ClientError)


@pytest.mark.parametrize("flags, words", [(("armed",), "armed already"),
                                          (("fault_alarm",), "alarm"),
                                          (("interlock_open",), "interlock")])
def test_a_board_not_ready_is_refused_before_anything_is_written(flags, words):
    board = FakeBoard(flags=flags)
    with pytest.raises(JobAborted, match=words):
        JobStreamer(board, poll_s=0).run_vector(job(10), {"pitch": 60})
    assert board.log == []


def test_a_board_without_the_mode_is_refused():
    board = FakeBoard(missing=["vec_op"])
    with pytest.raises(JobAborted, match="no vector mode"):
        JobStreamer(board, poll_s=0).run_vector(job(10), {})
    # Nothing written but the disarm every job ends with, and nothing refused.
    assert board.log == [("arm", 0), ("run", 0), ("guide", 0)]
    assert board.values["errors"] == 0


def test_a_bitstream_without_the_capability_register_is_one_line():
    board = FakeBoard(missing=["caps"])
    with pytest.raises(JobAborted, match="build and flash it again") as stop:
        JobStreamer(board, poll_s=0).run_vector(job(10), {"pitch": 60})
    assert "\n" not in str(stop.value)
    assert ("arm", 1) not in board.log


def test_a_board_without_the_delays_marks_without_them_and_says_so(capsys):
    """The default bitstream has no delays: their registers are unknown addresses there (a read
    gets no answer). The job is sent without them, with one line saying so, and no corner
    holds ride in vec_op (the board's vec_op takes 0 and 1 only)."""
    from galvoscan.gateware.host.regmap import DELAY_REGISTERS
    board = FakeBoard(missing=DELAY_REGISTERS)
    square = [("jump", 30000, 30000), ("mark", 31000, 30000), ("mark", 31000, 31000),
              ("jump", 30000, 30000)]
    delays = {"laser_on_delay": 100, "laser_off_delay": 50, "mark_delay": 100,
              "polygon_delay": 100, "polygon_scaled": 1}
    report = JobStreamer(board, poll_s=0).run_vector(square, {"pitch": 60, **delays},
                                                     timeout_s=5)
    assert report.segments == 4
    written = {name for name, _ in board.log}
    assert not written & set(DELAY_REGISTERS) and "pitch" in written
    assert [v for n, v in board.log if n == "vec_op"] == [0, 1, 1, 0]
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no laser or scanner delays" in err
    # Found out without waiting for an answer that does not come, nor a write refused: the
    # board's own error count is untouched.
    assert board.unanswered == []
    assert report.counters["errors"] == 0 and board.values["errors"] == 0
    # A board with them gets them.
    board = FakeBoard()
    JobStreamer(board, poll_s=0).run_vector(square, {"pitch": 60, **delays}, timeout_s=5)
    assert set(DELAY_REGISTERS) <= {name for name, _ in board.log}


@pytest.mark.slow
def test_ctrl_c_mid_job_turns_the_laser_pins_off_within_a_frame():
    """A real KeyboardInterrupt while the laser emits: the streamer's first frame after it is
    arm = 0, and from the end of that frame every laser output is low within one XY2-100
    frame (10 µs)."""
    from galvoscan.sim.board import LASER_PINS, PTYServer, SimulatedBoard
    board = SimulatedBoard(**QUICK_SIM_BOARD, **VECTOR_BOARD)
    emitting = threading.Event()
    run_for = board.run_for

    def run_then_look(seconds):
        # The server's thread looks after each step of the board: the first laser pulse is
        # the sign the job is mid-way with the laser on, in the board's own time however
        # busy the machine (a watcher polling in host time could miss it or come late).
        run_for(seconds)
        if board.pulses and not emitting.is_set():
            emitting.set()
            _thread.interrupt_main()                # what Ctrl-C does
    board.run_for = run_then_look
    server = PTYServer(board).start()
    # A shell that starts the tests in the background has them ignore SIGINT, and Python then
    # leaves it ignored: interrupt_main() would do nothing. Ctrl-C as a terminal delivers it.
    handler = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with SerialTransport(server.port, timeout=60) as link:
            client = HostClient(link)
            streamer = JobStreamer(client, poll_s=0.01)
            # 4 marks of 250 points each at 50 kHz: 20 ms of emission, far more than the host
            # takes to stop it once interrupted (the interrupt cuts it short).
            segments = [("jump", 30000, 30000)] + \
                [("mark", 30000 + 3000 * (i % 2), 30000 + 40 * i) for i in range(1, 5)]
            with pytest.raises(KeyboardInterrupt):
                streamer.run_vector(segments, {"pitch": 12, "pulses_per_point": 1,
                                               "laser_prr": 500, "laser_power": 40},
                                    ready_timeout_s=600, timeout_s=600)
            interrupted_at = len(board.bytes_in)
        # Let the board take what the host sent after the interrupt, and run on a while.
        deadline = time.monotonic() + 120
        # (The disarm went out before run_vector raised: look a few frames back.)
        since = max(0, interrupted_at - 12 * 16)
        while disarmed_at(board.bytes_in, since) is None:
            assert time.monotonic() < deadline, "the disarm frame never reached the board"
            time.sleep(0.1)
        until = board.now + 200e-6
        while board.now < until:
            time.sleep(0.1)
    finally:
        signal.signal(signal.SIGINT, handler)
        server.stop()
    assert emitting.is_set()
    frame_done = disarmed_at(board.bytes_in, since)
    clocks_per_frame = board.clk_freq * 10e-6
    changes_after = [(cycle, pins) for cycle, pins in board.laser_changes
                     if cycle >= frame_done]
    last_on = [cycle for cycle, pins in changes_after
               if any(pins[LASER_PINS.index(name)] for name in
                      ("laser_enable", "laser_mo", "laser_am", "laser_prr", "laser_latch"))]
    off_by = max(last_on, default=frame_done)
    # The pins' state from the last change on: all low, within a frame of the arm = 0 frame.
    final = [pins for cycle, pins in board.laser_changes][-1]
    assert not any(final[LASER_PINS.index(name)] for name in
                   ("laser_enable", "laser_mo", "laser_am", "laser_prr", "laser_latch"))
    assert off_by - frame_done <= clocks_per_frame


def disarmed_at(bytes_in, since):
    """The clock the first ``arm = 0`` frame (COBS-decoded by the tests' own codec) received
    after byte ``since`` ended (its zero byte's stop bit), or None."""
    packet = b""
    for cycle, byte in list(bytes_in)[since:]:
        if byte:
            packet += bytes([byte])
            continue
        frame = cobs_decode(packet) if packet else None
        packet = b""
        if frame and len(frame) == 10 and frame[1] == BY_NAME["arm"].address and \
                frame[2:4] == b"\0\0":
            return cycle
    return None


@pytest.mark.slow
def test_framing_traces_the_box_with_the_guide_laser_and_the_laser_off():
    """`--frame`: the job's bounding box walked with the guide laser on, never armed."""
    from galvoscan.plan.vector_job import box_outline, frame_segments
    from galvoscan.sim.board import LASER_PINS, SimTransport, SimulatedBoard
    board = SimulatedBoard(**QUICK_SIM_BOARD, **VECTOR_BOARD)
    client = HostClient(SimTransport(board))
    box = (-1.0, -0.5, 1.0, 0.5)                      # mm
    segments = frame_segments(box_outline(box), 110, 2)
    JobStreamer(client, poll_s=0).run_vector(
        segments, {"pitch": 100, "pulses_per_point": 1, "laser_prr": 500, "jump_delay": 1,
                   "laser_power": 0, "guide": 1}, armed=False, timeout_s=1e9)
    guide = LASER_PINS.index("laser_guide")
    emission = [LASER_PINS.index(name) for name in ("laser_enable", "laser_mo", "laser_am",
                                                    "laser_latch")]
    assert any(pins[guide] for _, pins in board.laser_changes)
    assert not any(pins[i] for _, pins in board.laser_changes for i in emission)
    assert board.laser_changes[-1][1][guide] == 0          # off again at the end
    units = 65536 / 110
    corners = {(32768 + round(x * units), 32768 + round(y * units))
               for x in (box[0], box[2]) for y in (box[1], box[3])}
    visited = {(x, y) for _, x, y in board.frames}
    assert corners <= visited
    assert not board.pulses


def test_the_frame_is_the_jobs_convex_hull():
    """`mark --frame` walks the convex hull of everything the job marks: an L's outer corners
    and the diagonal across its notch, not the bounding box's corner in the notch; a line is
    walked there and back."""
    import numpy as np
    from galvoscan.plan.vector_job import hull_outline
    ell = [np.array([(0, 0), (4, 0), (4, 1), (1, 1), (1, 3), (0, 3), (0, 0)], dtype=float)]
    hull = hull_outline(ell)
    assert np.array_equal(hull[0], hull[-1])                 # closed
    corners = {tuple(p) for p in hull}
    assert corners == {(0, 0), (4, 0), (4, 1), (1, 3), (0, 3)}
    assert (4, 3) not in corners
    line = hull_outline([np.array([(0, 0), (2, 0)]), np.array([(1, 0), (3, 0)])])
    assert {tuple(p) for p in line} == {(0, 0), (3, 0)} and len(line) == 3
