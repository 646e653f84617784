"""`galvoscan clean`: the area planned in user units (checked against sums written here), bad
input refused in one line before any link, and a short run on the simulated board."""

import json
import math

import pytest

from galvoscan.cli import main
from galvoscan.plan.area import plan_area_job
from galvoscan.geometry.field import PlanError
from galvoscan.gateware.sources.spiral_table import SpiralTable
from galvoscan.profile.machine import default_profile

from sim_board import quick_sim_board
from spiral_model import spiral_points


NOPORT = ["--port", "/nonexistent/ttyUSB9"]


def plan(**kwargs):
    settings = dict(area_mm=(10, 8), centre_mm=(5, -3), pattern="spiral", speed_mm_s=2000,
                    power_percent=50, prr_khz=50, profile=default_profile(), passes=2)
    settings.update(kwargs)
    return plan_area_job(**settings)


def test_dose_is_energy_over_area():
    profile = default_profile()
    job = plan(pattern="raster", passes=None, dose_j_cm2=3.0)
    # 50 % is laser_power 128 of 255: the power the laser actually gets.
    watts = profile.laser.max_power_w * 128 / 255
    # 3 J/cm² over 0.8 cm² is 2.4 J: at `watts`, 2.4 / watts seconds.
    assert math.isclose(job.seconds, 3.0 * 0.8 / watts, rel_tol=1e-9)
    assert math.isclose(job.dose_j_cm2, 3.0, rel_tol=1e-9)
    again = plan(pattern="raster", passes=None, duration_s=job.seconds)
    assert math.isclose(again.dose_j_cm2, 3.0, rel_tol=1e-9)


def test_raster_registers_in_galvo_units():
    job = plan(pattern="raster")
    units_per_mm = 65536 / 110
    regs = job.registers
    assert regs["mode"] == 1
    # 2000 mm/s is 0.02 mm per 10 µs frame; half the 0.05 mm spot between lines.
    assert regs["ras_step"] == round(0.02 * units_per_mm)
    assert regs["ras_spacing"] == round(0.025 * units_per_mm)
    assert regs["ras_x"] == 32768 + round(0 * units_per_mm)          # 5 - 10/2 = 0 mm
    assert regs["ras_y"] == 32768 + round(-7 * units_per_mm)         # -3 - 8/2
    assert (regs["ras_w"], regs["ras_h"]) == (round(10 * units_per_mm), round(8 * units_per_mm))
    assert regs["laser_prr"] == 500 and regs["laser_power"] == 128


def test_spiral_speed_is_held_to_the_asked_speed():
    """The dwell is a whole number of frames, the smallest that keeps the axes at or under the
    speed: the speed built is the asked one to within a dwell's rounding, not a fraction."""
    for speed in (100, 500, 1000, 2000, 5000):
        job = plan(speed_mm_s=speed)
        dwell = job.registers["dwell"]
        assert speed * (dwell - 1) / dwell < job.speed_mm_s <= speed * (1 + 1e-9), speed
        assert job.registers["mode"] == 0 and job.registers["dwell"] >= 1
        assert job.registers["center_x"] == 32768 + round(5 * 65536 / 110)


@pytest.mark.parametrize("kwargs, words", [
    (dict(area_mm=(120, 10)), "the field is"),
    (dict(centre_mm=(52, 0)), "the field is"),
    (dict(speed_mm_s=20_000), "max_speed_mm_s"),
    (dict(passes=None), "one of"),
    (dict(passes=1, dose_j_cm2=1), "one of"),
    (dict(pattern="zigzag"), "spiral or raster"),
])
def test_impossible_jobs_are_one_line(kwargs, words):
    with pytest.raises(PlanError, match=words):
        plan(**kwargs)


@pytest.mark.parametrize("args, words", [
    (["--area", "200x10"], "the field is"),
    (["--area", "10x10", "--prr", "300"], "kHz"),
    (["--area", "10x10", "--power", "120"], "power must be from 0 to 100"),
    (["--area", "10x"], "WIDTHxHEIGHT"),
    (["--area", "10x10", "--passes", "2", "--dose", "1"], "not allowed with"),
])
def test_bad_command_lines_are_refused_before_the_link(args, words, capsys):
    with pytest.raises(SystemExit) as stop:
        main(["clean", *args, *NOPORT])
    message = str(stop.value) if stop.value.code not in (1, 2) else \
        capsys.readouterr().err
    assert words in message
    assert "Traceback" not in message and "cannot open" not in message


@pytest.mark.slow
def test_clean_on_the_simulated_board_counts_its_pulses(capsys):
    with quick_sim_board():
        assert main(["clean", "--area", "3x2", "--speed", "2000", "--prr", "50",
                     "--duration", "0.001", "--sim", "--json"]) == 0
    result = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    # 1 ms at 50 kHz is 50 pulses; the host stops once it has counted them.
    assert result["pulses"] >= 50
    assert result["errors"] == 0 and result["frames"] > 100


