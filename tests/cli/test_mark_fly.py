"""`galvoscan mark --fly`: marking on the fly from the command line and the API, end to end.

A 2 mm square is marked by `mark --sim --board ulx3s` (the ULX3S's bitstream, which has the
fly, at tests/support/ulx3s_board.py's 8 MHz) while a belt carries the part: the board's
simulated encoder (`--fly-speed`), or a real encoder on its ENCODER input under the simulated
board's belt (`--encoder` with `--belt-speed`). The marks are read off the XY2-100 wires, and
each is moved back by the belt's travel from the instant the host's `fly_clear` reached the
board (read off the link's bytes by the tests' own codec) to its frame: they lie on the
square, written out here, within half a pitch. The refusals come before any byte: a bad
axis, a negative encoder, no speed, a part that would leave the field (its figures worked out
here from the field and the square), a bitstream without the fly."""

import json
import math

import numpy as np
import pytest

from galvoscan import api
from galvoscan.cli import main
from galvoscan.link.client import HostClient
from galvoscan.outputs.stream import JobAborted, JobStreamer
from galvoscan.sim.board import SimTransport, SimulatedBoard
from galvoscan.sim.xy2_receiver import frame_of_each_pulse

from fly_marks import pulsed_frames, writes
from sim_board import QUICK_SIM_BOARD, VECTOR_BOARD, part_arrivals, quick_sim_board
from ulx3s_board import ulx3s_board, ulx3s_sim as shared_ulx3s_sim


FIELD_MM = 110.0
UNITS_PER_MM = 65536 / FIELD_MM
# A 0.1 mm spot: the planner's pitch is at most half of it.
PROFILE = "[laser]\nspot_mm = 0.1\n[galvo]\njump_delay_us = 100\n"
HALF_PITCH_MM = 0.025
# The square: 2 mm, its centre placed at OFFSET in the field.
SIDE_MM = 2.0
OFFSET = (-5.0, 3.0)
SVG = (f'<svg xmlns="http://www.w3.org/2000/svg" width="4mm" height="4mm" viewBox="0 0 4 4">'
       f'<rect x="1" y="1" width="{SIDE_MM:g}" height="{SIDE_MM:g}" fill="none" '
       f'stroke="black"/></svg>')
#: fly_ctrl's bits, as the register map says them: on; the X count from the simulated encoder.
FLY_ON, X_SIMULATED = 0b01, 0b10
#: The simulated encoder's counts a mm, as the docs (docs/user/fly.md) say galvoscan runs it.
SIM_COUNTS_PER_MM = 1000
NOPORT = ["--port", "/nonexistent/ttyUSB9"]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("fly")
    (folder / "square.svg").write_text(SVG)
    (folder / "machine.toml").write_text(PROFILE)
    return folder


def mark_args(files, *more):
    return ["mark", str(files / "square.svg"), f"--offset={OFFSET[0]:g},{OFFSET[1]:g}",
            "--speed", "1000", "--machine", str(files / "machine.toml"), *more]


def last_json(capsys):
    return json.loads(capsys.readouterr().out.strip().splitlines()[-1])


def ulx3s_sim():
    """:func:`ulx3s_board.ulx3s_sim` with the tests' quick MO lead."""
    return shared_ulx3s_sim(QUICK_SIM_BOARD["mo_lead"])


SIM_ULX3S = ["--sim", "--board", "ulx3s", "--baud", "1e6", "--timeout", "600", "--json"]


def square_distance(point, centres=(OFFSET,)):
    """Field mm from ``point`` to the nearest outline of the squares centred at ``centres``."""
    half = SIDE_MM / 2
    nearest = math.inf
    for centre in centres:
        dx, dy = abs(point[0] - centre[0]), abs(point[1] - centre[1])
        nearest = min(nearest, min(half - dx, half - dy) if dx <= half and dy <= half else
                      math.hypot(max(dx - half, 0), max(dy - half, 0)))
    return nearest


def on_the_square(board, mm_s, axis, sign, centres=(OFFSET,)):
    """Each mark off the wires, in field mm, moved back by the belt's travel (``mm_s`` along
    ``axis``, towards ``sign``) since the count was zeroed: the worst distance off the squares
    (centred at ``centres``) so, the worst without the move, the furthest travel (mm), and
    the marks moved back."""
    cleared = writes(board.bytes_in, "fly_clear")
    assert len(cleared) == 1, cleared
    start = cleared[0][0]
    worst = worst_still = furthest = 0.0
    back = []
    for clock, x, y in pulsed_frames(board):
        assert clock > start
        point = np.array([(x - 32768) / UNITS_PER_MM, (y - 32768) / UNITS_PER_MM])
        travel = mm_s * (clock - start) / board.clk_freq
        furthest = max(furthest, travel)
        moved = point.copy()
        moved["XY".index(axis)] -= sign * travel
        worst = max(worst, square_distance(moved, centres))
        worst_still = max(worst_still, square_distance(point, centres))
        back.append(moved)
    return worst, worst_still, furthest, np.array(back)


