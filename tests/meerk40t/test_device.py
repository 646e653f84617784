"""The galvoscan device in meerk40t (galvoscan/meerk40t/), headless and in-process as meerk40t's
own driver tests run (its test/bootstrap.py: a kernel of its core plugins, console commands;
tests/support/meerk40t_session.py): the plugin found through the ``meerk40t.extension`` entry
point, a job made with meerk40t's own commands, planned by galvoscan and marked on the
simulated board, and the marks read off the XY2-100 wires by the tests' own reader
(tests/support/wires.py) against the rectangle meerk40t was told to make, computed here from
the command's numbers."""

import os
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from hypothesis import given, settings, strategies as st

pytest.importorskip("meerk40t")

from meerk40t.core.cutcode.cubiccut import CubicCut     # noqa: E402
from meerk40t.core.cutcode.dwellcut import DwellCut     # noqa: E402
from meerk40t.core.cutcode.inputcut import InputCut     # noqa: E402
from meerk40t.core.cutcode.linecut import LineCut       # noqa: E402
from meerk40t.core.cutcode.outputcut import OutputCut   # noqa: E402
from meerk40t.core.cutcode.plotcut import PlotCut       # noqa: E402
from meerk40t.core.cutcode.quadcut import QuadCut       # noqa: E402
from meerk40t.core.cutcode.rastercut import RasterCut   # noqa: E402

from galvoscan import api                               # noqa: E402
from galvoscan.geometry.field import PlanError          # noqa: E402
from galvoscan.link.client import HostClient            # noqa: E402
from galvoscan.meerk40t.cutcode import job_from_cuts    # noqa: E402
from galvoscan.meerk40t.driver import SIM               # noqa: E402
from galvoscan.profile.keys import SECTIONS             # noqa: E402
from galvoscan.profile.machine import default_profile, load_profile  # noqa: E402
from galvoscan.profile.template import profile_text     # noqa: E402
from galvoscan.sim.board import PTYServer               # noqa: E402

from meerk40t_session import (BOTTOM, FIELD_MM, LEFT, POWER_PERMILLE, PRR_KHZ,  # noqa: E402
                              PROFILE, RECT_MM, RIGHT, SPEED_MM_S, TOP, UNIT_MM, GrblSender,
                              distance_to_rect, marks_off_the_wires, median_pitch,
                              outline_gaps, plan_name, rect_command, spool_and_wait)
from sim_board import SimBoard                          # noqa: E402


def test_a_rectangle_from_meerk40t_is_marked_on_the_simulated_board(meerk40t):
    """meerk40t's rectangle, engraved through the device: every mark off the wires lies on the
    rectangle within half a pitch (and a galvo unit of rounding), the marks go all round it,
    and the console said the plan's speed (the nearest the pitch and PRR make)."""
    kernel, device, board, lines = meerk40t
    board.run_for(0)
    before = len(board.xy2_frames())
    started = time.monotonic()
    spool_and_wait(kernel, device, rect_command(*RECT_MM))
    took = time.monotonic() - started
    assert device.driver.last_error is None, device.driver.last_error
    report = device.driver.last_report
    assert report.clean
    marks, pulses = marks_off_the_wires(board, before)
    assert len(marks) > 100
    # The pitch and the pulses a point, off the wires: the speed they make is the one the
    # console said, the nearest to meerk40t's 400 mm/s the galvo units and pulses make.
    pitch = median_pitch(marks)
    per_point = int(np.median(pulses))
    speed = pitch * PRR_KHZ * 1e3 / per_point
    said = "\n".join(lines)
    reported = re.search(r"marked at ([\d.]+) mm/s \(pitch ([\d.]+) µm × (\d+) pulses?\)",
                         said)
    assert reported, said
    assert speed == pytest.approx(float(reported[1]), rel=0.01)
    assert pitch * 1000 == pytest.approx(float(reported[2]), abs=0.1)
    assert per_point == int(reported[3])
    assert speed == pytest.approx(SPEED_MM_S, rel=0.03)
    assert f"{SPEED_MM_S:g} mm/s falls between the speeds" in said     # the nearer speed's note
    assert f"speed {SPEED_MM_S:g} mm/s, power {POWER_PERMILLE / 10:g} %, PRR {PRR_KHZ:g} kHz" \
        in said
    # Every mark on meerk40t's rectangle, within half a pitch (and a galvo unit of rounding).
    assert distance_to_rect(marks).max() <= pitch / 2 + UNIT_MM
    # All round: every point of the outline within half a pitch of a mark.
    assert outline_gaps(marks, LEFT, TOP, RIGHT, BOTTOM) <= pitch / 2 + UNIT_MM
    assert "galvoscan: marked" in said
    assert took < 60


