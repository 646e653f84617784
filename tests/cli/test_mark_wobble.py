"""`galvoscan mark --wobble` and the profile's [wobble]: µm and Hz made into the board's wob_*
registers through the field size, everything refused in one line before a port is opened, a
board built without the stage refused before the laser is armed, and one job marked on the
simulated board (``--sim``) whose marks, decoded off the XY2-100 wires, lie around the line as
the figure says."""

import contextlib
import io
import json

from hypothesis import given, settings, strategies as st
import pytest

from galvoscan.cli import main
from galvoscan.geometry.field import PlanError
from galvoscan.profile.machine import ProfileError, default_profile, parse_profile
from galvoscan.profile.template import profile_text
from galvoscan.outputs.stream import JobAborted, JobStreamer
from galvoscan.plan.wobble import WobbleSettings, wobble_registers

from sim_board import VECTOR_BOARD, quick_sim_board
from fake_board import FakeBoard, job


# A 2 mm line along X, SVG units = mm (Y down in the file).
LINE = """<svg xmlns="http://www.w3.org/2000/svg" width="4mm" height="4mm" viewBox="0 0 4 4">
  <path d="M 1 2 H 3" fill="none" stroke="black"/>
</svg>
"""
NOPORT = ["--port", "/nonexistent/ttyUSB9"]
UNIT_UM = 110 / 65536 * 1000


@pytest.fixture
def line(tmp_path):
    path = tmp_path / "line.svg"
    path.write_text(LINE)
    return path


def test_micrometres_become_galvo_units_through_the_field():
    profile = default_profile()                                # 110 mm field
    regs = wobble_registers(WobbleSettings(across_um=50, along_um=20, freq_hz=1500.4), profile)
    assert regs == {"wob_shape": 1, "wob_across": round(50 / UNIT_UM),
                    "wob_along": round(20 / UNIT_UM), "wob_freq": 1500}
    small = parse_profile("[field]\nsize_mm = 11\n")          # ten times finer units
    assert wobble_registers(WobbleSettings(50, 50, 1000), small)["wob_across"] == \
        round(50 / (UNIT_UM / 10))
    assert wobble_registers(WobbleSettings(0, 0, 1000), profile) == {}
    assert wobble_registers(None, profile) == {}


@pytest.mark.parametrize("wobble, words", [
    (WobbleSettings(7000, 0, 1000), "4095 galvo units"),
    (WobbleSettings(0.4, 0.4, 1000), "less than one galvo unit"),
    (WobbleSettings(50, 50, 0.2), "outside 1"),
    (WobbleSettings(50, 50, 25_001), "outside 1"),
])
def test_what_the_board_cannot_hold_is_refused(wobble, words):
    with pytest.raises(PlanError, match=words):
        wobble_registers(wobble, default_profile())


def plan_lines(args, capsys):
    assert main(args) == 0
    return capsys.readouterr().out


def test_the_plan_says_what_the_wobble_is(line, capsys):
    out = plan_lines(["mark", str(line), "--estimate", "--wobble", "50", "--wobble-along",
                      "20", "--wobble-hz", "2000"], capsys)
    assert "wobble: ±50 µm across × ±20 µm along (30 × 12 units) at 2000 Hz" in out
    assert "wobble" not in plan_lines(["mark", str(line), "--estimate"], capsys)


def test_the_profile_gives_the_defaults_and_the_command_line_wins(line, tmp_path, capsys):
    machine = tmp_path / "m.toml"
    machine.write_text("[wobble]\nacross_um = 100\nalong_um = 40\nfreq_hz = 500\n")
    out = plan_lines(["mark", str(line), "--estimate", "--machine", str(machine)], capsys)
    # What the board will do: 100 µm is 60 units, ≈ 101 µm.
    assert "±101 µm across × ±40 µm along (60 × 24 units) at 500 Hz" in out
    out = plan_lines(["mark", str(line), "--estimate", "--machine", str(machine),
                      "--wobble", "30"], capsys)
    assert "(18 × 18 units) at 500 Hz" in out
    out = plan_lines(["mark", str(line), "--estimate", "--machine", str(machine),
                      "--wobble", "0", "--wobble-along", "0"], capsys)
    assert "wobble" not in out


def test_the_template_has_the_wobble_section_off():
    assert parse_profile(profile_text()).wobble == default_profile().wobble
    assert default_profile().wobble.across_um == default_profile().wobble.along_um == 0


