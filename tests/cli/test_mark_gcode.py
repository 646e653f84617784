"""`galvoscan mark FILE.gcode`: G-code as a drawing, each distinct S and F a layer at that
speed and power, planned with ``--estimate`` (no board); a damaged line refused in one line,
exit status 2; ``--s-max`` through the command line and a job file. The files are
tests/data/gcode/'s (see its README)."""

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