def test_a_circle_from_meerk40t_is_marked_round(meerk40t):
    """meerk40t's circle (its cutcode is cubic curves, flattened by the device): every mark off
    the wires within the chord tolerance and half a pitch of the circle, all round it."""
    kernel, device, board, lines = meerk40t
    board.run_for(0)
    before = len(board.xy2_frames())
    centre, radius = (52.0, 57.0), 3.0
    spool_and_wait(kernel, device, f"circle {centre[0]:g}mm {centre[1]:g}mm {radius:g}mm engrave "
                         f"-s {SPEED_MM_S:g} -p {POWER_PERMILLE:g} frequency {PRR_KHZ:g}")
    assert device.driver.last_error is None, device.driver.last_error
    assert device.driver.last_report.clean
    marks, _ = marks_off_the_wires(board, before)
    pitch = median_pitch(marks)
    cx, cy = centre[0] - FIELD_MM / 2, FIELD_MM / 2 - centre[1]
    off = abs(np.hypot(marks[:, 0] - cx, marks[:, 1] - cy) - radius)
    assert off.max() <= device.tolerance_mm + pitch / 2 + UNIT_MM
    angles = np.linspace(0, 2 * np.pi, 720, endpoint=False)
    ring = np.column_stack([cx + radius * np.cos(angles), cy + radius * np.sin(angles)])
    nearest = np.min(np.hypot(*(ring[:, None, :] - marks[None, :, :]).transpose(2, 0, 1)),
                     axis=1)
    assert nearest.max() <= device.tolerance_mm + pitch / 2 + UNIT_MM


def test_a_rectangle_over_a_serial_link_to_board_sim(meerk40t):
    """The device's link set to a serial port: the pseudo-terminal ``galvoscan board --sim``
    serves (its PTYServer, here in this process), the same board: the rectangle off the wires
    as through the in-process link."""
    kernel, device, board, lines = meerk40t
    board.run_for(0)
    before = len(board.xy2_frames())
    server = PTYServer(board.board).start()
    try:
        device.link = server.port
        spool_and_wait(kernel, device, rect_command(*RECT_MM))
    finally:
        device.link = SIM
        server.stop()
    assert server.error is None
    assert device.driver.last_error is None, device.driver.last_error
    assert device.driver.last_report.clean
    marks, _ = marks_off_the_wires(board, before)
    pitch = median_pitch(marks)
    assert distance_to_rect(marks).max() <= pitch / 2 + UNIT_MM
    assert outline_gaps(marks, LEFT, TOP, RIGHT, BOTTOM) <= pitch / 2 + UNIT_MM


def test_a_job_over_the_field_is_one_line_and_nothing_sent(meerk40t):
    """A rectangle reaching past the lens field: one line on the console, and not a byte to
    the board."""
    kernel, device, board, lines = meerk40t
    sent = len(board.board.bytes_in)
    said = len(lines)
    spool_and_wait(kernel, device, rect_command(FIELD_MM - 5, 20, 10, 10))
    errors = [line for line in lines[said:] if "galvoscan: error:" in line]
    assert len(errors) == 1, lines[said:]
    assert "nothing sent" in errors[0] and "field" in errors[0]
    assert "\n" not in errors[0]
    assert not any(line.startswith("galvoscan: marked") for line in lines[said:])
    assert len(board.board.bytes_in) == sent


def test_a_port_that_cannot_be_opened_is_one_line(meerk40t, tmp_path):
    kernel, device, board, lines = meerk40t
    start = len(lines)
    device.link = str(tmp_path / "ttyNONE")
    try:
        spool_and_wait(kernel, device, rect_command(*RECT_MM))
    finally:
        device.link = SIM
    errors = [line for line in lines[start:] if "galvoscan: error:" in line]
    assert len(errors) == 1 and "the board cannot be opened, nothing sent" in errors[0], \
        lines[start:]
    assert device.laser_status == "idle"


def test_a_speed_the_laser_cannot_make_is_refused(meerk40t):
    kernel, device, board, lines = meerk40t
    sent = len(board.board.bytes_in)
    spool_and_wait(kernel, device, "rect 40mm 40mm 5mm 5mm engrave -s 5000 frequency 20")
    assert "out of reach" in device.driver.last_error
    assert len(board.board.bytes_in) == sent


