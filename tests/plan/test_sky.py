"""SkyWriting planned on the host (galvoscan/plan/sky.py): an L-shaped job in galvo units,
planned as a `.job` at SkyWriting's modes, its segments and registers held to what SCANLAB's
RTC definitions say, worked out here from the job's own geometry and the test-side DDA
(tests/support/vector_model.dda): every run-in and run-out on its mark's line, as many points
as Nprev and Npost take at the mark's speed (whole points, at least as long), the laser off in
them (pixel lines without pixel words); corners taken apart where the mode says (mode 3: on
each side of its limit); the laser delays Timelag (+ LaserOnShift); the time it adds."""

import math

from hypothesis import given, settings as hypothesis_settings, strategies as st
import pytest

from galvoscan.geometry.field import PlanError
from galvoscan.plan.objects import JobSettings
from galvoscan.plan.sky import Sky
from galvoscan.plan.vector_job import plan_job_file
from galvoscan.profile.machine import parse_profile

from vector_model import dda


PROFILE = parse_profile("[galvo]\npolygon_delay_us = 40\njump_length_limit_mm = 0\n")
A, B = (30000, 30000), (33000, 30000)          # the first mark, along +X
SPEED, PRR_KHZ = 1000.0, 50.0


def corner_job(turn_deg):
    """A jump to A, a mark to B, and a mark of the same length turning ``turn_deg`` at B."""
    angle = math.radians(turn_deg)
    c = (round(B[0] + 3000 * math.cos(angle)), round(B[1] + 3000 * math.sin(angle)))
    return [("jump", *A), ("mark", *B), ("mark", *c)], c


def planned(segments, sky):
    return plan_job_file(segments, JobSettings(SPEED, 10.0, PRR_KHZ, sky=sky), PROFILE)


def dwell_us(job):
    return job.pitch.pulses_per_point / (job.registers["laser_prr"] * 100.0) * 1e6


def points(start, end, pitch):
    """The points the board steps from ``start`` to ``end`` (the test-side DDA)."""
    return dda(start, end, pitch)


def cross(u, v):
    return u[0] * v[1] - u[1] * v[0]


def test_mode_1_runs_each_mark_in_and_out_on_its_line_with_the_laser_off():
    segments, c = corner_job(90)
    sky = Sky(mode=1, timelag_us=150.0, nprev_us=45.0, npost_us=30.0)
    job = planned(segments, sky)
    pitch = job.pitch.pitch_units
    dwell = dwell_us(job)
    n_in, n_out = math.ceil(45.0 / dwell - 1e-9), math.ceil(30.0 / dwell - 1e-9)
    ops = [op for op, *_ in job.segments]
    # A jump to the run-in's start, the run-in (a pixel line with no pixel words: dark), the
    # two marks, the run-out; then the jump that ends the job.
    assert ops[:5] == ["jump", "line", "mark", "mark", "line"], job.segments
    assert job.segments[2][1:] == B and job.segments[3][1:] == c
    begin, before, out = job.segments[0][1:], job.segments[1][1:], job.segments[4][1:]
    # The run-in lies on the first mark's line, behind A; it ends a pitch short of A, so that
    # the mark steps onto A (lit) first.
    assert begin[1] == before[1] == A[1] and begin[0] < before[0] < A[0]
    assert points(before, B, pitch)[0] == A
    assert len(points(begin, before, pitch)) == n_in
    # The run-out goes on along the last mark's direction, Npost's points.
    direction = (c[0] - B[0], c[1] - B[1])
    assert abs(cross(direction, (out[0] - c[0], out[1] - c[1]))) < 1e-6 * 3000 * 3000
    assert (out[0] - c[0]) * direction[0] + (out[1] - c[1]) * direction[1] > 0
    assert len(points(c, out, pitch)) == n_out
    # RTC: laser and polygon delays are not used; the laser switches Timelag after the set
    # point crosses the ends. The laser is off before the jump after the run-out.
    regs = job.registers
    assert (regs["laser_on_delay"], regs["laser_off_delay"]) == (150, 150)
    assert regs["polygon_delay"] == 0 and regs["polygon_scaled"] == 1
    assert n_out * dwell + regs["mark_delay"] >= 150 + 10
    # What it adds: the runs' points and the point a pitch before A.
    assert job.sky_s == pytest.approx((n_in + n_out + 1) * dwell * 1e-6, abs=1e-12)
    assert job.estimate_s == pytest.approx(planned(segments, None).estimate_s + job.sky_s)


