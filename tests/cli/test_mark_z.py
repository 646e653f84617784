"""`galvoscan mark --z`: a focus shift on XY2-100's Z channel from the command line, per job
and per layer, end to end on the simulated ULX3S (whose bitstream has the Z channel): the Z
frames decoded off the ``xy2_z`` wire, by the same receiver as X and Y, carry the plan's Z on
every frame a pulse falls on. The refusals come before any byte: no focus shifter in the
profile, a Z past its range, a bitstream without the Z channel."""


import pytest

from galvoscan.cli import main

from fly_marks import pulsed_frames, writes
from sim_board import QUICK_SIM_BOARD, VECTOR_BOARD, quick_sim_board
from ulx3s_board import ulx3s_board, ulx3s_sim as shared_ulx3s_sim


#: The profile's focus shifter: 1000 galvo units a mm of Z (a shift of ±32.8 mm at most).
Z_UNITS_PER_MM = 1000
PROFILE = (f"[field]\nz_units_per_mm = {Z_UNITS_PER_MM}\n[laser]\nspot_mm = 0.1\n"
           f"[galvo]\njump_delay_us = 100\n")
#: Two short lines, red at the left and blue at the right.
SVG = ('<svg xmlns="http://www.w3.org/2000/svg" width="6mm" height="2mm" viewBox="0 0 6 2">'
       '<path d="M0 1 H2" stroke="#ff0000" fill="none"/>'
       '<path d="M4 1 H6" stroke="#0000ff" fill="none"/></svg>')
SIM_ULX3S = ["--sim", "--board", "ulx3s", "--baud", "1e6", "--timeout", "600"]
NOPORT = ["--port", "/nonexistent/ttyUSB9"]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("z")
    (folder / "lines.svg").write_text(SVG)
    (folder / "machine.toml").write_text(PROFILE)
    (folder / "no_shifter.toml").write_text("[laser]\nspot_mm = 0.1\n")
    return folder


def mark_args(files, *more, machine="machine.toml"):
    return ["mark", str(files / "lines.svg"), "--speed", "1000",
            "--machine", str(files / machine), *more]


def ulx3s_sim():
    """:func:`ulx3s_board.ulx3s_sim` with the tests' quick MO lead."""
    return shared_ulx3s_sim(QUICK_SIM_BOARD["mo_lead"])


def z_of_pulses(board):
    """``(x, z)`` of each frame a pulse fell on: its X position and the Z frame sent with it."""
    z_at = dict(board.z_frames)
    assert len(z_at) == len(board.frames)
    return [(x, z_at[clock]) for clock, x, _ in pulsed_frames(board)]


def test_z_per_job_and_per_layer_on_the_wires(files, capsys):
    """`--z 1.5` for the job, the blue layer's own `z=-2`: every pulse of the red line falls on a
    frame with Z = 32768 + 1.5 mm × 1000, every pulse of the blue one on Z = 32768 − 2000;
    before the job, the shifter's middle."""
    with ulx3s_sim() as Board:
        assert main(mark_args(files, "--z", "1.5", "--layer", "#0000ff", "z=-2",
                              *SIM_ULX3S, "--json")) == 0
    captured = capsys.readouterr()
    assert "Z -2 mm" in captured.err
    # The record says each marked point's Z, off the Z line: the layers' two.
    import json
    record = json.loads(captured.out)
    assert set(record["marks_z_mm"]) == {1.5, -2.0}
    assert len(record["marks_z_mm"]) == len(record["marks"])
    board, = Board.built
    assert board.z_frames[0][1] == 32768
    marks = z_of_pulses(board)
    assert marks
    # The red line is left of the field's centre, the blue one right of it.
    red = {z for x, z in marks if x < 32768}
    blue = {z for x, z in marks if x > 32768}
    assert red == {32768 + 1500} and blue == {32768 - 2000}
    # Each layer's Z written once, before its marks: the blue layer first (the layers run in
    # the order given, what none matches last).
    assert [value for _, value in writes(board.bytes_in, "z")] == [32768 - 2000, 32768 + 1500]