def test_stop_sends_arm_0_first_and_leaves_the_board_ready(meerk40t, monkeypatch):
    """A long job stopped from meerk40t mid-way: the first write after the stop is arm = 0,
    the console says the job stopped, the laser stops pulsing, and the next job runs
    clean."""
    kernel, device, board, lines = meerk40t
    writes, stop_at = [], []
    original = HostClient.write

    def recording(self, name, value):
        writes.append((name, value))
        return original(self, name, value)
    monkeypatch.setattr(HostClient, "write", recording)
    device.driver.last_report = device.driver.last_error = None
    kernel.elements.clear_all()
    # A slow circle: seconds of the board's time.
    kernel.console(f"circle 55mm 55mm 20mm engrave -s 20 frequency 20 {plan_name()} copy-selected "
                   "preprocess validate blob preopt optimize spool\n")
    deadline = time.monotonic() + 60
    pulses_before = len(board.board.pulses)
    while len(board.board.pulses) < pulses_before + 200:
        assert time.monotonic() < deadline and device.driver.last_error is None, \
            device.driver.last_error
        time.sleep(0.01)
    stop_at.append(len(writes))
    kernel.console("estop\n")
    while device.driver.last_error is None and device.driver.last_report is None:
        assert time.monotonic() < deadline
        time.sleep(0.02)
    assert device.driver.last_report is None
    assert "job stopped, laser disarmed" in device.driver.last_error
    after = writes[stop_at[0]:]
    assert after and after[0] == ("arm", 0), after[:5]
    # No pulse once the disarm had landed: the board is given a moment more of its time.
    pulses = len(board.board.pulses)
    board.board.run_for(2e-3)
    assert len(board.board.pulses) == pulses
    monkeypatch.undo()
    spool_and_wait(kernel, device, rect_command(*RECT_MM))
    assert device.driver.last_error is None, device.driver.last_error
    assert device.driver.last_report.clean


#: The G-code sender's square: its corner and side (mm), at M4 S500 F6000 (mm/min).
GRBL_CORNER, GRBL_SIDE = (50.0, 50.0), 6.0


def test_a_square_from_a_grbl_sender_through_grblcontrol(meerk40t, grbl_port):
    """meerk40t's GRBL server (``grblcontrol``) with the galvoscan device active: a sender's
    square at M4 S500 F6000 has every line answered ok and is marked, the marks off the wires
    on the square (its G-code coordinates taken as a sender's, Y up, through the device's view),
    at 100 mm/s and 50 %; ``?`` is answered with a status report. (The square's place: G-code's
    0,0 at the field's lower left corner, its Y up; tests/meerk40t/test_marks.py has an L that
    shows the way up.)"""
    kernel, device, board, lines = meerk40t
    device.driver.last_report = device.driver.last_error = None
    port = grbl_port
    kernel.console(f"grblcontrol -p {port}\n")
    board.run_for(0)
    before = len(board.xy2_frames())
    x0, y0 = GRBL_CORNER
    x1, y1 = x0 + GRBL_SIDE, y0 + GRBL_SIDE
    program = ["G21", "G90", f"G0 X{x0:g} Y{y0:g}", "M4 S500", f"G1 X{x1:g} Y{y0:g} F6000",
               f"G1 X{x1:g} Y{y1:g}", f"G1 X{x0:g} Y{y1:g}", f"G1 X{x0:g} Y{y0:g}", "M5"]
    sender = GrblSender(port)
    try:
        answers = [sender.send(line) for line in program]
        sender.socket.sendall(b"?")
        status = sender.line()
    finally:
        sender.close()
        kernel.console("grblcontrol quit\n")
    assert answers == ["ok"] * len(program)
    assert re.fullmatch(r"<(Idle|Run)\|MPos:[-\d.]+,[-\d.]+,[-\d.]+\|FS:.*>", status), status
    assert device.driver.last_error is None, device.driver.last_error
    assert device.driver.last_report.clean
    said = "\n".join(lines)
    assert "(speed 100 mm/s, power 50 %)" in said          # F6000 mm/min, S500 of 1000
    marks, pulses = marks_off_the_wires(board, before)
    # G-code's 0,0 at the field's lower left corner, its Y up.
    left, bottom = x0 - FIELD_MM / 2, y0 - FIELD_MM / 2
    right, top = left + GRBL_SIDE, bottom + GRBL_SIDE
    pitch = median_pitch(marks)
    # GRBL gives no PRR: the profile's. The speed off the wires is F6000's 100 mm/s.
    speed = pitch * PROFILE.defaults.prr_khz * 1e3 / int(np.median(pulses))
    assert speed == pytest.approx(6000 / 60, rel=0.03)
    assert distance_to_rect(marks, left, top, right, bottom).max() <= pitch / 2 + UNIT_MM
    assert outline_gaps(marks, left, top, right, bottom) <= pitch / 2 + UNIT_MM