def test_laser_on_shift_moves_laser_on_only():
    segments, _ = corner_job(90)
    regs = planned(segments, Sky(mode=1, timelag_us=150.0, laser_on_shift_us=-20.0)).registers
    assert (regs["laser_on_delay"], regs["laser_off_delay"]) == (130, 150)


def test_default_runs_are_rtcs_shares_of_timelag():
    segments, _ = corner_job(90)
    job = planned(segments, Sky(mode=1, timelag_us=200.0))
    dwell = dwell_us(job)
    pitch = job.pitch.pitch_units
    begin, before = job.segments[0][1:], job.segments[1][1:]
    assert len(points(begin, before, pitch)) == math.ceil(0.15 * 200 / dwell - 1e-9)


def test_mode_2_takes_the_corner_apart_into_run_out_jump_run_in():
    segments, c = corner_job(90)
    sky = Sky(mode=2, timelag_us=150.0, nprev_us=45.0, npost_us=30.0)
    job = planned(segments, sky)
    one = planned(segments, Sky(mode=1, timelag_us=150.0, nprev_us=45.0, npost_us=30.0))
    ops = [op for op, *_ in job.segments]
    assert ops[:8] == ["jump", "line", "mark", "line", "jump", "line", "mark", "line"]
    # The run-out at B goes on along +X; the run-in of the second mark comes along B → C.
    assert job.segments[3][2] == B[1] and job.segments[3][1] > B[0]
    begin, before = job.segments[4][1:], job.segments[5][1:]
    assert begin[0] == before[0] == B[0] and begin[1] < before[1]
    # The run-in ends on the corner, which the first mark marked (lit once).
    assert before == B
    # Mode 2 adds a second set of runs and the jump (its frame and its delay).
    dwell = dwell_us(job)
    n_in, n_out = math.ceil(45.0 / dwell - 1e-9), math.ceil(30.0 / dwell - 1e-9)
    jump_s = (1 + math.ceil(job.registers["jump_delay"] / 10 - 1e-9)) * 10e-6
    assert job.sky_s == pytest.approx(one.sky_s + (n_in + n_out) * dwell * 1e-6 + jump_s,
                                      abs=1e-12)


@pytest.mark.parametrize("turn, limit, split", [
    (30, 0.5, False), (59, 0.5, False), (61, 0.5, True), (90, 0.5, True), (150, 0.5, True),
    (89, 0.0, False), (91, 0.0, True), (150, -0.9, False), (160, -0.9, True)])
def test_mode_3_takes_apart_only_corners_whose_cosine_is_below_the_limit(turn, limit, split):
    segments, _ = corner_job(turn)
    job = planned(segments, Sky(mode=3, timelag_us=100.0, limit=limit))
    jumps = sum(1 for op, *_ in job.segments[:-1] if op == "jump")
    assert jumps == (2 if split else 1), (math.cos(math.radians(turn)), limit)
    # The corners kept get the polygon delay (held as the host sends it with each corner).
    assert job.registers["polygon_delay"] == 40 and job.registers["polygon_scaled"] == 1


def test_mode_0_changes_nothing():
    segments, _ = corner_job(90)
    assert planned(segments, Sky(mode=0, timelag_us=100.0)).segments == \
        planned(segments, None).segments


def test_a_tracking_delay_longer_than_any_timelag_refuses_only_skywriting():
    """[galvo] tracking_delay_us may be up to 2 ms; Timelag (laser_off_delay) up to 1023 µs:
    a job without SkyWriting plans, one with it is refused in one line."""
    from galvoscan import api
    from galvoscan.geometry.drawing import Drawing
    from galvoscan.geometry.field import Placement
    from galvoscan.plan.objects import MarkObject
    import numpy as np
    profile = parse_profile("[galvo]\ntracking_delay_us = 1500\n")
    path = np.array([(0.0, 0.0), (2.0, 0.0)])
    for mode in (0, 1):
        job = api.Job(sky_mode=mode)
        try:
            settings = api.job_settings(job, profile)
        except PlanError as error:
            assert mode == 1 and "timelag must be from 0 to 1023, not 1500" in str(error)
            continue
        assert mode == 0
        made = MarkObject(Drawing("line", (path,), (False,)), Placement(), settings)
        assert api.plan_made([made], job, profile).vector_job.sky_s == 0