def assert_whole_square(back, centre=OFFSET):
    """A mark near each corner and along each side: the square was marked whole."""
    half = SIDE_MM / 2
    for cx in (-half, 0, half):
        for cy in (-half, 0, half):
            if cx == cy == 0:
                continue
            target = np.array(centre) + (cx, cy)
            assert np.hypot(*(back - target).T).min() < 2 * HALF_PITCH_MM, target


# --- end to end on the simulated ULX3S ------------------------------------------------------

def test_the_simulated_encoder_carries_the_marks_and_they_lie_on_the_drawing(files, capsys):
    """`--fly X --fly-speed 100`: the simulated encoder at 1000 counts/mm (80 clocks a count at
    8 MHz), the fly set up off, turned on as the job starts with the count zeroed, and off
    (fly_return: the on bit; the count still the simulated encoder's) after the last pulse;
    the marks, moved back, lie on the square."""
    with ulx3s_sim() as Board:
        assert main(mark_args(files, "--fly", "X", "--fly-speed", "100", *SIM_ULX3S)) == 0
    result = last_json(capsys)
    board, = Board.built
    assert [v for _, v in writes(board.bytes_in, "fly_sim_period")] == \
        [round(8e6 / (100 * SIM_COUNTS_PER_MM))]
    control = writes(board.bytes_in, "fly_ctrl")
    assert [v for _, v in control] == [X_SIMULATED, X_SIMULATED | FLY_ON, X_SIMULATED]
    assert control[1][0] < board.pulses[0] and control[2][0] > board.pulses[-1]
    scale = round(UNITS_PER_MM / SIM_COUNTS_PER_MM * 65536)
    assert [v for _, v in writes(board.bytes_in, "fly_scale_x")] == [scale & 0xFFFF]
    worst, still, furthest, back = on_the_square(board, 100, "X", +1)
    assert furthest > 0.5, "the belt moved too little to tell"
    assert still > 10 * HALF_PITCH_MM, "the marks did not move with the belt"
    assert worst <= HALF_PITCH_MM, worst
    assert_whole_square(back)
    fly = result["fly"]
    assert fly["clipped"] == 0 and fly["speed_mm_s"] == 100
    # The square's edge ahead at -4 mm, the field's at +55 mm: 59 mm at 100 mm/s.
    assert fly["in_field_s"] == pytest.approx((FIELD_MM / 2 - (OFFSET[0] + 1)) / 100)
    print(f"simulated encoder, 100 mm/s: worst {worst * 1000:.1f} µm "
          f"({worst * UNITS_PER_MM:.2f} units) off the square after {furthest:.3f} mm of belt")


@pytest.mark.parametrize("distance_mm", [0, 1.5])
def test_parts_on_the_belt_each_start_the_fly_at_the_sensor(files, capsys, distance_mm):
    """`--fly X --fly-speed 100 --wait-input part --repeat 2`: each part's count zeroed and the
    fly turned on by the board's queue as the part comes to the sensor (no fly_clear or fly
    on from the host); each part's marks, moved back by the belt's travel since its part came
    to the sensor, lie on the square, whole. With `--sensor-distance 1.5`, the sensor 1.5 mm
    before the drawing's place: the queue waits for the encoder to count 1.5 mm (15 ms at
    100 mm/s) and zeroes the count then: the marks moved back by the travel since."""
    with ulx3s_sim() as Board:
        assert main(mark_args(files, "--fly", "X", "--fly-speed", "100", "--wait-input",
                              "part", "--repeat", "2", "--sensor-distance", f"{distance_mm:g}",
                              *SIM_ULX3S)) == 0
    result = last_json(capsys)
    assert result["parts"] == 2 and result["fly"]["clipped"] == 0
    board, = Board.built
    assert writes(board.bytes_in, "fly_clear") == []
    assert {v for _, v in writes(board.bytes_in, "fly_ctrl")} == {X_SIMULATED}
    came = part_arrivals(board)
    parts = {}
    for clock, x, y in pulsed_frames(board):
        start = max(at for at in came if at < clock)
        point = np.array([(x - 32768) / UNITS_PER_MM, (y - 32768) / UNITS_PER_MM])
        point[0] -= 100 * (clock - start) / board.clk_freq - distance_mm
        parts.setdefault(start, []).append(point)
    assert len(parts) == 2
    for back in parts.values():
        back = np.array(back)
        assert max(square_distance(p) for p in back) <= HALF_PITCH_MM
        assert_whole_square(back)