def test_ctrl_x_from_a_grbl_sender_stops_the_job(meerk40t, grbl_port):
    """GRBL's soft reset (0x18) during a slow square reaches the board: the job stops with the
    laser disarmed, the pulses stop, and the sender's next square is marked clean."""
    kernel, device, board, lines = meerk40t
    device.driver.last_report = device.driver.last_error = None
    port = grbl_port
    kernel.console(f"grblcontrol -p {port}\n")
    slow = ["G21", "G90", "G0 X50 Y50", "M4 S500", "G1 X70 Y50 F60", "G1 X70 Y70", "M5"]
    sender = GrblSender(port)
    try:
        for line in slow[:-1]:
            assert sender.send(line) == "ok"
        pulses = len(board.board.pulses)
        sender.socket.sendall(b"M5\n")                # the slow square starts
        deadline = time.monotonic() + 60
        while len(board.board.pulses) < pulses + 200:
            assert time.monotonic() < deadline and device.driver.last_error is None
            time.sleep(0.01)
        sender.socket.sendall(b"\x18")
        while device.driver.last_error is None:
            assert time.monotonic() < deadline and device.driver.last_report is None
            time.sleep(0.02)
        assert "job stopped, laser disarmed" in device.driver.last_error
        stopped = len(board.board.pulses)
        board.board.run_for(2e-3)
        assert len(board.board.pulses) == stopped
        # GRBL's greeting again after its reset, and the M5 line's answer once its job ended.
        heard = set()
        while not {"Grbl", "[MSG", "ok"} <= heard:
            heard.add(sender.line()[:4])
        device.driver.last_error = None
        for line in ["G0 X50 Y50", "M4 S500", "G1 X52 Y50 F6000", "M5"]:
            assert sender.send(line) == "ok"
    finally:
        sender.close()
        kernel.console("grblcontrol quit\n")
    assert device.driver.last_error is None, device.driver.last_error
    assert device.driver.last_report.clean


def test_the_boards_state_in_meerk40ts_console(meerk40t):
    """``board_status``: the board read and said in one line: ready with the interlock closed,
    then the interlock opened on the simulated machine, and closed again."""
    kernel, device, board, lines = meerk40t
    spool_and_wait(kernel, device, rect_command(*RECT_MM))         # (the board exists, and is idle)

    def said():
        start = len(lines)
        kernel.console("board_status\n")
        found = [line for line in lines[start:] if "galvoscan: board:" in line]
        assert len(found) == 1, lines[start:]
        return found[0]
    assert "ready, disarmed, interlock closed, no fault latched" in said()
    board.board.interlock_closed = False
    try:
        assert "interlock open" in said()
    finally:
        board.board.interlock_closed = True
    assert "interlock closed" in said()
    assert device.laser_status == "idle"


def test_frame_traces_the_last_job_with_the_guide_laser(meerk40t, monkeypatch):
    """``guide_frame 2`` after meerk40t's rectangle: its outline traced twice off the wires, the
    laser never armed and not a pulse fired; the console says so."""
    kernel, device, board, lines = meerk40t
    spool_and_wait(kernel, device, rect_command(*RECT_MM))
    writes = []
    original = HostClient.write

    def recording(self, name, value):
        writes.append((name, value))
        return original(self, name, value)
    monkeypatch.setattr(HostClient, "write", recording)
    board.run_for(0)
    before, pulses = len(board.xy2_frames()), len(board.board.pulses)
    clocks = len(board.laser_pins)
    device.driver.last_report = device.driver.last_error = None
    kernel.console("guide_frame 2\n")
    deadline = time.monotonic() + 60
    while device.driver.last_report is None and device.driver.last_error is None:
        assert time.monotonic() < deadline, lines[-15:]
        time.sleep(0.02)
    assert device.driver.last_error is None, device.driver.last_error
    assert any("framed the job's outline 2 time(s) with the guide laser" in line
               for line in lines)
    assert ("arm", 1) not in writes
    assert len(board.board.pulses) == pulses
    guide = SimBoard.LASER_PIN_NAMES.index("laser_guide")
    assert any(pins[guide] for pins in board.laser_pins[clocks:])
    board.run_for(0)
    traced = (np.array([xy for _, xy in board.xy2_frames()[before:]], dtype=float)
              - 32768) * UNIT_MM
    # Where the mirrors dwelt: on the rectangle (the hull of a rectangle is itself), all round.
    away = distance_to_rect(traced)
    on = traced[away <= 0.05]
    assert len(on) > 100
    assert outline_gaps(on, LEFT, TOP, RIGHT, BOTTOM) <= 0.05


