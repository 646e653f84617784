"""Scan analysis (issue 5): the galvo model, dose maps and metrics on patterns whose answer is
known, the spiral model against the tests' own, and ``galvoscan analyze``."""

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from galvoscan.analysis.dose import Laser, Region, pulses_along
from galvoscan.analysis.galvo import FRAME_PERIOD, GalvoModel
from galvoscan.analysis.patterns import (Frames, ScanHead, raster_frames, spiral_amplitude,
                                         spiral_frames)
from galvoscan.analysis.scan import analyse
from galvoscan.analysis.study import Setup, run_spiral
from galvoscan.cli import main
from galvoscan.cli.args import field_mm as _field
from galvoscan.gateware.sources.spiral_table import SpiralTable

from spiral_model import spiral_frames as model_frames, spiral_points


HEAD = ScanHead(110.0)
CENTRE_MM = float(HEAD.mm(32768))


def settle_time(samples, dt, target, band):
    """Time after which the samples stay within band × |target| of target (the tests' own)."""
    last_out = 0
    for n, value in enumerate(samples):
        if abs(value - target) > band * abs(target):
            last_out = n + 1
    return last_out * dt


# --- galvo model -----------------------------------------------------------------------------

def test_galvo_model_reproduces_the_001_step_times():
    galvo = GalvoModel.from_step_times()
    for share, expected in ((0.01, 0.3e-3), (0.10, 0.7e-3)):
        step = share * 65536
        frames = np.full(300, step)
        path = galvo.follow(frames, np.zeros(300), start=(0.0, 0.0))
        assert settle_time(path.x, path.dt, step, 0.01) == pytest.approx(expected, abs=3e-6)
    # A big step is speed-limited: its middle crosses at the top speed.
    path = galvo.follow(np.full(600, 30000.0), np.zeros(600), start=(0.0, 0.0))
    assert np.max(np.diff(path.x)) / path.dt <= galvo.v_max * 1.0001
    assert np.max(np.diff(path.x)) / path.dt > 0.99 * galvo.v_max


def test_galvo_model_follows_a_slow_sine_as_a_second_order_lag():
    """Below the speed limit the mirror is a linear critically damped system: gain
    1 / (1 + (ω/ωn)²), phase lag 2·atan(ω/ωn) (here ω = 0.13 ωn)."""
    galvo = GalvoModel.from_step_times()
    frequency = 500.0
    t = np.arange(4000) * FRAME_PERIOD
    # Small enough that the speed limit never acts (3 units a frame, 6 per half microsecond).
    command = 32768 + 100 * np.sin(2 * np.pi * frequency * t)
    path = galvo.follow(command, np.full(len(t), 32768.0), start=(32768.0, 32768.0))
    # Fit the settled second half with sin and cos at the frame starts (sample k·substeps).
    substeps = round(FRAME_PERIOD / path.dt)
    x = path.x[:-1:substeps][2000:] - 32768
    # The command of frame k is held for the whole frame: a zero-order hold, which delays by
    # half a frame.
    phase = 2 * np.pi * frequency * (t[2000:] - FRAME_PERIOD / 2)
    a, b = np.linalg.lstsq(np.column_stack([np.sin(phase), np.cos(phase)]), x, rcond=None)[0]
    ratio = frequency * 2 * np.pi / galvo.omega_n
    assert math.hypot(a, b) / 100 == pytest.approx(1 / (1 + ratio ** 2), rel=2e-3)
    assert -math.atan2(b, a) == pytest.approx(2 * math.atan(ratio), abs=2e-3)


def test_ideal_galvo_is_exactly_where_it_is_told():
    rng = np.random.default_rng(1)
    frames = rng.integers(0, 65536, size=(2, 50))
    path = GalvoModel.ideal().follow(*frames, substeps=4)
    assert np.array_equal(path.x[:-1:4], frames[0])
    assert np.array_equal(path.y[3::4], frames[1])


