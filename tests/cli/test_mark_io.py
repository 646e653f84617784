"""`galvoscan mark --wait-input part --set-output done --repeat N`: parts on a line, end to end
on the simulated ULX3S (whose bitstream has I/O in the queue). The board's part sensor input
sees a part now and then (the simulated line's); each part is marked only once one has come to
the sensor, and the "done" output to a PLC pulses once its last point is marked, read off the
board's ``io_out`` pins. The refusals come before any byte: a wait's setting without the wait,
a bitstream without I/O in the queue."""

import json

import pytest

from galvoscan.cli import main

from fly_marks import writes
from sim_board import QUICK_SIM_BOARD, VECTOR_BOARD, part_arrivals, quick_sim_board
from ulx3s_board import ulx3s_sim as shared_ulx3s_sim


PROFILE = "[laser]\nspot_mm = 0.1\n[galvo]\njump_delay_us = 100\n"
#: Two short lines.
SVG = ('<svg xmlns="http://www.w3.org/2000/svg" width="6mm" height="2mm" viewBox="0 0 6 2">'
       '<path d="M0 1 H2" stroke="#000" fill="none"/>'
       '<path d="M4 1 H6" stroke="#000" fill="none"/></svg>')
SIM_ULX3S = ["--sim", "--board", "ulx3s", "--baud", "1e6", "--timeout", "600"]
NOPORT = ["--port", "/nonexistent/ttyUSB9"]
#: The ULX3S at 8 MHz (the tests' clock): clocks a 10 µs frame.
FRAME_CLOCKS = 80


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("io")
    (folder / "lines.svg").write_text(SVG)
    (folder / "machine.toml").write_text(PROFILE)
    return folder


def mark_args(files, *more):
    return ["mark", str(files / "lines.svg"), "--speed", "1000",
            "--machine", str(files / "machine.toml"), *more]


def test_each_part_waits_for_the_sensor_and_says_it_is_done(files, capsys):
    with shared_ulx3s_sim(QUICK_SIM_BOARD["mo_lead"]) as Board:
        assert main(mark_args(files, "--wait-input", "part", "--set-output", "done",
                              "--output-pulse", "2", "--repeat", "2", *SIM_ULX3S,
                              "--json")) == 0
    captured = capsys.readouterr()
    assert "I/O: each part waits for input part (input 0) to go high, 60 s at most" in \
        captured.err
    record = json.loads(captured.out)
    assert record["parts"] == 2 and record["underruns"] == 0
    board, = Board.built
    came = part_arrivals(board)
    # The pulses fall in two bursts, a part each, of the same count.
    pulses = board.pulses
    gaps = [k for k in range(1, len(pulses)) if pulses[k] - pulses[k - 1] > 1000 * FRAME_CLOCKS]
    assert len(gaps) == 1
    parts = [pulses[:gaps[0]], pulses[gaps[0]:]]
    assert len(parts[0]) == len(parts[1]) > 0
    # Each burst starts soon after a part came to the sensor, and never before one came: the
    # wait starts only once the board runs (a jump to the first line before it, which the
    # board takes only then), so only the jump's delay (held up to twice for its length) and
    # the laser-on delay come after it: 1 ms at most, of the 25 ms between parts.
    for burst in parts:
        came_before = [at for at in came if at <= burst[0]]
        assert came_before and burst[0] - came_before[-1] < 1e-3 * 8e6, (burst[0], came)
    # The two parts came on different rises: the second part was not the first one's
    # sensor seen again.
    starts = [max(at for at in came if at <= burst[0]) for burst in parts]
    assert starts[0] < starts[1]
    # The "done" output (bit 0) rises once after each part's last pulse, before the next
    # part's first, and falls 2 ms (200 frames) later.
    changes = board.io_changes
    assert [value for _, value in changes] == [1, 0, 1, 0]
    for (rise, _), (fall, _), burst in zip(changes[::2], changes[1::2], parts):
        assert burst[-1] < rise < burst[-1] + 40 * FRAME_CLOCKS
        assert 199 * FRAME_CLOCKS <= fall - rise <= 201 * FRAME_CLOCKS
    assert parts[0][-1] < changes[0][0] < parts[1][0]
    assert [[round(c / board.clk_freq, 6), v] for c, v in changes] == record["io"]["outputs"]


@pytest.mark.parametrize("more, message", [
    (["--wait-level", "low"], "--wait-level is a wait's: give --wait-input too"),
    (["--output-pulse", "5"], "--output-pulse is an output's: give --set-output too"),
    (["--wait-input", "part", "--wait-timeout", "70"], "--wait-timeout"),
    (["--set-output", "done", "--output-pulse", "-1"], "--output-pulse"),
    (["--wait-input", "belt"], "--wait-input"),
])
def test_a_wrong_io_option_is_one_line_before_any_byte(files, capsys, more, message):
    with pytest.raises(SystemExit) as stop:
        main(mark_args(files, *more, *NOPORT))
    assert stop.value.code not in (0, None)
    err = capsys.readouterr().err.strip().splitlines()
    assert err and message in err[-1], err


def test_a_bitstream_without_io_refuses_it_before_any_write(files, capsys):
    """The iCEBreaker's vector build has no I/O in the queue (caps): one line, and the board
    received no write at all."""
    with quick_sim_board(**VECTOR_BOARD) as Board, pytest.raises(SystemExit) as stop:
        main(mark_args(files, "--wait-input", "part", "--sim", "--timeout", "600"))
    assert stop.value.code == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("galvoscan mark: error: job refused: the board's bitstream has "
                              "no I/O in the queue"), err
    board, = Board.built
    assert writes(board.bytes_in) == [] and board.pulses == []