def test_a_profile_that_cannot_be_read_is_one_line_and_the_field_kept(meerk40t, tmp_path):
    """The device's machine profile setting: a file that is not there, or not a profile, is
    one line on the console and the profile in use is kept; a good one gives the view its
    field."""
    kernel, device, board, lines = meerk40t
    try:
        for path, words in ((tmp_path / "none.toml", "no such file"),
                            (tmp_path / "bad.toml", "bad.toml")):
            if path.name == "bad.toml":
                path.write_text("[field]\nsize_mm = -3\n")
            start = len(lines)
            device.profile_path = str(path)
            device.realize(device.path)
            errors = [line for line in lines[start:] if "galvoscan: error:" in line]
            assert len(errors) == 1 and words in errors[0], lines[start:]
            assert device.profile.field.size_mm == FIELD_MM
        good = tmp_path / "lens.toml"
        good.write_text("[field]\nsize_mm = 70\n")
        device.profile_path = str(good)
        device.realize(device.path)
        assert device.profile.field.size_mm == 70
        assert device.view.width == "70mm"
    finally:
        device.profile_path = ""
        device.realize(device.path)
    assert device.profile.field.size_mm == FIELD_MM


@pytest.fixture
def default_profile_again(meerk40t):
    """The device back on galvoscan's default profile after the test, whatever it set."""
    kernel, device, board, lines = meerk40t
    yield
    device.profile_path = ""
    device.realize(device.path)
    assert device.profile == default_profile()


#: What meerk40t shows a key of each kind as (a pair as text, "20, 200").
SHOWN_AS = {"number": float, "integer": int, "bool": bool, "text": str, "path": str,
            "pair": str, "choice": str}


def test_every_profile_key_is_a_device_setting(meerk40t, default_profile_again):
    """galvoscan's declaration of the profile's keys, each a setting of the device in meerk40t
    (``choices/galvoscan``, what its property panels show), its value the profile's; set as
    meerk40t's panels set a value, the profile in use changes (the view takes the new field)
    and the file does not; a bad value is one line and changes nothing."""
    kernel, device, board, lines = meerk40t
    choices = {c["attr"]: c for c in device.lookup("choices/galvoscan")}
    profile = device.profile
    for section, keys in SECTIONS.items():
        for key in keys:
            choice = choices.pop(f"{section}_{key.name}")
            assert choice["type"] is SHOWN_AS[key.kind]
            assert key.help in choice["tip"]
            value = getattr(getattr(profile, section), key.name)
            shown = getattr(choice["object"], choice["attr"])
            if key.kind == "pair":
                assert shown == ", ".join(f"{v:g}" for v in value)
            else:
                assert shown == ("" if value is None else value)
    # What is left: the device's own settings.
    assert set(choices) == {"label", "profile_path", "link", "tolerance_mm", "status_poll_s"}
    settings = device.profile_settings
    settings.field_size_mm = 70.0                   # as meerk40t's panel sets it
    settings.laser_prr_khz = "30, 80"
    assert device.profile.field.size_mm == 70 and device.view.width == "70mm"
    assert device.profile.laser.prr_khz == (30, 80)
    assert device.lookup("frequency") == (30, 80)
    said = len(lines)
    settings.defaults_speed_mm_s = 2e6
    errors = [line for line in lines[said:] if "galvoscan: error:" in line]
    assert len(errors) == 1 and "[defaults] speed_mm_s" in errors[0], lines[said:]
    assert device.profile.defaults.speed_mm_s == default_profile().defaults.speed_mm_s
    assert device.profile.field.size_mm == 70