def test_rate_limit_alone_gives_a_ramp():
    galvo = GalvoModel(omega_n=math.inf, v_max=1e6)          # 10 units per frame
    path = galvo.follow([100.0] * 20, [0.0] * 20, substeps=2, start=(0.0, 0.0))
    # Sampled mid-way through each half frame: 2.5, 7.5, 12.5 … units, then the target.
    assert path.x[:22] == pytest.approx([2.5 + 5 * n for n in range(20)] + [100, 100])


@pytest.mark.parametrize("kwargs", [{"omega_n": 0, "v_max": 1}, {"omega_n": 1, "v_max": -1},
                                    {"omega_n": float("nan"), "v_max": 1}])
def test_galvo_model_rejects_bad_parameters(kwargs):
    with pytest.raises(ValueError, match="must be a positive number"):
        GalvoModel(**kwargs)


# --- dose and metrics on known patterns ------------------------------------------------------

def run(frames, region, *, laser=None, periodic=False, **kwargs):
    return analyse(frames, head=HEAD, laser=laser or Laser(), galvo=GalvoModel.ideal(),
                   region=region, periodic=periodic, **kwargs)


def test_single_point():
    """N pulses on one spot: the peak is N times one pulse's peak fluence, all energy is on the
    map, and the spot covers π w² of the field."""
    laser = Laser(power_w=20, prr_hz=100e3, spot_mm=0.2)
    n = 40
    frames = Frames(np.full(n, 32768), np.full(n, 32768))
    # Placed so that the point sits on a cell centre (cells of 0.02 mm, half a cell over).
    region = Region((CENTRE_MM + 0.01, CENTRE_MM + 0.01), (2.0, 2.0))
    result = run(frames, region, laser=laser, periodic=True, cell_mm=0.02)
    dose = result.dose
    assert dose.dose.max() == pytest.approx(n * laser.peak_fluence_j_cm2, rel=1e-3)
    total_j = dose.dose.sum() * (dose.cell / 10) ** 2
    assert total_j == pytest.approx(n * laser.pulse_energy_j, rel=1e-3)
    w = laser.spot_mm / 2
    assert result.metrics["fill"] == pytest.approx(math.pi * w * w / 4.0, rel=0.05)
    assert result.metrics["overlap50"] == result.metrics["fill"]     # all n pulses overlap
    # Repeated, the point is revisited once per pattern, after the pattern less its own pass.
    assert result.intervals == pytest.approx(FRAME_PERIOD * n - (n - 1) / laser.prr_hz)
    assert result.metrics["revisit_median_ms"] == pytest.approx(0.01)


def test_uniform_raster():
    """A dense raster at constant speed doses the inside evenly with P / (v · spacing)."""
    laser = Laser(power_w=30, prr_hz=100e3, spot_mm=0.3)
    step = 10                                 # units per 10 µs frame
    spacing = 20                              # units, a tenth of the spot
    frames = raster_frames(corner=(30000, 30000), size=(3000, 1500), spacing=spacing,
                           step=step)
    region = Region((float(HEAD.mm(31500)), float(HEAD.mm(30750))),
                    (float(HEAD.mm(3000)), float(HEAD.mm(1500))))
    m = run(frames, region, laser=laser).metrics
    speed_cm_s = float(HEAD.mm(step)) / 10 / FRAME_PERIOD
    spacing_cm = float(HEAD.mm(spacing)) / 10
    expected = laser.power_w / (speed_cm_s * spacing_cm)
    result = run(frames, region, laser=laser)
    inner = result.dose.dose[result.dose.inner]
    assert inner.mean() == pytest.approx(expected, rel=0.01)
    assert m["cv_inner"] < 0.01
    assert m["fill"] == 1.0 and m["overlap50"] == 1.0
    # At the border half the spot falls outside: edges get less than the centre.
    assert m["edge_centre"] < 1


