"""Running jobs from meerk40t on the galvoscan device, headless and in-process
(tests/support/meerk40t_session.py), on the simulated board, read off the XY2-100 wires and the
laser pins by the tests' own readers: a job paused mid-way from meerk40t's console and from a
GRBL sender (``!``, ``?``, ``~``) is held on the board with the laser disarmed and, resumed,
marks what the same job marks without a pause, point for point and pulse for pulse; meerk40t's
trace (its Outline button) walks the elements' outline with the guide laser, the laser never
armed."""

import time
from collections import Counter

import numpy as np
import pytest

pytest.importorskip("meerk40t")

from galvoscan.link.client import HostClient            # noqa: E402
from galvoscan.sim.board import LASER_PINS              # noqa: E402

from meerk40t_session import (BOTTOM, FIELD_MM, LEFT, RECT_MM, RIGHT, TOP,  # noqa: E402
                              UNIT_MM, GrblSender, distance_to_rect, outline_gaps, plan_name,
                              rect_command, status_bar_heard)
from vector_board import pulses_per_frame               # noqa: E402


#: The zigzag: POINTS corners (scene mm, Y down) of one polyline, ZAG mm across and STEP mm
#: down a corner: more mark segments than the board's queue holds (512), so that a pause
#: finds most of a queue's worth still to send.
POINTS, ZAG, STEP, CORNER = 620, 0.15, 0.01, (48.0, 48.0)
#: Its speed (mm/s), power (‰) and PRR (kHz): GRBL's F60000 (mm/min) and S500 of 1000, and
#: the default profile's PRR (GRBL has no word for it).
SPEED_MM_S, POWER_PERMILLE, PRR_KHZ = 1000.0, 500.0, 50.0
EMITTING = [LASER_PINS.index(name) for name in ("laser_enable", "laser_mo", "laser_am",
                                                  "laser_latch")]
#: Board seconds the tests watch a held job for.
HELD_S = 5e-3
#: meerk40t's status bar while the board holds a job (its items), and once it is done.
HELD = {"paused", "disarmed", "interlock closed"}
READY = {"ready", "disarmed", "interlock closed"}
#: The longest the status bar may take to show a state: the kernel's signal ticks.
HEARD_WITHIN_S = 5.0


def _zigzag():
    x0, y0 = CORNER
    return [(x0 + ZAG * (i % 2), y0 + STEP * i) for i in range(POINTS)]


def _spool_zigzag(kernel, device):
    """The zigzag drawn in meerk40t (its ``polyline`` takes every word after it: the operation
    comes in a command of its own), planned and spooled."""
    device.driver.last_report = device.driver.last_error = None
    kernel.elements.clear_all()
    kernel.console("polyline " + " ".join(f"{x:g}mm {y:g}mm" for x, y in _zigzag()) + "\n")
    kernel.console(f"element* engrave -s {SPEED_MM_S:g} -p {POWER_PERMILLE:g} frequency "
                   f"{PRR_KHZ:g} {plan_name()} copy-selected preprocess validate blob preopt "
                   f"optimize spool\n")


def _ended(device):
    return device.driver.last_report is not None or device.driver.last_error is not None


def _pulses_at(board, since):
    """Pulses at each position (galvo units) off the wires and the pins, frame ``since`` on."""
    board.run_for(0)
    marked = Counter()
    for xy, pulses in pulses_per_frame(board, since):
        if pulses:
            marked[tuple(xy)] += pulses
    return marked


@pytest.fixture(scope="module")
def unpaused(meerk40t):
    """The zigzag marked without a pause: its pulses at each position, and the report."""
    kernel, device, board, lines = meerk40t
    board.run_for(0)
    before = len(board.xy2_frames())
    _spool_zigzag(kernel, device)
    _until(lambda: _ended(device), "the job's end")
    assert device.driver.last_error is None, device.driver.last_error
    report = device.driver.last_report
    assert report.clean and report.segments > 512
    return _pulses_at(board, before), report


def _waited(condition, timeout_s):
    """Whether ``condition()`` came true within ``timeout_s``."""
    deadline = time.monotonic() + timeout_s
    while not condition():
        if time.monotonic() >= deadline:
            return False
        time.sleep(0.005)
    return True


def _until(condition, what, timeout_s=60):
    assert _waited(condition, timeout_s), f"waited in vain for {what}"


