"""A station on a belt with no PC: `galvoscan store --board ulx3s` with the production line's
options (the part sensor and the PLC's output, the fly, SkyWriting), and the ULX3S's job
player playing such an image on the simulated board (`standalone --sim --board ulx3s`): each
repeat waits for a part at the sensor, and the "done" output pulses after it, read off the
``io_out`` pins. What the iCEBreaker's marker cannot play is refused in one line, nothing
written."""

import json

import pytest

from galvoscan.cli import main
from galvoscan.gateware.fields import FlyControl, IOKind
from galvoscan.outputs.image import read_image

from sim_board import QUICK_SIM_BOARD, part_arrivals
from ulx3s_board import ulx3s_sim


SVG = ('<svg xmlns="http://www.w3.org/2000/svg" width="6mm" height="2mm" viewBox="0 0 6 2">'
       '<path d="M0 1 H2" stroke="#000" fill="none"/>'
       '<path d="M4 1 H6" stroke="#000" fill="none"/></svg>')
#: The tests' ULX3S at 8 MHz: clocks a 10 µs frame.
FRAME_CLOCKS = 80


@pytest.fixture
def drawing(tmp_path):
    path = tmp_path / "lines.svg"
    path.write_text(SVG)
    return path


def kinds(image):
    return [op.kind for op, *_ in image.segments if not isinstance(op, str)]


def test_the_ulx3s_player_waits_for_each_part_and_says_it_is_done(drawing, tmp_path, capsys):
    image_path = tmp_path / "line.img"
    assert main(["store", str(drawing), "--board", "ulx3s", "--wait-input", "part",
                 "--set-output", "done", "--output-pulse", "1", "--repeats", "2",
                 "-o", str(image_path)]) == 0
    assert "2 I/O step(s)" in capsys.readouterr().out
    image = read_image(image_path.read_bytes())
    assert kinds(image) == [IOKind.WAIT_INPUT, IOKind.SET_OUTPUT] and image.repeats == 2
    with ulx3s_sim(QUICK_SIM_BOARD["mo_lead"]) as Board:
        assert main(["standalone", "--sim", "--board", "ulx3s", "--flash", str(image_path),
                     "--part-every", "10", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["presses"] == ["done"] and report["underruns"] == 0
    board, = Board.built
    came = part_arrivals(board)
    pulses = board.pulses
    gaps = [k for k in range(1, len(pulses)) if pulses[k] - pulses[k - 1] > 300 * FRAME_CLOCKS]
    assert len(gaps) == 1
    parts = [pulses[:gaps[0]], pulses[gaps[0]:]]
    assert len(parts[0]) == len(parts[1]) > 0
    # Each repeat's marks start soon after a part came, each on a part of its own: the
    # second within the jump back to the first line (its 500 µs delay, the profile's, and
    # the laser-on delay; the player armed and running), the first once the player has
    # checked the image and led the laser in too (the part may come while it does).
    starts = []
    for burst, within in zip(parts, (4e-3 * board.clk_freq, 1e-3 * board.clk_freq)):
        before = [at for at in came if at <= burst[0]]
        assert before and burst[0] - before[-1] < within, (burst[0], came)
        starts.append(before[-1])
    assert starts[0] < starts[1]
    # "done" pulses 1 ms (100 frames) after each part's last mark, once the laser is off
    # (the jump that ends the part, its 500 µs delay).
    changes = board.io_changes
    assert [value for _, value in changes] == [1, 0, 1, 0]
    for (rise, _), (fall, _), burst in zip(changes[::2], changes[1::2], parts):
        assert burst[-1] < rise < burst[-1] + 1e-3 * board.clk_freq
        assert 99 * FRAME_CLOCKS <= fall - rise <= 101 * FRAME_CLOCKS
    assert report["io"]["outputs"] == [[round(c / board.clk_freq, 6), v] for c, v in changes]


def test_store_for_the_ulx3s_takes_the_fly_and_skywriting(drawing, tmp_path, capsys):
    """The fly set up off and started by the queue (no host to start it), ended after the
    part; SkyWriting's run-ins and run-outs as pixel lines, which the ULX3S plays."""
    image_path = tmp_path / "fly.img"
    assert main(["store", str(drawing), "--board", "ulx3s", "--fly", "X", "--fly-speed",
                 "100", "--sky", "1", "--timelag", "100", "-o", str(image_path)]) == 0
    image = read_image(image_path.read_bytes())
    assert kinds(image) == [IOKind.FLY_START, IOKind.FLY_END]
    assert image.registers["fly_ctrl"] == FlyControl.const({"x_simulated": 1}).as_value().value
    assert image.registers["fly_scale_x"] or image.registers["fly_scale_x_hi"]
    assert any(op == "line" for op, *_ in image.segments)


@pytest.mark.parametrize("more, message", [
    (["--wait-input", "part"], "has no I/O in the queue: store the job for the ULX3S"),
    (["--set-output", "done"], "has no I/O in the queue"),
    (["--fly", "X", "--fly-speed", "100"], "does not mark on the fly"),
    (["--sky", "1"], "does not take SkyWriting"),
])
def test_the_marker_refuses_what_it_cannot_play(drawing, tmp_path, more, message):
    with pytest.raises(SystemExit, match=message):
        main(["store", str(drawing), *more, "-o", str(tmp_path / "x.img")])
    assert not list(tmp_path.glob("*.img"))


def test_a_part_that_never_comes_stops_the_player_with_the_laser_off(drawing, tmp_path,
                                                                      capsys):
    image_path = tmp_path / "late.img"
    assert main(["store", str(drawing), "--board", "ulx3s", "--wait-input", "part",
                 "--wait-timeout", "0.005", "-o", str(image_path)]) == 0
    capsys.readouterr()
    with ulx3s_sim(QUICK_SIM_BOARD["mo_lead"]) as Board:
        assert main(["standalone", "--sim", "--board", "ulx3s", "--flash", str(image_path),
                     "--part-every", "60000", "--json"]) == 1
    report = json.loads(capsys.readouterr().out)
    assert report["presses"] == ["fault"] and report["pulses"] == 0 and not report["marks"]
    board, = Board.built
    assert board.pulses == []
    assert not any(pins[0] or pins[1] for _, pins in board.laser_changes[-1:])