def test_pure_sine_doses_by_the_arcsine_law():
    """A sine sweep spends time at x with density 1/(π√(A² − x²)): a third of the pulses lie
    within half the amplitude, and the edges get the most dose."""
    t = np.arange(20000) * FRAME_PERIOD
    amplitude = 6000
    x = np.rint(32768 + amplitude * np.sin(2 * np.pi * 211 * t))
    frames = Frames(x, np.full(len(x), 32768))
    region = Region((CENTRE_MM, CENTRE_MM), (float(HEAD.mm(2 * amplitude)), 0.5))
    result = run(frames, region, laser=Laser(spot_mm=0.1))
    offsets = result.pulses.x - CENTRE_MM
    half_mm = float(HEAD.mm(amplitude)) / 2
    assert np.mean(np.abs(offsets) < half_mm) == pytest.approx(1 / 3, abs=0.01)
    # The dose map carries the same law: a third of the energy within half the amplitude.
    dose = result.dose
    profile = dose.dose.sum(axis=1)
    central = np.abs(dose.x - CENTRE_MM) < half_mm
    assert profile[central].sum() / profile.sum() == pytest.approx(1 / 3, abs=0.01)


@pytest.mark.parametrize("half", [100, 50])
def test_revisit_intervals_of_a_hop_between_two_points(half):
    """The spot hops between two far points every ``half`` frames: each is left alone from its
    last pulse to the first pulse on the next visit, ``half`` frames and one pulse period."""
    x = np.concatenate([np.full(half, 30000), np.full(half, 36000)])
    frames = Frames(x, np.full(len(x), 32768))
    region = Region((CENTRE_MM, CENTRE_MM), (float(HEAD.mm(8000)), 1.0))
    result = run(frames, region, periodic=True)
    assert len(result.intervals) == 2 * 13       # two discs of 13 points (0.05 mm apart)
    away = half * FRAME_PERIOD + 1e-5
    assert result.intervals == pytest.approx(away)
    assert result.metrics["revisit_p5_ms"] == pytest.approx(away * 1e3)
    assert result.metrics["revisit_under_1ms"] == (1.0 if away < 1e-3 else 0.0)


def test_laser_gated_frames_fire_no_pulses():
    frames = Frames(np.full(10, 32768), np.full(10, 32768),
                    laser=[True] * 3 + [False] * 4 + [True] * 3)
    path = GalvoModel.ideal().follow(frames.x, frames.y)
    pulses = pulses_along(path, frames, Laser(prr_hz=100e3), HEAD)
    assert len(pulses) == 6
    assert np.allclose(pulses.t * 1e5, [0.5, 1.5, 2.5, 7.5, 8.5, 9.5])


def test_raster_frames_model():
    frames = raster_frames(corner=(100, 200), size=(25, 20), spacing=10, step=10,
                           turn_gate=1)
    lines = [list(zip(frames.x[frames.points == j], frames.y[frames.points == j]))
             for j in range(3)]
    assert lines[0] == [(100, 200), (110, 200), (120, 200), (125, 200)]     # ends exactly
    assert lines[1] == [(125, 210), (115, 210), (105, 210), (100, 210)]     # serpentine
    assert lines[2][0] == (100, 220)
    assert frames.laser.tolist() == [True] * 4 + [False] + [True] * 3 + [False] + [True] * 3
    one_way = raster_frames(corner=(0, 0), size=(20, 10), spacing=10, step=10,
                            bidirectional=False)
    assert one_way.x.tolist() == [0, 10, 20, 0, 10, 20]


@pytest.mark.parametrize("kwargs, message", [
    ({"spacing": 0}, "spacing must be"), ({"step": -1}, "step must be"),
    ({"size": (70000, 10)}, "within the field"), ({"lines_along": "z"}, "lines_along"),
    ({"turn_gate": -1}, "turn_gate")])
def test_raster_frames_reject_bad_parameters(kwargs, message):
    base = {"corner": (0, 0), "size": (100, 100), "spacing": 10, "step": 10}
    with pytest.raises(ValueError, match=message):
        raster_frames(**{**base, **kwargs})


# --- the spiral model is the gateware's ------------------------------------------------------