@pytest.mark.parametrize("text, piece", [
    ("[wobble]\nacross_um = -1\n", "across_um"),
    ("[wobble]\nfreq_hz = 30000\n", "freq_hz"),
    ("[wobble]\nfreq_hz = 'fast'\n", "freq_hz"),
    ("[wobble]\nradius_um = 5\n", "unknown key [wobble] radius_um"),
])
def test_bad_wobble_profiles_are_one_line(text, piece):
    with pytest.raises(ProfileError, match=piece.replace("[", r"\[").replace("]", r"\]")) \
            as error:
        parse_profile(text)
    assert "\n" not in str(error.value)


def refused(args):
    with pytest.raises(SystemExit) as stop:
        main(args)
    message = str(stop.value)
    assert "\n" not in message and "Traceback" not in message
    return message


def test_past_the_field_and_past_the_register_before_the_port(line):
    assert "reaches past the field" in refused(
        ["mark", str(line), *NOPORT, "--offset", "53.9,0", "--wobble", "200"])
    assert "4095 galvo units" in refused(["mark", str(line), *NOPORT, "--wobble", "9000"])


@settings(max_examples=40, deadline=None)
@given(st.sampled_from(["--wobble", "--wobble-along", "--wobble-hz"]),
       st.one_of(st.floats(allow_nan=True, allow_infinity=True).map(repr),
                 st.integers(-10**6, 10**6).map(str), st.text(max_size=8)))
def test_random_wobble_values_plan_or_are_one_line(tmp_path_factory, option, value):
    path = tmp_path_factory.getbasetemp() / "line.svg"
    path.write_text(LINE)
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(["mark", str(path), "--estimate", "--wobble", "50",
                         f"{option}={value}"])
        except SystemExit as stop:
            code = stop.code
    if code != 0:
        lines = [l for l in (str(code) if isinstance(code, str) else err.getvalue())
                 .strip().splitlines() if "note:" not in l]
        assert "Traceback" not in err.getvalue()
        assert lines and ("error" in lines[-1]), lines


def test_a_board_without_the_stage_is_refused_before_arming():
    regs = wobble_registers(WobbleSettings(50, 50, 1000), default_profile())
    board = FakeBoard(missing=[name for name in regs if name.startswith("wob_")])
    with pytest.raises(JobAborted, match="no wobble stage"):
        JobStreamer(board, poll_s=0).run_vector(job(10), {"pitch": 60, **regs})
    assert ("arm", 1) not in board.log
    # Found out without waiting for an answer, nor a write the board refuses and counts.
    assert board.unanswered == [] and board.values["errors"] == 0
    assert board.log == [("arm", 0), ("run", 0), ("guide", 0)]


def test_a_wobbled_job_leaves_the_wobble_off():
    board = FakeBoard()
    regs = wobble_registers(WobbleSettings(50, 50, 1000), default_profile())
    JobStreamer(board, poll_s=0).run_vector(job(10), {"pitch": 60, **regs})
    assert ("wob_shape", 1) in board.log and board.values["wob_shape"] == 0
    assert board.log.index(("wob_shape", 1)) < board.log.index(("arm", 1))


@pytest.mark.slow
def test_a_wobbled_line_marked_on_the_simulated_board(line, tmp_path):
    """The marks off the wires lie within the figure around the line, and reach its width
    across it: a 2 mm line, ±60 µm across, ±20 µm along."""
    machine = tmp_path / "m.toml"
    machine.write_text("[laser]\nspot_mm = 0.1\n[galvo]\njump_delay_us = 100\n")
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()), \
            quick_sim_board(**VECTOR_BOARD, vector_delays=True):
        # (The vector build with the delays and the wobble stage: the model of
        # tests/sim/test_compiled.py's job with delays and wobble on both backends.)
        assert main(["mark", str(line), "--speed", "1000", "--prr", "50", "--machine",
                     str(machine), "--wobble", "60", "--wobble-along", "20", "--wobble-hz",
                     "5000", "--sim", "--json"]) == 0
    result = json.loads(out.getvalue().strip().splitlines()[-1])
    assert result["errors"] == result["underruns"] == 0
    marks = result["drawing_marks"]                    # the SVG's own mm, Y down: y = 2
    across = [abs(y - 2) for _, y in marks]
    unit_mm = UNIT_UM / 1000
    assert max(across) <= 0.060 + 3 * unit_mm
    assert max(across) >= 0.060 - 3 * unit_mm          # the track's half width is reached
    assert min(x for x, _ in marks) >= 1 - 0.020 - 3 * unit_mm
    assert max(x for x, _ in marks) <= 3 + 0.020 + 3 * unit_mm
    assert sum(1 for a in across if a > 0.030) > len(marks) / 4
