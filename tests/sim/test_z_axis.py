"""XY2-100's Z channel through the pins of the system top (#38), on both simulated backends:
the ``z`` register written through the real link reaches the ``xy2_z`` line in the same frames
as X and Y, decoded off the wires by the same receiver as theirs."""

import pytest

from galvoscan.link.client import HostClient
from galvoscan.sim.board import SimTransport, SimulatedBoard

from sim_board import QUICK_SIM_BOARD


BUILD = dict(QUICK_SIM_BOARD, z_axis=True)
FRAME_S = 10e-6


def run(backend):
    """Z at power-up, then two values written: the board's X/Y and Z frames."""
    board = SimulatedBoard(backend=backend, **BUILD)
    client = HostClient(SimTransport(board))
    board.run_for(3 * FRAME_S)
    for z in (12_345, 65_535, 0):
        client.write("z", z)
        board.run_for(3 * FRAME_S)
    return board, client


@pytest.mark.parametrize("backend", ["python", "compiled"])
def test_z_frames_carry_the_z_register(backend):
    board, client = run(backend)
    assert client.read("z") == 0
    # One Z frame with every X/Y frame, complete on the same clock: the same frames.
    assert [cycle for cycle, _ in board.z_frames] == [cycle for cycle, *_ in board.frames]
    values = [z for _, z in board.z_frames]
    # Power-up: the middle of the focus shifter's range; then each value written, in order,
    # each for whole frames, none other.
    assert values[0] == 32_768
    runs = [values[0]]
    for z in values[1:]:
        if z != runs[-1]:
            runs.append(z)
    assert runs == [32_768, 12_345, 65_535, 0]


def test_both_backends_send_the_same_z_frames():
    python, _ = run("python")
    compiled, _ = run("compiled")
    assert python.z_frames == compiled.z_frames and python.frames == compiled.frames


def test_a_build_without_z_has_no_z_line_nor_register():
    board = SimulatedBoard(backend="python", **QUICK_SIM_BOARD)
    assert not hasattr(board.top, "xy2_z")
    assert "z" not in board.top.regmap.by_name