def test_galvoscan_profile_lists_sets_and_saves(meerk40t, default_profile_again, tmp_path):
    """``galvoscan_profile``: ``list`` says every key; ``set`` changes the profile in use,
    checked (a bad value one line, nothing changed), the file untouched until ``save``, which
    writes it with every comment kept and only the changed lines different, and it reads back
    through galvoscan's profile reader as set; a profile read from no file is saved only where
    a PATH says."""
    kernel, device, board, lines = meerk40t

    def said(command):
        start = len(lines)
        kernel.console(command + "\n")
        # (Each line from "galvoscan:" on: the console puts the time before it.)
        return [line[line.index("galvoscan:"):] for line in lines[start:]
                if "galvoscan:" in line]
    listed = said("galvoscan_profile list")
    assert len(listed) == 1 + sum(len(keys) for keys in SECTIONS.values())
    assert "galvoscan: [field] size_mm = 110 (1 … 2000 mm)" in listed
    assert "galvoscan: [laser] prr_khz = [20, 200] (20 … 200 kHz)" in listed
    refused = said("galvoscan_profile save")
    assert len(refused) == 1 and "give a PATH" in refused[0]
    path = tmp_path / "machine.toml"
    path.write_text(profile_text())
    device.profile_path = str(path)
    device.realize(device.path)
    assert said("galvoscan_profile set field.size_mm 70")[0].startswith(
        "galvoscan: [field] size_mm = 70")
    assert said("galvoscan_profile set galvo.mark_delay_us 120")
    for bad in ("galvoscan_profile set field.size_mm -3", "galvoscan_profile set field.sze 3",
                "galvoscan_profile set defaults.prr_khz 500", "galvoscan_profile frob"):
        errors = said(bad)
        assert len(errors) == 1 and "galvoscan: error:" in errors[0], (bad, errors)
    assert device.profile.field.size_mm == 70 and device.view.width == "70mm"
    assert device.profile.galvo.mark_delay_us == 120
    assert path.read_text() == profile_text()               # not written until saved
    assert "(changed, not saved)" in said("galvoscan_profile list")[0]
    assert said("galvoscan_profile save") == [f"galvoscan: machine profile written to {path}"]
    written = path.read_text().splitlines()
    template = profile_text().splitlines()
    assert [(a, b) for a, b in zip(template, written) if a != b] == \
        [("size_mm = 110", "size_mm = 70"), ("mark_delay_us = 100", "mark_delay_us = 120")]
    assert len(written) == len(template)
    assert load_profile(path) == device.profile
    elsewhere = tmp_path / "copy.toml"
    said(f"galvoscan_profile save {elsewhere}")
    assert load_profile(elsewhere) == device.profile and device.profile_path == str(elsewhere)


README = (Path(__file__).parents[2] / "README.md").read_text()


def test_the_readmes_first_job_from_meerk40t(tmp_path):
    """The README's "From meerk40t" first job: its batch file and command line, run as the
    README gives them (meerk40t's own program, headless, with the plugin found through the
    entry point), say the plan and the marks the README quotes. meerk40t's settings go to a
    home of the test's own; the simulated board's compiled model is the shared one."""
    section = README[README.index("## From meerk40t"):README.index("## The documentation")]
    batch = re.search(r"\(`first\.txt`\):\n\n```text\n(.+?)```", section, re.S)[1]
    command = re.search(r"```text\n\.venv/bin/(meerk40t [^\n]+)\n```", section)[1].split()
    (tmp_path / "first.txt").write_text(batch)
    cache = os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache")
    done = subprocess.run([str(Path(sys.executable).parent / command[0]), *command[1:]],
                          cwd=tmp_path, capture_output=True, text=True, timeout=120,
                          env={**os.environ, "HOME": str(tmp_path), "XDG_CACHE_HOME": cache})
    assert done.returncode == 0, done.stderr
    out = done.stdout
    quoted = re.findall(r"\(`(layer 1 .+?) …`\)", " ".join(section.split()))
    assert quoted and quoted[0] in " ".join(out.split()), out
    marked = re.search(r"\(`(galvoscan: marked \d+ segments, \d+ pulses)`\)", section)[1]
    assert marked in out, out


# --- cutcode into galvoscan's job, without a board -------------------------------------------

def _native(x_mm, y_mm):
    """Field mm as the device's native units (galvo units, Y up)."""
    return (x_mm / UNIT_MM + 32768, y_mm / UNIT_MM + 32768)


