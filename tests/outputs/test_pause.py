"""A vector job held on the board and let go on (galvoscan.outputs.stream.Pause): on the
simulated board, the marks read off the XY2-100 wires and the laser pins by the tests' own
readers, every point of the job marked once and only once though the job was held mid-line,
nothing fired while held, and the one underrun of the queue run dry at the hold not counted
as a fault; and the streamer's protocol on the fake board (where the feed stops, a stop while
held)."""

from collections import Counter

import pytest

from galvoscan.link.client import HostClient
from galvoscan.gateware.host.regmap import Status
from galvoscan.outputs.stream import JobInterrupted, JobStreamer, Pause, _hold_point
from galvoscan.sim.board import LASER_PINS, SimTransport

from fake_board import FakeBoard, job
from sim_board import quick_board
from vector_board import pulses_per_frame


#: The job: LINES short polylines one above the other, each a jump to its left end and MARKS
#: marks of POINTS pitches each to the right, at PULSES pulses a point: more segments than the
#: board's queue holds (512), so that the pause comes with a quarter of the job still to send.
LINES, MARKS, POINTS, PITCH, PULSES = 150, 3, 4, 16, 2
X0, Y0, ROW = 30000, 28000, 20
REGISTERS = {"pitch": PITCH, "pulses_per_point": PULSES, "laser_prr": 500,
             "laser_power": 40, "jump_delay": 10}
#: Segments sent, at least, when the pause is asked for (between two marks of a line).
PAUSE_AFTER = 450
#: Board seconds the test looks at the held board before letting it go on.
HELD_S = 3e-3
EMITTING = [LASER_PINS.index(name) for name in ("laser_enable", "laser_mo", "laser_am",
                                                  "laser_latch")]


def _lines():
    segments = []
    for row in range(LINES):
        y = Y0 + ROW * row
        segments += [("jump", X0, y)] + [("mark", X0 + (k + 1) * POINTS * PITCH, y)
                                         for k in range(MARKS)]
    return segments


def _expected_marks():
    """Each point of each line (from its left end, a pitch apart, to its right end) with its
    pulses: what the job asks for, from its own numbers."""
    return Counter({(X0 + k * PITCH, Y0 + ROW * row): PULSES
                    for row in range(LINES) for k in range(MARKS * POINTS + 1)})


class _Watched(HostClient):
    """The real client, every write logged; while the job is held, it looks at the board on
    each of the streamer's waits (its status, the pulses and the laser pins) and, HELD_S of
    board time on, lets the job go on."""

    def __init__(self, transport, board, pause):
        super().__init__(transport)
        self.sim, self.pause = board, pause
        self.writes = []
        self.held = None            # (board time, pulses, laser changes) when held
        self.seen = None            # what was seen at the end of the hold

    def write(self, name, value):
        self.writes.append((name, value))
        return super().write(name, value)

    def queue_segments(self, segments):
        self.writes += [("vec_op", op_word) for op_word, _, _ in segments]
        return super().queue_segments(segments)

    def sleep(self, seconds):
        super().sleep(seconds)
        if not self.pause.holding.is_set():
            return
        board = self.sim.board
        if self.held is None:
            self.held = (board.now, len(board.pulses), len(board.laser_changes))
        elif board.now - self.held[0] >= HELD_S:
            flags = Status.from_bits(self.read("status"))
            self.seen = {"armed": bool(flags.armed), "busy": bool(flags.vector_busy),
                         "pulses": len(board.pulses) - self.held[1],
                         "changes": board.laser_changes[self.held[2]:],
                         "pins": board.laser_changes[-1][1]}
            self.pause.resume()


@pytest.fixture(scope="module")
def held_job():
    """The job run once with a pause after PAUSE_AFTER segments, let go on after HELD_S:
    ``(sim board, client, report, frames before the job)``."""
    board = quick_board(record_laser=True)
    pause = Pause()
    client = _Watched(SimTransport(board.board), board, pause)
    segments = _lines()
    sent = []

    def progress(count):
        sent.append(count)
        done = sum(sent)
        if done >= PAUSE_AFTER and not pause.holds and segments[done - 1][0] == "mark" and \
                segments[done][0] == "mark":
            pause.pause()
    board.run_for(0)
    before = len(board.xy2_frames())
    underruns = client.read("vec_underruns")
    streamer = JobStreamer(client, poll_s=2e-4, progress=progress, pause=pause)
    report = streamer.run_vector(segments, REGISTERS, timeout_s=60, ready_timeout_s=60)
    underruns = client.read("vec_underruns") - underruns
    board.run_for(100e-6)                   # (the last frames' ends, on the wires)
    return board, client, pause, report, before, underruns


