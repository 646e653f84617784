"""`galvoscan test-grid` (galvoscan/plan/test_grid.py, cli/testgrid.py): a square for each
speed and power, each at its own settings, labelled; planned, refused, and marked on the
simulated board square by square."""

import argparse
import json
import math

import pytest
from hypothesis import given, settings, strategies as st

from galvoscan.cli import main
from galvoscan.cli.testgrid import _axis
from galvoscan.plan.test_grid import plan_test_grid
from galvoscan.profile.machine import default_profile
from galvoscan.settings.laser import SPEED

from sim_board import VECTOR_BOARD, quick_sim_board


def test_the_grid_and_its_settings():
    """Columns are speeds, rows powers (the highest at the top), centred; each square is
    planned at its own speed (the nearest the machine makes: within a pitch unit's step)
    and power."""
    profile = default_profile()
    cells, labels = plan_test_grid([200, 600, 1000], [20, 80], profile, prr_khz=50,
                                   cell_mm=5, gap_mm=2)
    assert len(cells) == 6
    xs = sorted({c.centre_mm[0] for c in cells})
    ys = sorted({c.centre_mm[1] for c in cells})
    assert xs == pytest.approx([-7, 0, 7]) and ys == pytest.approx([-3.5, 3.5])
    for c in cells:
        assert c.job.registers["laser_power"] == profile.power_register(c.power_percent)
        assert c.job.pitch.speed_mm_s == pytest.approx(c.speed_mm_s)
        x0, y0, x1, y1 = c.job.bounds_mm
        assert (x1 - x0, y1 - y0) == pytest.approx((5, 5))
    top = [c for c in cells if c.centre_mm[1] > 0]
    assert {c.power_percent for c in top} == {80}
    # 600 mm/s is between two speeds whole galvo units make at 50 kHz: the nearer is used.
    assert sorted({round(c.speed_mm_s, 1) for c in cells})[1] == pytest.approx(587.5, abs=0.1)
    assert labels.segments and labels.bounds_mm[1] < min(ys) - 2.5


@pytest.mark.parametrize("argv, words", [
    (["--speeds", "100:200", "--powers", "10"], "A:B:N"),
    (["--speeds", "100:200:0", "--powers", "10"], "N from 1 to 100"),
    (["--speeds", "100:200:30", "--powers", "1:90:30"], "400 at most"),
    (["--speeds", "100", "--powers", "120"], "--powers must be from 0 to 100 %"),
    (["--speeds", "100", "--powers", "10", "--preview", "g.bmp"], ".png"),
    # A speed past what the machine makes is refused, not replaced by the fastest.
    (["--speeds", "200:5000:3", "--powers", "20"], "2600 mm/s is out of reach at 50 kHz"),
    # A grid past the field says so as a grid, not as one square's place.
    (["--speeds", "200:1000:10", "--powers", "20:80:10", "--cell", "20"],
     "10 × 10 squares of 20 mm, 2 mm apart, make a grid 218 × 218 mm"),
])
def test_bad_grids_are_one_line(argv, words, capsys):
    with pytest.raises(SystemExit) as stop:
        main(["test-grid", *argv, "--estimate"])
    message = str(stop.value) + capsys.readouterr().err
    assert words in message and "Traceback" not in message


def test_estimate_json(capsys):
    assert main(["test-grid", "--speeds", "300:900:2", "--powers", "30", "--estimate",
                 "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert len(record["cells"]) == 2 and record["estimate_s"] > 0


_numbers = st.one_of(st.floats(allow_nan=True, allow_infinity=True).map(repr),
                     st.integers(-10 ** 6, 10 ** 6).map(str), st.text(max_size=6))


@settings(max_examples=300, deadline=None)
@given(parts=st.lists(_numbers, min_size=1, max_size=4), separator=st.sampled_from(":,; "))
def test_random_axes_parse_or_are_one_line(parts, separator):
    """Any --speeds text: N values from A to B inside the limits, or one line (argparse's
    ArgumentTypeError) saying what is wrong; nothing else escapes."""
    text = separator.join(parts)
    try:
        values = _axis("--speeds", SPEED)(text)
    except argparse.ArgumentTypeError as error:
        assert "\n" not in str(error) and str(error)
        return
    assert 1 <= len(values) <= 100
    assert all(math.isfinite(v) and 0.1 <= v <= 100_000 for v in values)
    assert values == sorted(values) or values == sorted(values, reverse=True)


@settings(max_examples=25, deadline=None)
@given(cell=st.sampled_from(["0.4", "0.5", "3", "100", "101", "x", "-1", "nan"]),
       gap=st.sampled_from(["0", "2", "100", "-1", "inf"]),
       hatch=st.sampled_from([None, "0.001", "0.05", "10", "11", "0"]),
       label=st.sampled_from(["0.3", "1.5", "20", "21"]))
def test_random_grid_options_plan_or_are_one_line(cell, gap, hatch, label):
    """Sizes in and out of range, together (a grid past the field too): it plans, or one
    line and exit status 1 or 2; never a traceback."""
    argv = ["test-grid", "--speeds", "300:900:2", "--powers", "20:60:2", "--cell", cell,
            "--gap", gap, "--label-height", label, "--estimate"]
    if hatch is not None:
        argv += ["--hatch", hatch]
    try:
        assert main(argv) == 0
    except SystemExit as stop:
        assert stop.code not in (0, None)
        assert "\n" not in str(stop)


@pytest.mark.slow
def test_each_square_is_marked_at_its_settings_on_the_board(tmp_path, capsys):
    machine = tmp_path / "machine.toml"
    machine.write_text("[laser]\nspot_mm = 0.2\n[galvo]\njump_delay_us = 100\n")
    with quick_sim_board(**VECTOR_BOARD):
        assert main(["test-grid", "--speeds", "500:1000:2", "--powers", "40", "--cell", "1",
                     "--gap", "1", "--label-height", "0.5", "--prr", "50", "--machine",
                     str(machine), "--sim", "--timeout", "600", "--json"]) == 0
    record = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    slow, fast = record["cells"]
    # The same square at twice the speed: about half the points, so half the pulses.
    assert slow["pulses"] > 0 and fast["pulses"] > 0
    assert 1.6 < slow["pulses"] / fast["pulses"] < 2.4

