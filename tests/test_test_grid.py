"""`galvoscan test-grid` (galvoscan/jobs/test_grid.py, cli/testgrid.py): a square for each
speed and power, each at its own settings, labelled; planned, refused, and marked on the
simulated board square by square."""

import json

import pytest

from galvoscan.cli import main
from galvoscan.jobs.profile import default_profile
from galvoscan.jobs.test_grid import plan_test_grid

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
])
def test_bad_grids_are_one_line(argv, words, capsys):
    with pytest.raises(SystemExit) as stop:
        main(["test-grid", *argv, "--estimate"])
    message = str(stop.value.code) + capsys.readouterr().err
    assert words in message and "Traceback" not in message


def test_estimate_json(capsys):
    assert main(["test-grid", "--speeds", "300:900:2", "--powers", "30", "--estimate",
                 "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert len(record["cells"]) == 2 and record["estimate_s"] > 0


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

