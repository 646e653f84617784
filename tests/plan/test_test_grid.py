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
from galvoscan.geometry.field import PlanError
from galvoscan.plan.test_grid import grid_pitches, plan_test_grid
from galvoscan.profile.machine import default_profile
from galvoscan.settings.laser import SPEED

from sim_board import VECTOR_BOARD, quick_sim_board


def test_the_grid_and_its_settings():
    """Columns are speeds, rows powers (the highest at the top), centred; each square is
    planned at its own speed (the nearest the machine makes: within a pitch unit's step)
    and power."""
    profile = default_profile()
    grid = plan_test_grid([200, 600, 1000], [20, 80], profile, prr_khz=50, cell_mm=5,
                          gap_mm=2)
    cells, labels = grid.cells, grid.labels
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


def _speeds_made(speeds, prr_hz, units_per_mm, top_units, pulses):
    """An independent model of the machine's speeds: at ``pulses`` per point, each asked
    speed's nearest of ``pitch × PRR / pulses`` over every whole pitch 1 … ``top_units``."""
    made = [p / units_per_mm * prr_hz / pulses for p in range(1, top_units + 1)]
    return [min(made, key=lambda v: abs(v - asked)) for asked in speeds]


def _worst_error(speeds, made):
    return max(abs(v - asked) / asked for asked, v in zip(speeds, made))


@pytest.mark.parametrize("speeds", [[200, 400, 600, 800, 1000], [200, 275, 350, 425, 500],
                                    [50, 60, 70], [300]])
def test_one_pulses_per_point_across_the_columns(speeds):
    """Every square at one number of pulses per point, the one whose worst column is nearest
    its asked speed (brute force over every number and pitch); each square's registers make
    its column's speed, ``pitch × PRR / N``; each label says that speed; a note names each
    column more than 2 % off, and no other."""
    profile = default_profile()
    grid = plan_test_grid(speeds, [20, 60], profile, prr_khz=50, cell_mm=1, gap_mm=1,
                          label_height_mm=0.5)
    units_per_mm, prr_hz = profile.units_per_mm, 50e3
    top = int(profile.laser.spot_mm / 2 * units_per_mm + 1e-9)
    n = grid.pulses_per_point
    assert {c.job.registers["pulses_per_point"] for c in grid.cells} == {n}
    # The best worst error of any one number of pulses, reachable or not.
    fastest = top / units_per_mm * prr_hz
    best = min(_worst_error(speeds, _speeds_made(speeds, prr_hz, units_per_mm, top, k))
               for k in range(1, 256) if fastest / k >= max(speeds) * 0.98)
    made = _speeds_made(speeds, prr_hz, units_per_mm, top, n)
    assert _worst_error(speeds, made) == pytest.approx(best, abs=1e-12)
    for c in grid.cells:
        regs = c.job.registers
        speed = regs["pitch"] / units_per_mm * regs["laser_prr"] * 100 / regs["pulses_per_point"]
        assert c.speed_mm_s == pytest.approx(speed, rel=1e-12)
    assert [c.speed_mm_s for c in grid.cells[:len(speeds)]] == pytest.approx(made, rel=1e-12)
    assert grid.column_labels == [f"{v:.0f}" for v in made]
    off = [k for k, (asked, v) in enumerate(zip(speeds, made), 1)
           if abs(v - asked) / asked > 0.02]
    assert len(grid.notes) == len(off)
    for k, note in zip(off, grid.notes):
        assert note.startswith(f"column {k} makes {made[k - 1]:.0f} mm/s, not the "
                               f"{speeds[k - 1]:g} asked")


def test_the_asked_columns_of_the_trial():
    """The trial's 200:1000:5 at 50 kHz: 5, 3, 1, 1 and 1 pulses per point before; now one
    number for all, and 800 mm/s, which cannot be made, is said in a note and labelled as
    made."""
    profile = default_profile()
    grid = plan_test_grid([200, 400, 600, 800, 1000], [20], profile, prr_khz=50)
    assert len({c.job.pitch.pulses_per_point for c in grid.cells}) == 1
    made = round(grid.cells[3].speed_mm_s)
    assert made != 800 and grid.column_labels[3] == str(made)
    assert any(note.startswith(f"column 4 makes {made} mm/s, not the 800 asked")
               for note in grid.notes)