def test_a_run_in_past_the_fields_edge_is_refused():
    segments = [("jump", 20, 30000), ("mark", 3000, 30000)]
    with pytest.raises(PlanError, match="SkyWriting: the run-in .* past the field's edge"):
        planned(segments, Sky(mode=1, timelag_us=100.0, nprev_us=500.0))


@pytest.mark.parametrize("values, said", [
    (dict(mode=4), "--sky must be from 0 to 3"),
    (dict(mode=1, timelag_us=-5.0), "timelag must be from 0 to 1023"),
    (dict(mode=1, timelag_us=20.0, laser_on_shift_us=-30.0), "is -10 µs: laser-on must come"),
    (dict(mode=1, nprev_us=-1.0), "nprev must be from 0"),
    (dict(mode=1, limit=1.5), "sky limit must be from -1 to 1")])
def test_bad_values_are_refused_in_one_line(values, said):
    with pytest.raises(PlanError, match=said) as raised:
        Sky(**values)
    assert "\n" not in str(raised.value)


@hypothesis_settings(max_examples=60, deadline=None)
@given(mode=st.one_of(st.integers(-5, 8), st.floats(allow_nan=True), st.text(max_size=3)),
       timelag=st.floats(-2000, 3000, allow_nan=False),
       shift=st.floats(-2000, 2000, allow_nan=False),
       nprev=st.one_of(st.none(), st.floats(-100, 20000, allow_nan=False)))
def test_any_sky_is_taken_or_refused_in_one_line(mode, timelag, shift, nprev):
    """Whatever a program gives: a Sky whose registers are in range, or one line."""
    try:
        sky = Sky(mode=mode, timelag_us=timelag, laser_on_shift_us=shift, nprev_us=nprev)
    except PlanError as error:
        assert str(error).startswith("SkyWriting") and "\n" not in str(error)
        return
    assert mode in (0, 1, 2, 3)
    if mode:
        assert 0 <= timelag <= 1023
        assert 0 <= sky.laser_on_delay <= 1023 and 0 <= sky.laser_off_delay <= 1023


def test_a_programs_layer_is_held_to_the_sky_settings():
    from galvoscan.plan.layer_keys import check_layer, layer_from_pairs
    from galvoscan.plan.layers import Layer
    with pytest.raises(ValueError, match=r"layer 1: sky: --sky must be from 0 to 3, not 7"):
        check_layer(Layer("#000000", sky_mode=7), "layer 1")
    layer = layer_from_pairs("#000000", [("sky", "3"), ("sky_limit", "0.2"), ("timelag", "90")],
                             "--layer")
    base = JobSettings(SPEED, 10.0, PRR_KHZ, sky=Sky(mode=0, timelag_us=80.0))
    assert layer.settings(base).sky == Sky(mode=3, timelag_us=90.0, limit=0.2)
    with pytest.raises(ValueError, match="--layer: timelag: timelag must be from 0 to 1023"):
        layer_from_pairs("#000000", [("timelag", "5000")], "--layer")


def test_the_settings_pages_sky_table_is_the_declarations():
    from pathlib import Path
    from galvoscan.settings.schema import markdown_table
    from galvoscan.settings.sky import SKY_SETTINGS
    page = (Path(__file__).parents[2] / "docs" / "reference" / "settings.md").read_text(
        encoding="utf-8")
    assert markdown_table(SKY_SETTINGS) in page


@pytest.mark.parametrize("given, flag", [(dict(timelag_us=100), "--timelag"),
                                         (dict(laser_on_shift_us=-5), "--laser-on-shift"),
                                         (dict(nprev_us=20), "--nprev"),
                                         (dict(npost_us=20), "--npost"),
                                         (dict(limit=0.2), "--sky-limit")])
def test_a_sky_setting_without_skywriting_is_refused_not_ignored(given, flag):
    from galvoscan.plan.sky import job_sky
    profile = parse_profile("")
    with pytest.raises(PlanError, match=f"^{flag} is SkyWriting's: give --sky 1, 2 or 3 too"):
        job_sky(profile, **given)
    with pytest.raises(PlanError):
        job_sky(profile, mode=0, **given)
    assert job_sky(profile, mode=1, **given).on
