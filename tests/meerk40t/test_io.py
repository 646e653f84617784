"""meerk40t's input and output operations (InputCut, OutputCut) through the galvoscan device,
on a simulated board with I/O in the queue: an output cut sets the board's output (read off its
``io_out`` pins) once the cuts before it are marked, and an input cut holds the job until the
board's input (driven by the simulated part sensor) is at the level asked; the cuts split into
I/O steps by the masks' bits, and a mask the board has no pins for refused in one line."""

import time

import pytest

pytest.importorskip("meerk40t")

from meerk40t.core.cutcode.inputcut import InputCut     # noqa: E402
from meerk40t.core.cutcode.linecut import LineCut       # noqa: E402
from meerk40t.core.cutcode.outputcut import OutputCut   # noqa: E402

from galvoscan.gateware.fields import IOKind            # noqa: E402
from galvoscan.geometry.field import PlanError          # noqa: E402
from galvoscan.meerk40t.cutcode import io_steps, job_parts  # noqa: E402
from galvoscan.sim.board import SimulatedBoard          # noqa: E402

from meerk40t_session import device_on                 # noqa: E402
from sim_board import IO_BOARD                          # noqa: E402


SETTINGS = {"speed": 400.0, "power": 500.0, "frequency": 50.0}


@pytest.fixture(scope="module")
def io_device():
    board = SimulatedBoard(backend="compiled", **IO_BOARD)
    with device_on(board) as (kernel, device, lines):
        yield kernel, device, board, lines


def _spooled(device, lines, items, timeout_s=60):
    device.driver.last_report = device.driver.last_error = None
    device.spooler.laserjob(list(items), label="test io", helper=True)
    deadline = time.monotonic() + timeout_s
    while device.driver.last_report is None and device.driver.last_error is None:
        assert time.monotonic() < deadline, ("the device did not finish the job", lines[-8:])
        time.sleep(0.02)


def test_an_output_is_set_after_its_cuts_and_an_input_holds_the_next(io_device):
    kernel, device, board, lines = io_device
    first = LineCut((30000, 30000), (31000, 30000), settings=SETTINGS)
    second = LineCut((31000, 31000), (32000, 31000), settings=SETTINGS)
    # One part, at input 1 (low while it is seen), 200 ms from now: well after the first line
    # (the board's set-up and the line take some 60 ms).
    board.parts_arrive(input=1, first_s=0.2, seen_s=20e-3, level=0)
    came = round((board.now + 0.2) * board.clk_freq)
    pulses = len(board.pulses)
    _spooled(device, lines, [("plot", first), ("plot", OutputCut(1, 1)), ("plot", InputCut(2, 0)),
                      ("plot", second), "plot_start"])
    assert device.driver.last_error is None, device.driver.last_error
    marked = board.pulses[pulses:]
    gaps = [k for k in range(1, len(marked)) if marked[k] - marked[k - 1] > 10_000]
    assert len(gaps) == 1
    one, two = marked[:gaps[0]], marked[gaps[0]:]
    # Output 0 set (held) once the first line was marked, before the second.
    (rise, outputs), = board.io_changes
    assert outputs == 0b01 and one[-1] < rise < two[0]
    # The second line waited for the part: marked only after it came, and soon after (the
    # second line is a job of its own: set up, verified and led in over the link, some 50 ms).
    assert rise < came < two[0] < came + 0.1 * board.clk_freq


def test_the_cuts_are_steps_by_their_masks_bits():
    a = LineCut((30000, 30000), (31000, 30000), settings={})
    b = LineCut((31000, 30000), (31000, 31000), settings={})
    parts = job_parts([a, OutputCut(0b11, 0b10), InputCut(0b01, 0b01), b])
    assert [kind for kind, _ in parts] == ["cuts", "io", "cuts"]
    steps = parts[1][1]
    assert [(s.kind, s.index, s.level, s.edge, s[1]) for s in steps] == [
        (IOKind.SET_OUTPUT, 0, 0, False, 0), (IOKind.SET_OUTPUT, 1, 1, False, 0),
        (IOKind.WAIT_INPUT, 0, 1, False, 60_000)]


@pytest.mark.parametrize("cut, message", [
    (InputCut(0b100, 0b100), "the board has inputs 0 and 1"),
    (OutputCut(0, 0), "the board has outputs 0 and 1"),
    (OutputCut(-1, 0), "a whole number of bits"),
    (InputCut("1", 1), "a whole number of bits"),
    (OutputCut(1, None), "value is None"),
])
def test_a_mask_the_board_has_no_pins_for_is_one_line(cut, message):
    with pytest.raises(PlanError, match=message) as refused:
        io_steps(cut)
    assert "\n" not in str(refused.value)