def test_each_cut_kind_becomes_its_operations_layer():
    """Lines joined into one polyline, a quadratic and a cubic curve flattened within the
    tolerance, a dwell a dot of its time's pulses, a raster's dark runs lines; each operation
    a layer of its own with its speed, power and frequency."""
    line_op = {"speed": 300.0, "power": 250.0, "frequency": 40.0}
    curve_op = {"speed": 100.0, "power": 1000.0, "frequency": 20.0}
    dwell_op = {"power": 500.0, "frequency": 30.0}
    raster_op = {"speed": 200.0, "power": 800.0, "frequency": 25.0}
    a, b, c = _native(0, 0), _native(10, 0), _native(10, 10)
    plot = PlotCut(settings=raster_op)
    for k, on in enumerate([1, 1, 0, 1]):
        plot.plot_append(int(_native(k, -5)[0]), int(_native(k, -5)[1]), on)
    plot.plot_append(int(_native(4, -5)[0]), int(_native(4, -5)[1]), 0)
    cuts = [LineCut(a, b, settings=line_op), LineCut(b, c, settings=line_op),
            QuadCut(_native(-10, 0), _native(-10, 10), _native(0, 10), settings=curve_op),
            CubicCut(_native(-10, -10), _native(-10, 0), _native(0, 0), _native(0, -10),
                     settings=curve_op),
            DwellCut(_native(5, 5), dwell_time=2.0, settings=dwell_op),
            plot]
    job, objects = job_from_cuts(cuts, PROFILE, tolerance_mm=0.01)
    assert [(layer.speed_mm_s, layer.power_percent, layer.prr_khz, layer.pulses_per_point)
            for layer in job.layers] == [(300, 25, 40, None), (100, 100, 20, None),
                                         # (A dot's speed: a galvo unit a point of
                                         # its 60 pulses at 30 kHz.)
                                         (pytest.approx(UNIT_MM * 30e3 / 60), 50, 30, 60),
                                         (200, 80, 25, None)]
    lines, curves, dwell, raster = (o.drawing for o in objects)
    assert len(lines.paths) == 1
    assert lines.paths[0] == pytest.approx(np.array([[0, 0], [10, 0], [10, 10]]),
                                           abs=UNIT_MM)
    # The quadratic: B(t) = (1-t)² P0 + 2t(1-t) P1 + t² P2, every chord within 0.01 mm.
    quad, cubic = curves.paths
    t = np.linspace(0, 1, 2001)[:, None]
    p0, p1, p2 = np.array([-10, 0]), np.array([-10, 10]), np.array([0, 10])
    exact = (1 - t) ** 2 * p0 + 2 * t * (1 - t) * p1 + t ** 2 * p2
    assert _max_distance(exact, quad) <= 0.01 + UNIT_MM
    q0, q1, q2, q3 = (np.array(p) for p in ([-10, -10], [-10, 0], [0, 0], [0, -10]))
    exact = ((1 - t) ** 3 * q0 + 3 * t * (1 - t) ** 2 * q1 + 3 * t ** 2 * (1 - t) * q2
             + t ** 3 * q3)
    assert _max_distance(exact, cubic) <= 0.01 + UNIT_MM
    assert len(dwell.paths) == 1 and not np.ptp(dwell.paths[0], axis=0).any()
    assert dwell.paths[0][0] == pytest.approx([5, 5], abs=UNIT_MM)
    # Dark from x = 0 to 2, light from 2 to 3, dark from 3 to 4.
    assert [p[[0, -1], 0].tolist() for p in raster.paths] == \
        [pytest.approx([0, 2], abs=UNIT_MM), pytest.approx([3, 4], abs=UNIT_MM)]


def _max_distance(curve, polyline):
    """The largest distance from a point of ``curve`` to the polyline (its segments)."""
    starts, ends = polyline[:-1], polyline[1:]
    d = ends - starts
    rel = curve[:, None, :] - starts[None, :, :]
    t = np.clip((rel * d).sum(-1) / np.maximum((d * d).sum(-1), 1e-12), 0, 1)
    nearest = starts[None] + t[..., None] * d[None]
    return np.min(np.hypot(*(curve[:, None, :] - nearest).transpose(2, 0, 1)), axis=1).max()