class _Writes:
    """Every register write through the real client, while installed."""

    def __init__(self, monkeypatch):
        self.log = []
        original = HostClient.write

        def recording(client, name, value):
            self.log.append((name, value))
            return original(client, name, value)
        monkeypatch.setattr(HostClient, "write", recording)

    def arms(self):
        return [value for name, value in self.log if name == "arm"]


def _watch_the_hold(board, device):
    """Once the board holds the job: the board watched for HELD_S of its time (the streamer's
    waits run it): ``(pulses fired, the emitting pins' changes, the pins now)`` meanwhile."""
    _until(device.driver.hold.holding.is_set, "the job to be held")
    sim = board.board
    start, pulses, changes = sim.now, len(sim.pulses), len(sim.laser_changes)
    _until(lambda: sim.now >= start + HELD_S, "the board's time to pass")
    assert device.driver.hold.holding.is_set()
    return (len(sim.pulses) - pulses, list(sim.laser_changes[changes:]),
            sim.laser_changes[-1][1])


def test_a_job_paused_from_meerk40t_is_held_on_the_board_and_goes_on(meerk40t, unpaused,
                                                                     monkeypatch):
    """meerk40t's ``pause`` (its Pause button) mid-way through the zigzag: the board marks out
    its queue and holds, disarmed (arm = 0 written, no pulse, every emitting pin low for 5 ms
    of its time), the driver's state ``hold`` and meerk40t's status bar ``paused, disarmed``
    (the status poll off: from the held job's own reads); ``pause`` again lets it go on (arm =
    1), and the job ends marked as the same job unpaused marks it, every position with the same
    pulses, with every segment and no underrun reported, the status bar ``ready`` again."""
    kernel, device, board, lines = meerk40t
    reference, reference_report = unpaused
    writes = _Writes(monkeypatch)
    with status_bar_heard(kernel) as heard:
        board.run_for(0)
        before = len(board.xy2_frames())
        sim = board.board
        fired = len(sim.pulses)
        _spool_zigzag(kernel, device)
        _until(lambda: len(sim.pulses) > fired + 50 or _ended(device), "the laser")
        assert not _ended(device), device.driver.last_error
        said = len(lines)
        kernel.console("pause\n")
        pulses, changes, pins = _watch_the_hold(board, device)
        assert device.driver.status()[1] == "hold"
        # (Waited for, and looked at once the job goes on: a held job left held would hang.)
        _waited(lambda: heard and heard[-1] == HELD, HEARD_WITHIN_S)
        while_held = list(heard)
        kernel.console("board_status\n")
        held_said = [line for line in lines[said:] if "galvoscan: board:" in line]
        kernel.console("pause\n")                           # (the Pause button again: resume)
        assert while_held and while_held[-1] == HELD, while_held[-5:]
        assert len(held_said) == 1 and "a job held (paused), the laser disarmed" in held_said[0]
        _until(lambda: _ended(device), "the job's end")
        _until(lambda: heard and heard[-1] == READY, "the status bar to say the board is ready")
        assert device.driver.last_error is None, device.driver.last_error
        report = device.driver.last_report
        assert pulses == 0
        assert not any(pins[i] for i in EMITTING)
        assert not any(p[i] for _, p in changes for i in EMITTING)
        assert writes.arms() == [1, 0, 1, 0]
        assert report.stream.holds == 1
        assert report.segments == reference_report.segments
        assert report.counters["vec_underruns"] == 0 and report.clean
        assert _pulses_at(board, before) == reference
        assert any(line.endswith("held 1 time(s)") for line in lines[said:])
        assert device.driver.status()[1] == "idle"