@pytest.mark.parametrize("interpolation", ["off", "linear"])
@pytest.mark.parametrize("table, dwell, amp, centre, x_range, y_range", [
    (SpiralTable(), 3, (32768, 32768), (32768, 32768), (0, 127), (1, 126)),
    (SpiralTable(sampling="uniform"), 2, (50000, 16384), (60000, 1000), (10, 20), (3, 40)),
    (SpiralTable(points=64, sigma=0.5), 1, (40000, 65535), (100, 65000), (0, 63), (1, 62)),
    (SpiralTable(sampling="triangle"), 7, (60000, 20000), (30000, 40000), (5, 100), (0, 3)),
    (SpiralTable(points=16), 300, (32768, 32768), (32768, 32768), (0, 15), (1, 14)),
])
def test_spiral_model_equals_the_tests_model(table, dwell, amp, centre, x_range, y_range,
                                             interpolation):
    """The analysis' spiral (numpy) against the tests' plain model, saturation and
    interpolation included; the full replay test checks the same model against the gateware's
    wires."""
    count = 700 if dwell < 10 else 20
    frames = spiral_frames(table, dwell=dwell, amp=amp, centre=centre, x_range=x_range,
                           y_range=y_range, count=count, interpolation=interpolation)
    expected = model_frames(table.x, table.y, count, dwell=dwell,
                            interp=int(interpolation == "linear"), x_range=x_range,
                            y_range=y_range, gain=amp, centre=centre)[2:]
    assert list(zip(frames.x.tolist(), frames.y.tolist())) == expected
    if interpolation == "off":
        assert expected == [p for p in spiral_points(table.x, table.y, count, x_range=x_range,
                                                     y_range=y_range, gain=amp, centre=centre)
                            for _ in range(dwell)]


def test_spiral_model_rejects_a_bad_interpolation():
    with pytest.raises(ValueError, match="interpolation must be one of off, linear"):
        spiral_frames(SpiralTable(), interpolation="cubic")


def test_spiral_amplitude_spans_the_field():
    amp = spiral_amplitude(50.0, HEAD)
    frames = spiral_frames(SpiralTable(), amp=(amp, amp))
    assert float(HEAD.mm(frames.x.max() - frames.x.min())) == pytest.approx(50.0, abs=0.01)
    with pytest.raises(ValueError, match="does not fit"):
        spiral_amplitude(250.0, HEAD)


# --- the paper's claim on the default field --------------------------------------------------

def test_gaussian_default_beats_uniform_sampling_on_the_default_field():
    setup = Setup()
    gaussian = run_spiral(setup)
    uniform = run_spiral(setup, table=SpiralTable(sampling="uniform"), dwell=gaussian.dwell)
    assert gaussian.metrics["cv"] < uniform.metrics["cv"]
    assert gaussian.metrics["cv_1mm"] < uniform.metrics["cv_1mm"] / 3
    # Uniform sampling piles dose on the edges; Gaussian keeps them a little under the centre.
    assert uniform.metrics["edge_centre"] > 3
    assert 0.6 < gaussian.metrics["edge_centre"] < 1


def test_interpolation_smooths_the_mirror_on_the_default_field():
    """Results, "Held points": peak spot speed within 1.2 times the mean (from about 1.7), lower
    peak acceleration, 1 mm blocks no less even."""
    setup = Setup()
    held = run_spiral(setup, interpolation="off").metrics
    linear = run_spiral(setup, interpolation="linear").metrics
    assert held["peak_over_mean"] > 1.6 and linear["peak_over_mean"] <= 1.2
    assert linear["peak_accel_km_s2"] < 0.6 * held["peak_accel_km_s2"]
    assert linear["cv_1mm"] <= held["cv_1mm"]
    assert linear["duration_s"] == held["duration_s"] and linear["dwell"] == held["dwell"]


# --- CLI ---------------------------------------------------------------------------------------