@pytest.mark.parametrize("more, machine, message", [
    (["--z", "1"], "no_shifter.toml", "needs a focus shifter: set [field] z_units_per_mm"),
    (["--z", "40"], "machine.toml", "Z 40 mm is past the focus shifter's range (-32.8 … 32.8 mm"),
    (["--layer", "#ff0000", "z=-33"], "machine.toml", "Z -33 mm is past the focus shifter's"),
    (["--z", "101"], "machine.toml", "--z"),
    (["--z", "high"], "machine.toml", "--z"),
])
def test_a_z_the_machine_cannot_make_is_one_line_before_any_byte(files, capsys, more, machine,
                                                                 message):
    with pytest.raises(SystemExit) as stop:
        main(mark_args(files, *more, *NOPORT, machine=machine))
    assert stop.value.code not in (0, None)
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) >= 1 and message in err[-1], err


def test_a_bitstream_without_z_refuses_it_before_any_write(files, capsys):
    """The iCEBreaker's vector build has no Z channel (caps): one line, and the board received
    no write at all."""
    with quick_sim_board(**VECTOR_BOARD) as Board, pytest.raises(SystemExit) as stop:
        main(mark_args(files, "--z", "1", "--sim", "--timeout", "600"))
    assert stop.value.code == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("galvoscan mark: error: job refused: the board's bitstream has "
                              "no Z channel"), err
    board, = Board.built
    assert writes(board.bytes_in) == [] and board.pulses == []


def test_estimate_says_each_layers_z(files, capsys):
    """`--estimate --json`: each layer's Z in mm (the red layer the job's, the blue its own)."""
    import json
    assert main(mark_args(files, "--z", "1.5", "--layer", "#0000ff", "z=-2", "--estimate",
                          "--json")) == 0
    record = json.loads(capsys.readouterr().out)
    assert [layer["z_mm"] for layer in record["layers"]] == [-2, 1.5]


def test_a_job_without_z_is_marked_at_the_shifters_middle():
    """The job before left Z at +1.5 mm; the next gives none: its pulses fall on frames with
    the shifter's middle (the streamer writes it), never on the Z the job before left."""
    from galvoscan.link.client import HostClient
    from galvoscan.outputs.stream import JobStreamer
    from galvoscan.sim.board import SimTransport, SimulatedBoard
    board = SimulatedBoard(backend="compiled", **ulx3s_board(mo_lead=QUICK_SIM_BOARD["mo_lead"]))
    client = HostClient(SimTransport(board))
    line = [("jump", 30000, 32768), ("mark", 30400, 32768)]
    registers = {"pitch": 40, "pulses_per_point": 1, "laser_prr": 500, "laser_power": 50,
                 "jump_delay": 20}
    streamer = JobStreamer(client, poll_s=50e-6)
    streamer.run_vector(line, {**registers, "z": 32768 + 1500})
    first = len(board.pulses)
    streamer.run_vector(line, registers)
    assert first and len(board.pulses) > first
    z_at = dict(board.z_frames)
    # Between the first job's last pulse and the second's first (the jobs are far apart).
    second = (board.pulses[first - 1] + board.pulses[first]) // 2
    marks = [(clock, z_at[clock]) for clock, _, _ in pulsed_frames(board)]
    assert {z for clock, z in marks if clock < second} == {32768 + 1500}
    assert {z for clock, z in marks if clock >= second} == {32768}


def test_z_between_the_shifters_steps_is_said(files, capsys):
    (files / "coarse.toml").write_text("[field]\nz_units_per_mm = 0.5\n")
    assert main(mark_args(files, "--z", "1", "--estimate", machine="coarse.toml")) == 0
    out = capsys.readouterr().out
    assert "note: Z 1 mm is not a whole step of the focus shifter (0.5 units/mm): sent as +2 mm" \
        in out


def test_a_layers_z_past_the_range_names_the_layer(files, capsys):
    with pytest.raises(SystemExit):
        main(mark_args(files, "--layer", "#0000ff", "z=-40", *NOPORT))
    assert "layer 1 ('#0000ff'): Z -40 mm is past" in capsys.readouterr().err