def test_a_real_encoder_under_the_boards_belt_carries_the_marks(files, capsys):
    """`--fly Y --fly-direction - --encoder 200 --belt-speed 250`: with --sim the board's belt
    runs at 250 mm/s under ENCODER Y (50,000 counts/s); the scale is negative (the part moves
    towards -Y), the simulated encoder is not used, and the marks, moved back, lie on the
    square."""
    with ulx3s_sim() as Board:
        assert main(mark_args(files, "--fly", "Y", "--fly-direction", "-", "--encoder", "200",
                              "--belt-speed", "250", *SIM_ULX3S)) == 0
    result = last_json(capsys)
    board, = Board.built
    assert (board.belt.axis, board.belt.counts_per_s) == ("y", 250 * 200)
    assert [v for _, v in writes(board.bytes_in, "fly_ctrl")] == [0, FLY_ON, 0]
    scale = -round(UNITS_PER_MM / 200 * 65536)
    assert [v for _, v in writes(board.bytes_in, "fly_scale_y")] == [scale & 0xFFFF]
    assert [v for _, v in writes(board.bytes_in, "fly_scale_y_hi")] == [(scale >> 16) & 0xFFFF]
    worst, still, furthest, back = on_the_square(board, 250, "Y", -1)
    assert furthest > 1.0 and still > 10 * HALF_PITCH_MM
    assert worst <= HALF_PITCH_MM, worst
    assert_whole_square(back)
    assert result["fly"]["encoder"] == "ENCODER Y" and result["fly"]["clipped"] == 0
    print(f"real encoder, 250 mm/s: worst {worst * 1000:.1f} µm "
          f"({worst * UNITS_PER_MM:.2f} units) off the square after {furthest:.3f} mm of belt")


# --- through the API, on one simulated ULX3S ---------------------------------------------------

@pytest.fixture(scope="module")
def api_board():
    """A SimulatedBoard of the ULX3S's bitstream (8 MHz), reset for each test."""
    return SimulatedBoard(backend="compiled", **ulx3s_board(mo_lead=QUICK_SIM_BOARD["mo_lead"]))


@pytest.fixture
def board(api_board):
    api_board.reset()
    return api_board


#: Two squares side by side, red and black: each a layer of its own.
TWO_SQUARES = ('<svg xmlns="http://www.w3.org/2000/svg" width="8mm" height="4mm" '
               'viewBox="0 0 8 4"><rect x="1" y="1" width="2" height="2" fill="none" '
               'stroke="#ff0000"/><rect x="5" y="1" width="2" height="2" fill="none" '
               'stroke="black"/></svg>')


def test_layers_are_one_part_on_the_belt(files, board, tmp_path):
    """A job of two layers on the fly (api.run): each layer set up and run on its own, the
    count zeroed once, as the first starts, and counting on between the layers (the fly off
    keeps the simulated encoder's count: 5 ms of belt were lost when it did not), so the
    second layer's marks follow the part on from where the first left it: both squares'
    marks, moved back by the belt's travel since that one zeroing, lie on the drawing."""
    drawing = tmp_path / "two.svg"
    drawing.write_text(TWO_SQUARES)
    profile = api.load_profile(files / "machine.toml")
    plan = api.plan(api.Job(drawings=[api.Drawing(str(drawing), offset_mm=OFFSET)],
                            layers=[api.Layer("#ff0000", speed_mm_s=500)], speed_mm_s=1000,
                            fly=api.Fly("X", speed_mm_s=100)), profile)
    assert len(plan.vector_job.layers) == 2
    report = api.run(plan, board)
    assert report.clean and report.clipped == 0
    assert [v for _, v in writes(board.bytes_in, "fly_ctrl")] == \
        [X_SIMULATED, X_SIMULATED | FLY_ON, X_SIMULATED] * 2
    centres = [(OFFSET[0] - 2, OFFSET[1]), (OFFSET[0] + 2, OFFSET[1])]
    worst, still, furthest, back = on_the_square(board, 100, "X", +1, centres)
    assert furthest > 1.0 and still > 10 * HALF_PITCH_MM
    assert worst <= HALF_PITCH_MM, worst
    for centre in centres:
        assert_whole_square(back, centre)
    print(f"two layers, 100 mm/s: worst {worst * 1000:.1f} µm off the squares after "
          f"{furthest:.3f} mm of belt")


