"""`galvoscan mark FILE.gcode`: G-code as a drawing, each distinct S and F a layer at that
speed and power, planned with ``--estimate`` (no board); a damaged line refused in one line,
exit status 2; ``--s-max`` through the command line and a job file; a small file marked on
the simulated board, its points off the wires on its shapes and each layer's speed and power
measured there. The files are tests/data/gcode/'s (see its README)."""

import json
import math
from pathlib import Path

import pytest

from galvoscan.cli import main


DATA = Path(__file__).resolve().parents[1] / "data" / "gcode"


def test_jtech_file_is_one_layer_at_its_feed_and_full_power(capsys):
    """S255 of an S maximum of 255: 100 %; F750.0 mm/min: 12.5 mm/s (the speed the plan makes
    within 1 %: the pitch × PRR / N rule)."""
    assert main(["mark", str(DATA / "jtech_square_triangle.gcode"), "--s-max", "255",
                 "--estimate"]) == 0
    out = capsys.readouterr().out
    assert "layer 1 'S255 F750' (speed 12.5 mm/s, power 100 %)" in out
    assert "140.0 mm marked at 12.5 mm/s" in out          # 4 × 20 + 3 × 20 mm
    assert "S as a share of S255" in out


def test_lasergrbl_raster_is_a_layer_a_power(capsys):
    assert main(["mark", str(DATA / "lasergrbl_raster.nc"), "--estimate"]) == 0
    out = capsys.readouterr().out
    assert "2 layers, each marked as a job of its own" in out
    assert "layer 1 'S300 F1000' (speed 16.6667 mm/s, power 30 %)" in out
    assert "layer 2 'S600 F1000' (speed 16.6667 mm/s, power 60 %)" in out
    assert "(GRBL's $30 by default; --s-max gives the file's)" in out


def test_a_layer_given_for_the_files_changes_it(capsys):
    assert main(["mark", str(DATA / "lasergrbl_raster.nc"), "--layer", "S600 F1000",
                 "passes=2", "--estimate"]) == 0
    out = capsys.readouterr().out
    assert "layer 1 'S600 F1000' (speed 16.6667 mm/s, power 60 %, passes 2)" in out
    assert "layer 2 'S300 F1000'" in out


def test_a_damaged_line_is_refused_in_one_line(tmp_path, capsys):
    path = tmp_path / "bad.gcode"
    path.write_text("G21 G90\nM3 S500 F600\nG1 X10 Y1O\n")
    with pytest.raises(SystemExit) as stop:
        main(["mark", str(path), "--estimate"])
    assert stop.value.code == 2
    message = str(stop.value)
    # (As docs/user/marking.md says it.)
    assert message == f"galvoscan mark: error: {path}: line 3 ('G1 X10 Y1O'): 'O' is not a " \
        f"G-code word (a letter and a number)"