def test_an_images_dark_runs_are_its_lines():
    """A RasterCut of a small image (meerk40t's image operation): a line each run of dark
    pixels, on its row's centre line, from its first pixel's centre to its last's (one pixel:
    a dot), none anywhere else: meerk40t's pixel ``i`` is the square from ``offset + i × step``
    to ``offset + (i + 1) × step`` (its image operation's bounds; its raster plotter puts a run
    half a step before that, which the device moves back)."""
    rows = [".##.#...##",
            "...#......",
            "##########"]
    image = Image.new("L", (len(rows[0]), len(rows)), 255)
    for y, row in enumerate(rows):
        for x, pixel in enumerate(row):
            if pixel == "#":
                image.putpixel((x, y), 0)
    step = 20                                   # galvo units a pixel
    corner = _native(-2, 2)
    cut = RasterCut(image, int(corner[0]), int(corner[1]), step, step,
                    settings={"speed": 200.0, "power": 500.0, "frequency": 50.0})
    job, objects = job_from_cuts([cut], PROFILE, tolerance_mm=0.01)
    (raster,) = (o.drawing for o in objects)
    # Each run from the image, as (row, first pixel, pixels).
    wanted = sorted((y, m.start(), len(m[0])) for y, row in enumerate(rows)
                    for m in re.finditer("#+", row))
    found = []
    for path in raster.paths:
        units = (path - 0) / UNIT_MM + 32768       # back to galvo units
        assert np.ptp(units[:, 1]) < 1e-6           # along one row
        row = (units[0, 1] - int(corner[1])) / step - 0.5
        first = (units[:, 0].min() - int(corner[0])) / step - 0.5
        pixels = np.ptp(units[:, 0]) / step + 1
        assert (row, first, pixels) == pytest.approx(
            (round(row), round(first), round(pixels)), abs=1e-6)
        found.append((round(row), round(first), round(pixels)))
    assert sorted(found) == wanted


def test_a_cut_it_cannot_mark_is_refused_in_one_line():
    """meerk40t's input and output cuts (its I/O operations) are no marks: one line (the
    driver takes them out of the cuts first, as I/O steps: tests/meerk40t/test_io.py)."""
    for cut in (InputCut(1, 1), OutputCut(1, 1)):
        with pytest.raises(PlanError) as refused:
            job_from_cuts([LineCut(_native(0, 0), _native(1, 0), settings={}), cut], PROFILE,
                          tolerance_mm=0.01)
        said = str(refused.value)
        assert f"{type(cut).__name__} (an I/O operation) is no mark" in said
        assert "\n" not in said


def _numbers(low, high):
    """A setting meerk40t may send: mostly a plausible one, else anything."""
    return st.one_of(st.floats(low, high), st.none(), st.integers(-10**6, 10**6),
                     st.floats(allow_nan=True, allow_infinity=True, width=32))


@settings(max_examples=60, deadline=None)
@given(corner=st.tuples(st.integers(-20_000, 80_000), st.integers(-20_000, 80_000)),
       size=st.tuples(st.integers(0, 40_000), st.integers(0, 40_000)),
       speed=_numbers(10, 400), power=_numbers(0, 1000), frequency=_numbers(20, 200),
       dwell=st.one_of(st.none(), st.floats(0.01, 5), st.floats(-10, 1e6),
                       st.just(float("nan"))))
def test_whatever_meerk40t_sends_is_planned_or_refused_in_one_line(corner, size, speed, power,
                                                                   frequency, dwell):
    """Cutcode from meerk40t is input from outside: a rectangle anywhere (in the field or past
    it), at any speed, power and frequency, with or without a dwell, is planned, or refused
    with one line (a ValueError), and nothing else."""
    operation = {key: value for key, value in
                 (("speed", speed), ("power", power), ("frequency", frequency))
                 if value is not None}
    (x, y), (w, h) = corner, size
    points = [(x, y), (x + w, y), (x + w, y + h), (x, y + h), (x, y)]
    cuts = [LineCut(a, b, settings=operation) for a, b in zip(points, points[1:])]
    if dwell is not None:
        cuts.append(DwellCut((x, y), dwell_time=dwell, settings=operation))
    try:
        job, objects = job_from_cuts(cuts, PROFILE, tolerance_mm=0.01)
        plan = api.plan_made(objects, job, PROFILE)
    except ValueError as error:
        said = str(error)
        # One line, naming the operation it is about.
        assert "\n" not in said and "meerk40t operation" in said, said
        return
    # Planned: every point in the field, every speed one the machine makes.
    half = FIELD_MM / 2
    bounds = plan.vector_job.bounds_mm
    assert -half <= min(bounds) and max(bounds) <= half
    assert plan.segments
