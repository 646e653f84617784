"""Marking on the fly through the pins of the system top (#38): a belt under the simulated
board (galvoscan/sim/belt.py) turns its speed into encoder edges on ``encoder_x_a``/``_b``, the
real job streamer marks a line through the real link, and the marks decoded off the XY2-100
wires, moved back by the belt's travel at each frame, lie on the drawing."""

import pytest

from galvoscan.link.client import HostClient
from galvoscan.outputs.stream import JobStreamer
from galvoscan.sim.board import SimTransport, SimulatedBoard
from galvoscan.sim.xy2_receiver import frame_of_each_pulse

from sim_board import QUICK_SIM_BOARD, VECTOR_BOARD


FLY_BOARD = dict(VECTOR_BOARD, **QUICK_SIM_BOARD, fly=True)
UNITS_PER_MM = 65536 / 110
COUNTS_PER_MM = 100
#: The fly scale: galvo units a count, 16 fraction bits.
SCALE = round(UNITS_PER_MM / COUNTS_PER_MM * 65536)
PITCH = 80
LINE = [("jump", 26000, 32768), ("mark", 38000, 32768)]
REGISTERS = {"pitch": PITCH, "pulses_per_point": 1, "laser_prr": 500, "laser_power": 100,
             "jump_delay": 20}


#: The line in 24 pieces, so that the streamer (and the test) hears of progress as it marks.
PIECES = [LINE[0]] + [("mark", 26000 + 500 * k, 32768) for k in range(1, 25)]


def fly_board(backend="compiled", **kwargs):
    board = SimulatedBoard(backend=backend, **dict(FLY_BOARD, **kwargs))
    client = HostClient(SimTransport(board))
    client.write("fly_scale_x", SCALE & 0xFFFF)
    client.write("fly_scale_x_hi", SCALE >> 16)
    client.write("fly_clear", 1)
    client.write("fly_ctrl", 1)
    return board, client


def marks(board):
    """``(clock, x, y)`` of each frame a pulse fell on."""
    frames = board.frames
    placed = frame_of_each_pulse(board.sync_rises, board.pulses, len(frames))
    return sorted({k: frames[k] for k, _ in placed}.values())


def on_the_line(board, speeds):
    """Each mark moved back by the belt's travel (``speeds``: ``[(from_s, mm_s)]``) at its
    frame: its distance off the drawn line, and the largest travel, in galvo units."""
    def travel(t):
        mm = 0.0
        for (start, mm_s), (end, _) in zip(speeds, speeds[1:] + [(float("inf"), 0)]):
            if t > start:
                mm += mm_s * (min(t, end) - start)
        return mm * UNITS_PER_MM
    worst, furthest = 0.0, 0.0
    for clock, x, y in marks(board):
        moved = travel(clock / board.clk_freq)
        furthest = max(furthest, moved)
        back = x - moved
        along = max(LINE[0][1] - back, back - LINE[1][1], 0)
        worst = max(worst, abs(y - 32768), along)
    return worst, furthest


@pytest.mark.parametrize("mm_s", [100, 500])
def test_marks_on_a_moving_belt_lie_on_the_drawing(mm_s):
    board, client = fly_board()
    start = board.now
    board.belt_moves(mm_s, COUNTS_PER_MM)
    report = JobStreamer(client, poll_s=50e-6).run_vector(LINE, REGISTERS)
    assert report.pulses > 100
    worst, furthest = on_the_line(board, [(start, mm_s)])
    assert furthest > 4 * PITCH, "the belt moved too little to tell"
    assert worst <= PITCH / 2, worst
    assert client.read("enc_x_bad") == 0 and client.read("fly_clipped") == 0


def test_an_encoder_that_stops_mid_part_keeps_the_marks_on_the_drawing():
    board, client = fly_board(vector_queue_depth=4)
    start = board.now
    board.belt_moves(300, COUNTS_PER_MM)
    stopped = []

    def stop(taken):
        if len(board.pulses) > 60 and not stopped:
            board.belt_moves(0, COUNTS_PER_MM)
            stopped.append(board.now)
    streamer = JobStreamer(client, poll_s=50e-6)
    streamer.progress = stop
    streamer.run_vector(PIECES, REGISTERS)
    assert stopped
    worst, furthest = on_the_line(board, [(start, 300), (stopped[0], 0)])
    assert worst <= PITCH / 2, worst


def test_noise_on_the_lines_is_counted_never_a_jump():
    board, client = fly_board()
    board.belt_moves(200, COUNTS_PER_MM)
    board.run_for(1e-3)
    for _ in range(5):
        board.belt.glitch_periods = 1
        board.run_for(0.2e-3)
    board.belt_moves(0, COUNTS_PER_MM)      # (still while the registers are read)
    board.run_for(0.1e-3)
    count = client.read("enc_x") | client.read("enc_x_hi") << 16
    # Both lines turned over and back: two illegal steps a glitch, and no count.
    assert client.read("enc_x_bad") == 10
    assert abs(count - board.belt.count) <= 1, (count, board.belt.count)


def test_a_point_pushed_off_the_field_is_held_at_its_edge_and_never_fired():
    board, client = fly_board()
    client.write("fly_ctrl", 0)
    # 64 units a count: 100 counts carry the line's end past the field's edge.
    client.write("fly_scale_x", 0)
    client.write("fly_scale_x_hi", 64)
    client.write("fly_ctrl", 1)
    board.belt_moves(800, COUNTS_PER_MM)
    JobStreamer(client, poll_s=50e-6).run_vector([("jump", 30000, 32768),
                                                  ("mark", 60000, 32768)], REGISTERS)
    clipped = client.read("fly_clipped")
    assert clipped > 0
    edge_frames = {k for k, (_, x, _) in enumerate(board.frames) if x == 65535}
    assert edge_frames, "no frame held at the field's edge"
    fired = {k for k, _ in frame_of_each_pulse(board.sync_rises, board.pulses,
                                               len(board.frames))}
    assert not edge_frames & fired
    assert not any(x > 65535 or x < 0 for _, x, _ in board.frames)


def test_both_backends_keep_the_same_records():
    records = []
    for backend in ("compiled", "python"):
        board, client = fly_board(backend)
        board.belt_moves(500, COUNTS_PER_MM)
        JobStreamer(client, poll_s=50e-6).run_vector([("jump", 30000, 32768),
                                                      ("mark", 31000, 32768)], REGISTERS)
        records.append((board.frames, board.pulses, board.belt.count,
                        client.read("enc_x")))
    assert records[0] == records[1]
