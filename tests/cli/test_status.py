"""`galvoscan status`: the board's state and its scan head's, read through the real serial
link code from a simulated board (the ULX3S's bitstream, which reads the head's STATUS line;
the iCEBreaker's engraver, which does not) served on a pseudo-terminal."""

import contextlib
import io
import json

from galvoscan.build import simulated_bitstream
from galvoscan.cli import main
from galvoscan.gateware.host.regmap import HeadStatus
from galvoscan.sim.board import PTYServer, SimulatedBoard
from galvoscan.sim.head import HEALTHY_HEAD

from ulx3s_board import ulx3s_board


TEMP_OK = 1 << HeadStatus["temp_ok"].offset


def preset_board(board, preset="default", **kwargs):
    if board == "ulx3s":            # (at the tests' 8 MHz: one compiled model for them all)
        return SimulatedBoard(backend="compiled", **ulx3s_board(), **kwargs)
    config, contents = simulated_bitstream(board, preset=preset)
    return SimulatedBoard(config=config, backend="compiled", **contents, **kwargs)


def status(board, *options):
    out, err = io.StringIO(), io.StringIO()
    with PTYServer(board) as server, contextlib.redirect_stdout(out), \
            contextlib.redirect_stderr(err):
        code = main(["status", "--port", server.port, "--baud", str(board.baud),
                     "--timeout", "30", *options])
    return code, out.getvalue(), err.getvalue()


def test_status_says_the_heads_bits():
    board = preset_board("ulx3s", head_word=HEALTHY_HEAD & ~TEMP_OK)
    code, out, err = status(board, "--json")
    assert code == 0, err
    state = json.loads(out)
    head = state["head"]
    assert head["word"] == HEALTHY_HEAD & ~TEMP_OK
    assert not head["temp_ok"] and head["power_ok"] and head["pos_ack_x"] and head["pos_ack_y"]
    assert not head["missing"] and head["check"] is False and head["fault"] is False
    assert state["latched"] == [] and not state["flags"]["armed"]
    code, out, err = status(board)
    assert code == 0, err
    board_line, head_line = out.splitlines()
    assert board_line.startswith("board: ready, disarmed")
    assert head_line.startswith("head: ") and "no Temp OK" in head_line
    assert f"0x{HEALTHY_HEAD & ~TEMP_OK:04X}" in head_line


def test_status_of_a_board_without_a_head_says_it_is_missing():
    board = preset_board("ulx3s", head_word=None)
    code, out, err = status(board, "--json")
    assert code == 0, err
    head = json.loads(out)["head"]
    assert head["missing"] and head["word"] == 0 and head["refused"] >= 1


def test_status_of_a_bitstream_without_the_receiver_has_no_head():
    board = preset_board("icebreaker", "engraver")
    code, out, err = status(board, "--json")
    assert code == 0, err
    assert json.loads(out)["head"] is None