def test_estimate_json_is_one_object_on_stdout(capsys):
    """``clean --estimate --json``: the plan as one JSON object on stdout, the text on stderr;
    the dose is the energy over the area (2 passes of a 1 cm² square)."""
    assert main(["clean", "--area", "10x10", "--pattern", "raster", "--passes", "2",
                 "--power", "50", "--estimate", "--json"]) == 0
    out, err = capsys.readouterr()
    record = json.loads(out)
    assert "passes" in err
    assert record["pattern"] == "raster" and record["area_mm"] == [10, 10]
    assert record["passes"] == 2 and record["seconds"] == pytest.approx(2 * record["pass_s"])
    assert record["dose_j_cm2"] == pytest.approx(record["power_w"] * record["seconds"] / 1.0,
                                                 rel=1e-3)       # (power_w is rounded)


@pytest.mark.parametrize("how, words", [
    (["--passes", "3"], "3 passes,"),
    (["--dose", "5"], "whole, then the run stops"),
])
def test_the_passes_say_how_the_last_one_ends(how, words, capsys):
    assert main(["clean", "--area", "10x10", *how, "--estimate", "--json"]) == 0
    out, err = capsys.readouterr()
    assert words in err
    record = json.loads(out)
    assert record["whole_passes"] == math.floor(record["passes"] + 1e-9)


def _spiral_fastest_mm_s(registers, field_mm=110):
    """The spiral's fastest axis speed at a point a frame, from its registers, by the plain
    model of the scanner (tests/support/spiral_model.py): the largest step between points
    of a whole pattern (and back to its first), over one 10 µs frame."""
    table = SpiralTable()
    count = math.lcm(table.points, table.points - 2)
    points = spiral_points(table.x, table.y, count + 1, x_range=(0, table.points - 1),
                           y_range=(1, table.points - 2),
                           gain=(registers["amp_x"], registers["amp_y"]),
                           centre=(registers["center_x"], registers["center_y"]))
    step = max(abs(b[axis] - a[axis]) for a, b in zip(points, points[1:]) for axis in (0, 1))
    return step * field_mm / 65536 / 10e-6


@pytest.mark.parametrize("area, speed", [("10x10", 5000), ("10x10", 3000), ("10x10", 1000),
                                         ("10x10", 4250), ("3x2", 2000), ("30x5", 700),
                                         ("1x1", 1700)])
def test_the_spiral_says_the_speed_it_makes(area, speed, capsys):
    """The spiral holds each point a whole number of frames, the fewest that keep the axes at
    or under the speed asked: it cleans at the fastest speed / frames (the model's), and says
    so in a note when that is more than 2 % from the speed asked (mark's rule)."""
    width, height = (float(v) for v in area.split("x"))
    job = plan(area_mm=(width, height), centre_mm=(0, 0), speed_mm_s=speed)
    fastest = _spiral_fastest_mm_s(job.registers)
    frames = next(d for d in range(1, 10_000) if fastest / d <= speed * (1 + 1e-9))
    assert main(["clean", "--area", area, "--speed", str(speed), "--estimate", "--json"]) == 0
    out, err = capsys.readouterr()
    record = json.loads(out)
    made = fastest / frames
    assert job.registers["dwell"] == frames
    assert record["speed_mm_s"] == pytest.approx(made, abs=1e-3)
    off = abs(made - speed) / speed > 0.02
    assert len(record["notes"]) == off
    notes = [line for line in err.splitlines() if line.startswith("note: ")]
    assert len(notes) == off
    if off:
        assert f"{speed:g} mm/s falls between" in notes[0]
        assert f"cleaned at {made:.0f} mm/s" in notes[0]


@pytest.mark.parametrize("speed", [150, 200, 1000, 1100, 2500])
def test_the_raster_says_the_speed_it_makes(speed, capsys):
    """The raster steps whole galvo units a 10 µs frame: the nearest to the speed asked, said
    in a note when more than 2 % off."""
    assert main(["clean", "--area", "10x10", "--pattern", "raster", "--speed", str(speed),
                 "--estimate", "--json"]) == 0
    out, err = capsys.readouterr()
    record = json.loads(out)
    unit_mm_s = 110 / 65536 / 10e-6
    made = round(speed / unit_mm_s) * unit_mm_s
    assert record["speed_mm_s"] == pytest.approx(made, abs=1e-3)
    off = abs(made - speed) / speed > 0.02
    notes = [line for line in err.splitlines() if line.startswith("note: ")]
    assert len(record["notes"]) == len(notes) == off
    if off:
        assert f"cleaned at the nearest, {made:.1f} mm/s" in err


@pytest.mark.parametrize("area, speed", [("1x1", 5000), ("2x2", 9000), ("1x3", 5500)])
def test_a_speed_past_the_spirals_fastest_is_refused(area, speed, capsys):
    """Faster than the spiral goes at a point a frame (by the model), as mark refuses a speed
    out of reach: one line with the fastest, before any link."""
    width, height = (float(v) for v in area.split("x"))
    fastest = _spiral_fastest_mm_s(plan(area_mm=(width, height), centre_mm=(0, 0),
                                        speed_mm_s=100).registers)
    assert speed > fastest * 1.02
    with pytest.raises(SystemExit) as stop:
        main(["clean", "--area", area, "--speed", str(speed), *NOPORT])
    message = capsys.readouterr().err
    assert stop.value.code == 2
    assert f"{speed:g} mm/s is out of reach for the spiral" in message
    assert f"{fastest:.0f} mm/s at most" in message
    assert "Traceback" not in message and "cannot open" not in message