def test_analyze_cli_json(tmp_path, capsys):
    assert main(["analyze", "--field", "10x8", "--quiet", "--json", "--out", str(tmp_path)]) == 0
    report = json.loads(capsys.readouterr().out)
    gaussian, uniform = report["runs"]
    assert gaussian["pattern"].startswith("spiral gaussian")
    assert uniform["pattern"] == "spiral uniform"
    assert gaussian["field_mm"] == [10, 8] and gaussian["dwell"] == uniform["dwell"]
    held, linear = report["interpolation"]
    assert (held["interpolation"], linear["interpolation"]) == ("off", "linear")
    assert linear["peak_over_mean"] < held["peak_over_mean"]
    for name in ("fill.png", "dose.png", "interpolation.png"):
        assert (tmp_path / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert report["figures"] == [str(tmp_path / name)
                                 for name in ("fill.png", "dose.png", "interpolation.png")]


def test_analyze_cli_table(capsys):
    assert main(["analyze", "--field", "6x6", "--quiet", "--no-plots", "--sampling", "uniform",
                 "--ideal-galvo"]) == 0
    out = capsys.readouterr().out
    assert "ideal mirror" in out
    assert "CV, 1 mm blocks" in out and "spiral uniform" in out


@pytest.mark.parametrize("argv, message", [
    (["--field", "0x5"], "field sides must be"),
    (["--field", "abc"], "field must be WIDTHxHEIGHT"),
    (["--spot", "-1"], "spot must be from"),
    (["--field", "200x20"], "must fit the scan head"),
    (["--speed", "nan"], "speed must be from"),
])
def test_analyze_cli_rejects_bad_arguments(argv, message, capsys):
    with pytest.raises(SystemExit) as exit:
        main(["analyze", "--no-plots", "--quiet"] + argv)
    assert exit.value.code != 0
    captured = capsys.readouterr()
    assert message in captured.err + str(exit.value)


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=20))
def test_field_parser_takes_any_text(text):
    import argparse
    try:
        width, height = _field(text)
    except argparse.ArgumentTypeError as error:
        assert "field" in str(error)
    else:
        assert 0.5 <= width <= 2000 and 0.5 <= height <= 2000


# --- the RTC delays on a vector mark (galvoscan/analysis/delays.py) -----------------------------

def test_delays_take_the_burnt_dot_and_the_corner_within_20_percent():
    """Through the JD1403 model at 1 m/s: without delays a burnt dot at the line's start (over
    twice the mid-line dose); with the docs' recommended delays (the defaults) the start,
    the corner and the end within 20 % of it, and the line's ends within a spot of their set
    points."""
    from galvoscan.analysis.delays import NONE, DelaySettings, corner_job_dose
    from galvoscan.profile.machine import default_profile
    without = corner_job_dose(NONE)
    assert without["start"] > 2
    galvo = default_profile().galvo
    recommended = DelaySettings(galvo.laser_on_delay_us, galvo.laser_off_delay_us,
                                galvo.mark_delay_us, galvo.polygon_delay_us)
    with_delays = corner_job_dose(recommended)
    for where in ("start", "corner", "end"):
        assert with_delays[where] <= 1.2, where
    assert abs(with_delays["start_shift_mm"]) < 0.05
    assert abs(with_delays["end_shift_mm"]) < abs(without["end_shift_mm"])
    # A long laser-off delay makes the end dot instead; a polygon delay over-doses the corner.
    assert corner_job_dose(DelaySettings(100, 150, 200, 0))["end"] > 2
    assert corner_job_dose(DelaySettings(100, 50, 100, 30))["corner"] > 1.2


def test_analyze_delays_cli_prints_both_runs(tmp_path, capsys):
    import json
    from galvoscan.cli import main
    assert main(["analyze", "--delays", "--json", "--out", str(tmp_path)]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [row["run"] for row in rows] == ["no delays", "with delays"]
    assert rows[1]["start_peak"] <= 1.2 and rows[1]["corner_peak"] <= 1.2
    assert (tmp_path / "delays.png").stat().st_size > 10_000
