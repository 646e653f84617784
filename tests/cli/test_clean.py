"""`galvoscan clean`: the area planned in user units (checked against sums written here), bad
input refused in one line before any link, and a short run on the simulated board."""

import json
import math

import pytest

from galvoscan.cli import main
from galvoscan.plan.area import plan_area_job
from galvoscan.geometry.field import PlanError
from galvoscan.profile.machine import default_profile

from sim_board import quick_sim_board


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