def test_a_belt_faster_than_planned_holds_points_at_the_edge_unmarked(files, board):
    """Planned for a 50 mm/s belt (2 mm of room: 40 ms), the board's belt runs at 900: the
    points it carries past the field's edge are held there, none fired, and the report counts
    them; the job is not clean."""
    profile = api.load_profile(files / "machine.toml")
    plan = api.plan(api.Job(drawings=[api.Drawing(str(files / "square.svg"),
                                                  offset_mm=(52.0, 0.0))],
                            fly=api.Fly("X", counts_per_mm=100, belt_speed_mm_s=50)), profile)
    assert plan.fly.in_field_s == pytest.approx((55 - 53) / 50)
    board.belt_moves(900, 100)
    report = api.run(plan, board)
    edge = {k for k, (_, x, _) in enumerate(board.frames) if x == 65535}
    assert report.clipped > 0 and edge and not report.clean
    fired = {k for k, _ in frame_of_each_pulse(board.sync_rises, board.pulses,
                                               len(board.frames))}
    assert fired and not edge & fired


def test_a_fault_mid_job_turns_the_fly_off(files, board):
    """The interlock opens while the part is marked; the job stops, and the fly is turned off
    (fly_return) after the laser is disarmed, as at a job's end."""
    profile = api.load_profile(files / "machine.toml")
    plan = api.plan(api.Job(drawings=[api.Drawing(str(files / "square.svg"))],
                            fly=api.Fly("X", speed_mm_s=100)), profile)
    client = HostClient(SimTransport(board))
    streamer = JobStreamer(client, poll_s=50e-6)
    keepalive = streamer.keepalive

    def open_the_interlock_once_marking():
        if len(board.pulses) > 20:
            board.interlock_closed = False
        keepalive()
    streamer.keepalive = open_the_interlock_once_marking
    with pytest.raises(JobAborted, match="interlock"):
        api.stream_layers(streamer, plan.vector_job, board, 10.0,
                          fly=plan.fly.at_clock(board.clk_freq).registers())
    assert len(board.pulses) > 20
    control = writes(board.bytes_in, "fly_ctrl")
    assert [v for _, v in control] == [X_SIMULATED, X_SIMULATED | FLY_ON, X_SIMULATED]
    disarmed = writes(board.bytes_in, "arm")[-1]
    assert disarmed[1] == 0 and control[1][0] < disarmed[0] < control[2][0]
    assert writes(board.bytes_in)[-1][1] == "fly_ctrl"
    assert client.read("fly_ctrl") == X_SIMULATED


# --- refused before any byte -----------------------------------------------------------------

@pytest.mark.parametrize("options, said", [
    (["--fly", "Z", "--fly-speed", "100"], "argument --fly: invalid choice: 'Z'"),
    (["--fly", "X", "--encoder", "-100", "--belt-speed", "100"],
     "encoder must be from 1 to 10000, not -100"),
    (["--fly", "X"], "--fly X needs an encoder: --encoder COUNTS_PER_MM"),
    (["--fly", "X", "--encoder", "100"], "needs the belt's top speed, --belt-speed MM_S"),
    (["--encoder", "100", "--belt-speed", "100"],
     "--encoder is for marking on the fly: give --fly X or --fly Y too"),
    (["--fly", "X", "--encoder", "100", "--fly-speed", "100"], "give one of them"),
    (["--fly", "X", "--fly-speed", "100", "--belt-speed", "100"], "a real belt's"),
    (["--fly", "X", "--encoder", "2", "--belt-speed", "100"],
     "the board's fly scale holds less than 128 (an encoder of at least 4.66 counts/mm)"),
    (["--fly", "X", "--fly-speed", "0.5"], "fly speed must be from 1 to 4000"),
    (["--fly", "X", "--fly-direction", "up", "--fly-speed", "100"], "invalid choice: 'up'"),
])
def test_bad_fly_options_are_one_line_before_anything(files, capsys, options, said):
    with pytest.raises(SystemExit) as stop:
        main(mark_args(files, *options, *NOPORT))
    assert stop.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert said in err[-1] and "ttyUSB9" not in err[-1], err


