"""I/O in the queue through the pins of the system top, on both simulated backends: a job
queued through the real link sets an output (``io_out``, recorded at each change) and waits
for an input (``io_in``, which the test raises a while later as a part sensor would); the job
goes on only once the input rose, and both backends record the same to the clock."""

import functools

import pytest

from galvoscan.gateware.fields import IOKind, pack
from galvoscan.gateware.host.regmap import VectorOp
from galvoscan.gateware.sources.vector import IOVecOpWord, IOWord, VecOpWord
from galvoscan.link.client import HostClient
from galvoscan.sim.board import SimTransport, SimulatedBoard

from sim_board import IO_BOARD

FIRST, SECOND = (30000, 30000), (34000, 34000)
#: The pulse on output 1, in 10 µs frames.
PULSE_FRAMES = 3
#: How long after the job is queued the part reaches the sensor on input 0, in s.
PART_AFTER_S = 300e-6


def io_word(kind, *, index, level):
    """``vec_op``'s value of an I/O word (bit 9 set; what it does in bits 8:0)."""
    return pack(IOVecOpWord, io=1) | pack(IOWord, kind=kind, index=index, level=level)


@functools.cache
def run(backend):
    """A jump, output 0 set (held), output 1 pulsed, a wait for input 0 to be high (5 ms at
    most), a jump; input 0 raised :data:`PART_AFTER_S` after. Returns the board and the clock
    the input was raised on. (Once a backend: the tests only read its records.)"""
    board = SimulatedBoard(backend=backend, **IO_BOARD)
    client = HostClient(SimTransport(board))
    client.write_many([("jump_delay", 20), ("run", 1)])
    jump = pack(VecOpWord, op=VectorOp.JUMP)
    client.queue_segments([
        (jump, *FIRST),
        (io_word(IOKind.SET_OUTPUT, index=0, level=1), 0, 0),
        (io_word(IOKind.SET_OUTPUT, index=1, level=1), PULSE_FRAMES, 0),
        (io_word(IOKind.WAIT_INPUT, index=0, level=1), 5, 0),
        (jump, *SECOND),
    ])
    board.run_for(PART_AFTER_S)
    raised = round(board.now * board.clk_freq)
    board.io_inputs = 0b01
    board.run_for(150e-6)
    assert client.read("io") & 0b11 == 0b01         # (the inputs, as the board sees them)
    return board, raised


@pytest.mark.parametrize("backend", ["python", "compiled"])
def test_the_queue_sets_outputs_and_waits_for_an_input(backend):
    board, raised = run(backend)
    at_first = [cycle for cycle, *xy in board.frames if tuple(xy) == FIRST]
    at_second = [cycle for cycle, *xy in board.frames if tuple(xy) == SECOND]
    assert at_first and at_second
    # Output 0 set once the first jump is marked, then output 1 (as its word comes in over
    # the link), back after its pulse; none changed again.
    (held_at, held), (pulse_at, both), (pulse_end, after) = board.io_changes
    assert (held, both, after) == (0b01, 0b11, 0b01)
    assert at_first[0] <= held_at < pulse_at < raised
    frame_clocks = round(10e-6 * board.clk_freq)
    assert (PULSE_FRAMES - 1) * frame_clocks < pulse_end - pulse_at <= PULSE_FRAMES * frame_clocks
    # The queue held at the first jump's end until the input rose: the second jump's frames
    # only after, and within a few frames (its synchroniser, the jump's frames).
    assert raised < at_second[0] < raised + 10 * frame_clocks
    moved = [cycle for cycle, *xy in board.frames if cycle > at_first[0] and tuple(xy) != FIRST]
    assert min(moved) > raised


def test_both_backends_record_the_same_io():
    python, _ = run("python")
    compiled, _ = run("compiled")
    assert python.io_changes and python.io_changes == compiled.io_changes
    assert python.frames == compiled.frames