@pytest.mark.parametrize("pulses", [1, 2, 3])
def test_pulses_per_point_given(pulses, capsys):
    """``--pulses-per-point N``: every square at N, each speed the nearest at N."""
    assert main(["test-grid", "--speeds", "100:300:3", "--powers", "30", "--estimate",
                 "--json", "--pulses-per-point", str(pulses)]) == 0
    record = json.loads(capsys.readouterr().out)
    profile = default_profile()
    top = int(profile.laser.spot_mm / 2 * profile.units_per_mm + 1e-9)
    made = _speeds_made([100, 200, 300], 50e3, profile.units_per_mm, top, pulses)
    assert record["pulses_per_point"] == pulses
    assert [c["speed_mm_s"] for c in record["cells"]] == pytest.approx(made, abs=0.01)
    assert len(record["notes"]) == sum(abs(v - a) / a > 0.02 for a, v in
                                       zip([100, 200, 300], made))


@pytest.mark.parametrize("argv, words", [
    (["--pulses-per-point", "0"], "pulses per point must be from 1 to 255"),
    (["--pulses-per-point", "256"], "pulses per point must be from 1 to 255"),
    (["--pulses-per-point", "x"], "pulses per point must be"),
    # 1000 mm/s needs a pitch past half the spot at 3 pulses a point.
    (["--pulses-per-point", "3"], "1000 mm/s is out of reach at 50 kHz"),
])
def test_bad_pulses_per_point_are_one_line(argv, words, capsys):
    with pytest.raises(SystemExit) as stop:
        main(["test-grid", "--speeds", "200:1000:2", "--powers", "20", *argv, "--estimate"])
    message = str(stop.value) + capsys.readouterr().err
    assert stop.value.code == 2
    assert words in message and "Traceback" not in message and message.count("\n") <= 2


@pytest.mark.parametrize("argv, words", [
    (["--speeds", "100:200", "--powers", "10"], "A:B:N"),
    (["--speeds", "100:200:0", "--powers", "10"], "N from 1 to 100"),
    (["--speeds", "100:200:30", "--powers", "1:90:30"], "400 at most"),
    (["--speeds", "100", "--powers", "120"], "--powers must be from 0 to 100 %"),
    (["--speeds", "100", "--powers", "10", "--preview", "g.bmp"], ".png"),
    # A speed past what the machine makes is refused, not replaced by the fastest.
    (["--speeds", "200:5000:3", "--powers", "20"], "2600 mm/s is out of reach at 50 kHz"),
    # 50 mm/s needs 2 pulses a point or more, 1000 mm/s 1 at most: no one number for both.
    (["--speeds", "50:1000:2", "--powers", "20"], "no one number of pulses per point"),
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



@settings(max_examples=60, deadline=None)
@given(speeds=st.lists(st.floats(0.1, 20_000), min_size=1, max_size=6),
       pulses=st.one_of(st.none(), st.integers(-2, 300)),
       prr_khz=st.sampled_from([20, 50, 100, 150, 200]))
def test_random_speeds_share_one_pulses_per_point_or_are_one_line(speeds, pulses, prr_khz):
    """Any speeds, any pulses per point (or none given), any PRR: every column at one number
    of pulses per point (the one given), each speed ``pitch × PRR / N`` and the nearest a
    whole pitch makes at N; or one line (PlanError)."""
    profile = default_profile()
    units_per_mm, prr_hz = profile.units_per_mm, prr_khz * 1e3
    top = int(profile.laser.spot_mm / 2 * units_per_mm + 1e-9)
    try:
        pitches = grid_pitches(speeds, prr_hz, units_per_mm,
                               max_pitch_mm=profile.laser.spot_mm / 2, pulses_per_point=pulses)
    except PlanError as error:
        assert str(error) and "\n" not in str(error)
        return
    n = pitches[0].pulses_per_point
    assert {p.pulses_per_point for p in pitches} == {n} and prr_hz / n <= 100e3
    assert pulses is None or n == pulses
    made = _speeds_made(speeds, prr_hz, units_per_mm, top, n)
    for p, v in zip(pitches, made):
        assert p.speed_mm_s == pytest.approx(p.pitch_units / units_per_mm * prr_hz / n)
        assert p.speed_mm_s == pytest.approx(v, rel=1e-9)