def test_a_job_held_mid_way_marks_every_point_once(held_job):
    """Held between two marks of a line after some 450 of its 600 segments, and let go on:
    every point of every line off the wires, each with its pulses and no more (nothing lost,
    nothing marked twice), no point anywhere else; every segment taken; the board counted one
    underrun, the hold's, and the report none."""
    board, client, pause, report, before, underruns = held_job
    assert pause.holds == 1 and client.seen is not None
    marked = Counter()
    for xy, pulses in pulses_per_frame(board, before):
        if pulses:
            marked[tuple(xy)] += pulses
    assert marked == _expected_marks()
    assert report.segments == (1 + MARKS) * LINES + 1       # (and the jump a job ends on)
    assert underruns == 1
    assert report.holds == 1
    assert report.counters == {"vec_underruns": 0, "vec_stalls": 0, "vec_rejected": 0,
                               "errors": 0}
    assert report.clean


def test_a_held_job_is_disarmed_and_fires_nothing(held_job):
    """While held: the board says it is disarmed with nothing queued, no pulse fires and every
    laser output that emits is low; arm = 0 was written at the hold and arm = 1 after it (the
    MO lead waited out again), the feed having stopped between two marks."""
    board, client, pause, report, before, underruns = held_job
    seen = client.seen
    assert seen["armed"] is False and seen["busy"] is False
    assert seen["pulses"] == 0
    assert not any(seen["pins"][i] for i in EMITTING)
    assert not any(pins[i] for _, pins in seen["changes"] for i in EMITTING)
    arms = [(index, value) for index, (name, value) in enumerate(client.writes)
            if name == "arm"]
    # Armed at the start, disarmed at the hold, armed again, disarmed at the end.
    assert [value for _, value in arms] == [1, 0, 1, 0]
    ops = [value for name, value in client.writes if name == "vec_op"]
    held_after = sum(1 for name, _ in client.writes[:arms[1][0]] if name == "vec_op")
    # (vec_op 1 is a mark: the hold came between two.)
    assert ops[held_after - 1] == ops[held_after] == 1
    assert PAUSE_AFTER <= held_after < len(ops)


def test_the_feed_stops_at_once_and_goes_on_from_there():
    """The fake board: a pause stops the feed at the next batch, mid-line; the queue is let run
    empty before arm = 0; every segment goes once, in order."""
    board = FakeBoard(drain=8, depth=32)
    pause = Pause()
    segments = job(300)                 # a jump every 10 segments
    sent = []

    def progress(count):
        sent.append(count)
        if sum(sent) >= 205 and not pause.paused and not pause.holds:
            paused_at.append(sum(sent))
            pause.pause()
    paused_at = []
    original = board.read

    def read(name):
        if pause.holding.is_set():
            held_at.append((sum(1 for n, _ in board.log if n == "vec_op"), board.queue))
            pause.resume()
        return original(name)
    held_at = []
    board.read = read
    report = JobStreamer(board, batch=7, poll_s=0, progress=progress,
                         pause=pause).run_vector(segments, {}, timeout_s=5)
    assert pause.holds == report.holds == 1
    # Right after the batch that passed 205, mid-line, the queue empty.
    assert 205 <= paused_at[0] < 205 + 7 and segments[paused_at[0] - 1][0] == "mark"
    assert held_at[0] == (paused_at[0], 0)
    ops = [(board.log[i][1], board.log[i + 1][1]) for i, (name, _) in enumerate(board.log)
           if name == "vec_x"]
    assert ops[:300] == [(x, y) for _, x, y in segments]
    assert report.segments == 301
    # Armed, disarmed at the hold once the queue was empty, armed again, disarmed at the end.
    arms = [index for index, (name, _) in enumerate(board.log) if name == "arm"]
    assert [board.log[i][1] for i in arms] == [1, 0, 1, 0]
    assert sum(1 for name, _ in board.log[:arms[1]] if name == "vec_op") == paused_at[0]


def test_a_pixel_line_is_not_parted_from_its_words():
    """The feed stops where it is, but not between a pixel line and its pixel words (the line
    sweeps at one speed: it must not wait for them): after them."""
    segments = [("jump", 0, 0), ("mark", 5, 0), ("line", 9, 0), ("pixels", 1, 2),
                ("pixels", 3, 4), ("jump", 0, 1), ("line", 9, 1), ("jump", 0, 2)]
    assert [_hold_point(segments, sent) for sent in range(len(segments) + 1)] == \
        [0, 1, 2, 5, 5, 5, 6, 8, 8]


def test_a_stop_while_held_disarms_and_says_how_far():
    """Ctrl-C (meerk40t's stop) while the job is held: arm = 0 first, and the job ends."""
    board = FakeBoard(drain=8)
    pause = Pause()
    pause.pause()
    original = board.read

    def read(name):
        if pause.holding.is_set():
            raise KeyboardInterrupt
        return original(name)
    board.read = read
    with pytest.raises(JobInterrupted):
        JobStreamer(board, poll_s=0, pause=pause).run_vector(job(300), {}, timeout_s=5)
    assert not pause.holding.is_set()
    assert board.log[-3:] == [("arm", 0), ("run", 0), ("guide", 0)]
    assert not any(name == "vec_op" for name, _ in board.log)