def test_s_max_out_of_range_or_on_an_svg_is_refused(tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:
        main(["mark", str(DATA / "lasergrbl_raster.nc"), "--s-max", "0", "--estimate"])
    assert stop.value.code == 2
    assert "S maximum must be from" in capsys.readouterr().err
    svg = tmp_path / "a.svg"
    svg.write_text('<svg xmlns="http://www.w3.org/2000/svg" width="2mm" height="2mm" '
                   'viewBox="0 0 2 2"><path d="M 0 0 L 1 1" stroke="black"/></svg>')
    with pytest.raises(SystemExit) as stop:
        main(["mark", str(svg), "--s-max", "255", "--estimate"])
    assert stop.value.code == 2 and "an S maximum is for G-code" in str(stop.value)


def test_s_max_is_saved_in_a_job_file(tmp_path, capsys):
    job = tmp_path / "job.toml"
    assert main(["mark", str(DATA / "jtech_square_triangle.gcode"), "--s-max", "255",
                 "--save", str(job), "--estimate"]) == 0
    assert "s_max = 255" in job.read_text()
    capsys.readouterr()
    assert main(["mark", str(job), "--estimate"]) == 0
    assert "(speed 12.5 mm/s, power 100 %)" in capsys.readouterr().out


# A 1 mm square at S800 F60000 (1000 mm/s, 80 %) and a circle of 0.4 mm radius about (2.4, 0)
# at S400 F120000 (2000 mm/s, 40 %): small and fast, so the simulated board marks it in a
# few milliseconds of its time.
SIM_GCODE = """G21 G90
G0 X0 Y0
M4 S800 F60000
G1 X1 Y0
G1 X1 Y1
G1 X0 Y1
G1 X0 Y0
M5
G0 X2 Y0
M3 S400 F120000
G2 X2 Y0 I0.4 J0
M5
"""
# The machine of tests/cli/test_mark.py: a 0.1 mm spot, quick mirrors.
PROFILE = "[laser]\nspot_mm = 0.1\n[galvo]\njump_delay_us = 100\n"
#: One galvo unit of a 110 mm field, the pitch at most half the spot, the chord tolerance.
UNIT_MM, HALF_PITCH_MM, CHORD_MM = 110 / 65536, 0.05, 0.01


def test_gcode_layers_marked_off_the_wires(tmp_path, capsys):
    """On the simulated board: every marked point off the XY2-100 wires lies on the square or
    the circle (in the file's own mm), and each layer is marked at its F and S, as measured
    on the wires."""
    from sim_board import VECTOR_BOARD, quick_sim_board
    path = tmp_path / "part.gcode"
    path.write_text(SIM_GCODE)
    machine = tmp_path / "machine.toml"
    machine.write_text(PROFILE)
    with quick_sim_board(**VECTOR_BOARD):
        assert main(["mark", str(path), "--prr", "50", "--machine", str(machine), "--sim",
                     "--timeout", "600", "--json"]) == 0
    result = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert result["drawing_frame"].startswith("the drawing's own") and result["underruns"] == 0
    reach = HALF_PITCH_MM + CHORD_MM + 2 * UNIT_MM
    for x, y in result["drawing_marks"]:
        on_square = min(abs(x), abs(x - 1), abs(y), abs(y - 1)) <= reach and \
            -reach <= x <= 1 + reach and -reach <= y <= 1 + reach
        on_circle = abs(math.hypot(x - 2.4, y) - 0.4) <= reach
        assert on_square or on_circle, (x, y)
    square, circle = result["layers"]
    assert (square["match"], circle["match"]) == ("S800 F60000", "S400 F120000")
    assert square["speed_mm_s"] == pytest.approx(1000, rel=0.02)
    assert circle["speed_mm_s"] == pytest.approx(2000, rel=0.02)
    assert (square["power_percent"], circle["power_percent"]) == (80, 40)
    # Every point of both: the square's 4 mm and the circle's 2.5 mm at their pitches.
    assert square["points"] >= 4 / (1000 / 50e3) and circle["points"] >= 2.5 / (2000 / 50e3)


# An L: its stem 1 mm up from its corner (0, 0), its foot 0.5 mm to the right: not its own
# mirror image either way, so a flip in X or Y shows.
L_GCODE = """G21 G90
G0 X0 Y1
M4 S800 F60000
G1 X0 Y0
G1 X0.5 Y0
M5
"""


def test_gcode_is_marked_the_right_way_up(tmp_path, capsys):
    """G-code's Y is up (GRBL's, a sender's view): with ``--origin page`` the file's 0,0 is the
    field's centre, and on the simulated board the marks off the wires, in the field (Y up),
    are the L as written: the stem above the corner, the foot to its right."""
    from sim_board import VECTOR_BOARD, quick_sim_board
    path = tmp_path / "l.gcode"
    path.write_text(L_GCODE)
    machine = tmp_path / "machine.toml"
    machine.write_text(PROFILE)
    with quick_sim_board(**VECTOR_BOARD):
        assert main(["mark", str(path), "--origin", "page", "--prr", "50", "--machine",
                     str(machine), "--sim", "--timeout", "600", "--json"]) == 0
    result = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert result["marks_frame"].startswith("field")
    reach = HALF_PITCH_MM + 2 * UNIT_MM
    marks = result["marks"]
    assert len(marks) > 20
    for x, y in marks:
        on_stem = abs(x) <= reach and -reach <= y <= 1 + reach
        on_foot = abs(y) <= reach and -reach <= x <= 0.5 + reach
        assert on_stem or on_foot, (x, y)
    assert min(math.hypot(x, y - 1) for x, y in marks) <= reach          # the stem's top
    assert min(math.hypot(x - 0.5, y) for x, y in marks) <= reach        # the foot's end
