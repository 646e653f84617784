"""The wobble analysis (galvoscan/analysis/wobble.py, ``galvoscan analyze --wobble``) on cases
whose answer is known from the spot's Gaussian and the circle's geometry."""

import json
import math

import pytest

from galvoscan.analysis.dose import Laser
from galvoscan.analysis.galvo import GalvoModel
from galvoscan.analysis.patterns import ScanHead
from galvoscan.analysis.wobble import wobble_line
from galvoscan.cli import main


HEAD = ScanHead(110.0)
LASER = Laser(power_w=20, prr_hz=100e3, spot_mm=0.05)
IDEAL = GalvoModel.ideal()


def line(galvo=IDEAL, **kwargs):
    return wobble_line(HEAD, LASER, galvo, **{"speed_mm_s": 50, "along_um": kwargs.get(
        "across_um", 0), **kwargs})


def test_a_plain_line_is_as_wide_as_the_spots_half_maximum():
    metrics, dose, _ = line(across_um=0, hz=1000)
    w = LASER.spot_mm / 2
    fwhm = 2 * w * math.sqrt(math.log(2) / 2)             # of exp(-2 r² / w²)
    assert metrics["width_mm"] == pytest.approx(fwhm, abs=dose.cell)
    assert metrics["centre"] == pytest.approx(1, abs=0.02)
    assert metrics["ripple"] < 0.01


def test_a_wide_circle_reaches_its_amplitude_and_keeps_the_energy():
    plain = line(across_um=0, hz=2000)
    metrics, dose, profile = line(across_um=150, hz=2000)
    # The circle's sides are where it dwells: the track ends within a spot radius past them.
    assert 0.3 <= metrics["width_mm"] <= 0.3 + LASER.spot_mm
    assert metrics["centre"] < 0.6                           # two tramlines
    assert metrics["reach"] == pytest.approx(1, abs=0.02)
    # The same energy a length of line, spread wider.
    assert profile.sum() == pytest.approx(plain[2].sum(), rel=0.02)
    assert metrics["peak_j_cm2"] < plain[0]["peak_j_cm2"] / 3


def test_turns_farther_apart_than_the_spot_ripple_along_the_line():
    sparse = line(across_um=50, hz=500)[0]                  # a turn every 100 µm: 2 spots
    dense = line(across_um=50, hz=4000)[0]                  # every 12.5 µm
    assert sparse["ripple"] > 0.3 and dense["ripple"] < 0.02


def test_a_real_mirror_lags_a_fast_figure():
    galvo = GalvoModel.from_step_times()
    slow = line(galvo, across_um=50, hz=500)[0]
    fast = line(galvo, across_um=50, hz=8000)[0]
    assert slow["reach"] > 0.9 and fast["reach"] < 0.5
    assert fast["width_mm"] < slow["width_mm"]


def test_analyze_wobble_prints_json_and_refuses_a_prr_above_the_frame_rate(capsys, tmp_path):
    assert main(["analyze", "--wobble", "--ideal-galvo", "--no-plots", "--json", "--quiet",
                 "--prr", "50"]) == 0
    result = json.loads(capsys.readouterr().out)
    widths = [m["width_mm"] for m in result["amplitudes"]]
    assert widths == sorted(widths) and widths[0] < widths[-1]
    assert {m["hz"] for m in result["frequencies"]} == {500, 1000, 2000, 4000, 8000}
    with pytest.raises(SystemExit) as stop:
        main(["analyze", "--wobble", "--prr", "200", "--no-plots"])
    assert "at most 100 kHz" in str(stop.value) and "\n" not in str(stop.value)