def test_a_part_that_would_leave_the_field_is_refused_with_its_figures(files, capsys):
    """At 4000 mm/s with the square's edge ahead at +51 mm of the field's +55: 4 mm, 1 ms; the
    job (the planner's estimate) takes longer. One line with both, no board built; the other
    way along the belt, the same job has 104 mm and is marked."""
    assert main(mark_args(files, "--offset", "50,0", "--estimate", "--json")) == 0
    job_s = last_json(capsys)["estimate_s"]
    assert job_s > 0.001
    with ulx3s_sim() as Board, pytest.raises(SystemExit) as stop:
        main(mark_args(files, "--offset", "50,0", "--fly", "X", "--fly-speed", "4000",
                       *SIM_ULX3S))
    assert stop.value.code == 2 and Board.built == []
    line = capsys.readouterr().err.strip().splitlines()[-1]
    assert f"the part leaves the field after {(55 - 51) / 4000:.3f} s at 4000 mm/s" in line
    assert f"the job takes {job_s:.3f} s" in line, line
    assert main(mark_args(files, "--offset", "50,0", "--fly", "X", "--fly-direction", "-",
                          "--fly-speed", "4000", "--estimate", "--json")) == 0
    fly = last_json(capsys)["fly"]
    assert fly["in_field_s"] == pytest.approx((51 - 2 + 55) / 4000)
    assert fly["job_s"] == pytest.approx(job_s)


def test_a_bitstream_without_the_fly_refuses_it_before_any_write(files, capsys):
    """The iCEBreaker's vector build has no fly (caps): one line, and the board received no
    write at all (only the reads that asked what it holds and whether it is idle)."""
    with quick_sim_board(**VECTOR_BOARD) as Board, pytest.raises(SystemExit) as stop:
        main(mark_args(files, "--fly", "X", "--fly-speed", "100", "--sim", "--timeout", "600"))
    assert stop.value.code == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert "the board's bitstream has no marking on the fly" in err[-1], err
    board, = Board.built
    assert writes(board.bytes_in) == [] and board.pulses == []


# --- the plan's figures, job files and the profile -------------------------------------------

def test_estimate_json_gives_the_time_in_the_field(files, capsys):
    """`--estimate --json`: the time the part stays in the field, the job's, and what the
    board is given: the simulated encoder's period at the profile's 24 MHz and the scale."""
    assert main(mark_args(files, "--fly", "X", "--fly-speed", "500", "--estimate",
                          "--json")) == 0
    record = last_json(capsys)
    fly = record["fly"]
    assert fly["in_field_s"] == pytest.approx((55 - (OFFSET[0] + 1)) / 500)
    assert fly["job_s"] == pytest.approx(record["estimate_s"])
    assert fly["sim_period_clocks"] == 24e6 / (500 * SIM_COUNTS_PER_MM)
    assert fly["scale_q16"] == round(UNITS_PER_MM / SIM_COUNTS_PER_MM * 65536)
    assert (fly["axis"], fly["direction"], fly["encoder"]) == ("X", "+", "simulated")
    assert main(mark_args(files, "--estimate", "--json")) == 0
    assert last_json(capsys)["fly"] is None


def test_the_profile_and_a_job_file_hold_the_fly(files, tmp_path, capsys):
    """The profile's [fly] is the encoder, direction and belt speed when the command line
    gives none; a job saved with --fly marks on the fly again."""
    machine = tmp_path / "machine.toml"
    machine.write_text(PROFILE + '[fly]\ncounts_per_mm = 50\ndirection = "-"\n'
                                 'belt_speed_mm_s = 200\n')
    argv = ["mark", str(files / "square.svg"), "--machine", str(machine), "--estimate",
            "--json"]
    assert main([*argv, "--fly", "Y"]) == 0
    fly = last_json(capsys)["fly"]
    assert (fly["counts_per_mm"], fly["direction"], fly["speed_mm_s"]) == (50, "-", 200)
    assert fly["in_field_s"] == pytest.approx((55 - 1) / 200)
    job = tmp_path / "job.toml"
    assert main([*argv, "--fly", "X", "--fly-speed", "300", "--save", str(job)]) == 0
    saved = last_json(capsys)["fly"]
    assert 'fly = "X"' in job.read_text() and "fly_speed = 300" in job.read_text()
    assert main(["mark", str(job), "--machine", str(machine), "--estimate", "--json"]) == 0
    assert last_json(capsys)["fly"] == saved


def test_store_refuses_the_fly(files, tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:
        main(["store", str(files / "square.svg"), "--fly", "X", "--fly-speed", "100", "-o",
              str(tmp_path / "job.img")])
    assert stop.value.code == 2
    assert "does not mark on the fly" in capsys.readouterr().err
    assert not (tmp_path / "job.img").exists()