def test_a_grbl_senders_feed_hold_holds_the_job_and_cycle_start_goes_on(meerk40t, unpaused,
                                                                        grbl_port):
    """The zigzag from a G-code sender through ``grblcontrol`` (F60000, S500): ``!`` mid-way
    holds it on the board, disarmed, ``?`` answers ``Hold``, ``~`` lets it go on; every line
    answered ok, the marks those of the same job from meerk40t's console unpaused."""
    kernel, device, board, lines = meerk40t
    reference, reference_report = unpaused
    device.driver.last_report = device.driver.last_error = None
    kernel.console(f"grblcontrol -p {grbl_port}\n")
    board.run_for(0)
    before = len(board.xy2_frames())
    # The same zigzag in G-code's coordinates: from the field's lower left corner, Y up.
    zigzag = [(x, FIELD_MM - y) for x, y in _zigzag()]
    program = ["G21", "G90", f"G0 X{zigzag[0][0]:g} Y{zigzag[0][1]:g}", "M4 S500",
               f"G1 X{zigzag[1][0]:g} Y{zigzag[1][1]:g} F{SPEED_MM_S * 60:g}",
               *(f"G1 X{x:g} Y{y:g}" for x, y in zigzag[2:])]
    sender = GrblSender(grbl_port)
    sim = board.board
    try:
        answers = [sender.send(line) for line in program]
        fired = len(sim.pulses)
        sender.socket.sendall(b"M5\n")                  # the zigzag is marked
        _until(lambda: len(sim.pulses) > fired + 50 or _ended(device), "the laser")
        assert not _ended(device), device.driver.last_error
        sender.socket.sendall(b"!")
        pulses, changes, pins = _watch_the_hold(board, device)
        sender.socket.sendall(b"?")
        status = sender.line()
        sender.socket.sendall(b"~")
        answers.append(sender.line())                   # M5's, once the job has ended
    finally:
        sender.close()
        kernel.console("grblcontrol quit\n")
    assert answers == ["ok"] * (len(program) + 1)
    assert status.startswith("<Hold|"), status
    assert pulses == 0 and not any(pins[i] for i in EMITTING)
    assert not any(p[i] for _, p in changes for i in EMITTING)
    assert device.driver.last_error is None, device.driver.last_error
    report = device.driver.last_report
    assert report.stream.holds == 1 and report.clean
    assert report.segments == reference_report.segments
    assert _pulses_at(board, before) == reference


# meerk40t 0.9.9100's convex hull (core/geomstr.py) takes np.cross of 2-D vectors, which NumPy
# 2 deprecates: its warning, not the device's.
@pytest.mark.filterwarnings("ignore:Arrays of 2-dimensional vectors are deprecated:"
                            "DeprecationWarning")
def test_meerk40ts_trace_walks_the_outline_with_the_guide_laser(meerk40t, monkeypatch):
    """meerk40t's trace of a rectangle (``element* trace hull``: what its Outline button runs):
    the head walks the rectangle all round with the guide laser on, the laser never armed and
    not a pulse fired."""
    kernel, device, board, lines = meerk40t
    kernel.elements.clear_all()
    kernel.console(f"{rect_command(*RECT_MM)}\n")
    writes = _Writes(monkeypatch)
    board.run_for(0)
    before, pulses = len(board.xy2_frames()), len(board.board.pulses)
    changes = len(board.board.laser_changes)
    device.driver.last_report = device.driver.last_error = None
    kernel.console("element* trace hull\n")
    _until(lambda: _ended(device), "the trace")
    assert device.driver.last_error is None, device.driver.last_error
    assert any("framed the selection's outline 1 time(s) with the guide laser" in line
               for line in lines)
    assert ("arm", 1) not in writes.log
    assert len(board.board.pulses) == pulses
    guide = LASER_PINS.index("laser_guide")
    assert any(p[guide] for _, p in board.board.laser_changes[changes:])
    assert not any(p[i] for _, p in board.board.laser_changes[changes:] for i in EMITTING)
    board.run_for(0)
    traced = (np.array([xy for _, xy in board.xy2_frames()[before:]], dtype=float)
              - 32768) * UNIT_MM
    on = traced[distance_to_rect(traced) <= 0.05]
    assert len(on) > 100
    assert outline_gaps(on, LEFT, TOP, RIGHT, BOTTOM) <= 0.05


def test_a_trace_past_the_field_is_one_line_and_nothing_sent(meerk40t):
    """A rectangle reaching past the lens field, traced: one line, not a byte to the board."""
    kernel, device, board, lines = meerk40t
    kernel.elements.clear_all()
    kernel.console("rect 105mm 20mm 10mm 10mm engrave\n")
    sent, said = len(board.board.bytes_in), len(lines)
    device.driver.last_report = device.driver.last_error = None
    kernel.console("element* trace quick\n")
    _until(lambda: _ended(device), "the refusal")
    errors = [line for line in lines[said:] if "galvoscan: error:" in line]
    assert len(errors) == 1 and "outline refused, nothing sent" in errors[0], lines[said:]
    assert "field" in errors[0]
    assert len(board.board.bytes_in) == sent
