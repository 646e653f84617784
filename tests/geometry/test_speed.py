"""Speed and time (galvoscan/geometry/speed.py): the pitch and pulses per point for a speed,
against a brute force over every choice, and the time and lengths of segments, against sums
worked out by hand."""

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings, strategies as st

from galvoscan.geometry.field import PlanError
from galvoscan.geometry.speed import (Pitch, choose_pitch, estimate_seconds, jump_mark_lengths,
                                      settled_jumps)


def brute_force(speed, prr, units_per_mm, max_pitch_mm, max_point_hz=100e3):
    """Every (pitch, N): the least relative error and the choices that reach it."""
    top = min(65535, math.floor(max_pitch_mm * units_per_mm + 1e-9))
    pitch, n = np.meshgrid(np.arange(1, top + 1), np.arange(1, 256))
    allowed = prr / n <= max_point_hz * (1 + 1e-12)
    v = pitch / units_per_mm * prr / n
    error = np.where(allowed, np.abs(v - speed) / speed, np.inf)
    return error.min()


def test_choose_pitch_example():
    pitch = choose_pitch(1000, 100e3, 65536 / 110, max_pitch_mm=0.05)
    assert isinstance(pitch, Pitch)
    assert (pitch.pitch_units, pitch.pulses_per_point) == (6, 1)    # 6 units/N equal ties: N=1
    assert pitch.speed_mm_s == pytest.approx(6 * 110 / 65536 * 100e3)
    assert pitch.pitch_mm == pytest.approx(6 * 110 / 65536)


@settings(max_examples=150, deadline=None)
@given(speed=st.floats(1, 20000), prr_khz=st.floats(1, 1000), field_mm=st.floats(50, 400),
       max_pitch_mm=st.floats(0.001, 0.5))
def test_choose_pitch_against_brute_force(speed, prr_khz, field_mm, max_pitch_mm):
    prr, units_per_mm = prr_khz * 1e3, 65536 / field_mm
    assume(max_pitch_mm * units_per_mm >= 1)
    assume(prr / 255 <= 100e3)
    best = brute_force(speed, prr, units_per_mm, max_pitch_mm)
    try:
        pitch = choose_pitch(speed, prr, units_per_mm, max_pitch_mm=max_pitch_mm)
    except PlanError as error:
        assert best > 0.02 - 1e-12
        assert "mm/s" in str(error) and "\n" not in str(error)
        return
    v = pitch.pitch_units / units_per_mm * prr / pitch.pulses_per_point
    assert v == pytest.approx(pitch.speed_mm_s, rel=1e-12)
    assert abs(v - speed) / speed <= 0.02
    assert abs(v - speed) / speed == pytest.approx(best, rel=1e-9, abs=1e-12)
    assert pitch.error == pytest.approx((v - speed) / speed, rel=1e-9, abs=1e-15)
    assert 1 <= pitch.pitch_units and pitch.pitch_units / units_per_mm <= max_pitch_mm + 1e-12
    assert 1 <= pitch.pulses_per_point <= 255
    assert prr / pitch.pulses_per_point <= 100e3 * (1 + 1e-12)


@pytest.mark.parametrize("strict", [True, "range"])
@pytest.mark.parametrize("speed", [1e6, 0.01])
def test_choose_pitch_refuses_out_of_range(speed, strict):
    with pytest.raises(PlanError, match=r"out of reach at 100 kHz: .* mm/s"):
        choose_pitch(speed, 100e3, 65536 / 110, max_pitch_mm=0.05, strict=strict)


def test_a_speed_between_two_is_refused_or_the_nearest():
    """300 mm/s at 50 kHz on a 110 mm field lies between 293.7 (7 units, 2 pulses) and 307.7
    mm/s (11 units, 3 pulses), each over 2 % off: strict refuses naming both; "range" takes
    the nearer (mark then says so)."""
    units_per_mm = 65536 / 110
    with pytest.raises(PlanError, match=r"falls between .*: 293.7 or 307.7 mm/s"):
        choose_pitch(300, 50e3, units_per_mm, max_pitch_mm=0.025)
    pitch = choose_pitch(300, 50e3, units_per_mm, max_pitch_mm=0.025, strict="range")
    assert (pitch.pitch_units, pitch.pulses_per_point) == (7, 2)
    assert pitch.speed_mm_s == pytest.approx(7 / units_per_mm * 50e3 / 2)


def test_choose_pitch_respects_the_point_rate():
    pitch = choose_pitch(1000, 1e6, 65536 / 110, max_pitch_mm=0.1)
    assert pitch.pulses_per_point >= 10      # 1 MHz / 100 kHz of points


# --- time and lengths ---------------------------------------------------------------------------

SEGMENTS = [("jump", 32768 + 300, 32768), ("mark", 32768 + 300, 32768 + 400),
            ("mark", 32768, 32768 + 400), ("mark", 32768, 32768 + 405),
            ("jump", 32768, 32768)]


def test_estimate_by_hand():
    # Marks 400, 300, 5 units at pitch 10: 40 + 30 + 1 points, 3 pulses at 30 kHz = 100 µs
    # each; jumps 2 × (1 + 4) frames of 10 µs (a 35 µs delay is rounded up to 4 frames).
    seconds = estimate_seconds(SEGMENTS, pitch_units=10, pulses_per_point=3, prr_hz=30e3,
                               jump_delay_us=35)
    assert seconds == pytest.approx(71 * 100e-6 + 10 * 10e-6)


def test_jump_mark_lengths_by_hand():
    mark_mm, jump_mm = jump_mark_lengths(SEGMENTS, 10)
    assert mark_mm == pytest.approx(70.5)
    assert jump_mm == pytest.approx(30 + 40.5)


# --- each jump held as long as its length needs -----------------------------------------------

def test_each_jump_is_held_as_long_as_rtcs_variable_jump_delay_needs():
    """Jumps of several lengths under the default profile's variable jump delay (240 µs for a
    jump of 0, 500 µs from 5 mm): each, with the jumps to the same point that follow it, waits
    at least 240 µs + 52 µs a mm up to 5 mm, 500 beyond; the first, from wherever the head
    was, as long as a jump across the field (500 µs)."""
    from galvoscan.profile.machine import default_profile
    profile = default_profile()
    units_per_mm = profile.units_per_mm
    lengths_mm = [0.05, 0.05, 0.3, 1.0, 2.5, 4.9, 5.0, 12.0, 0.1, 40.0, 0.05]
    segments, x = [], 32768.0
    for length in lengths_mm:
        x += length * units_per_mm
        segments += [("jump", round(x), 32768), ("mark", round(x) + 30, 32768)]
        x = round(x) + 30
    settled, delay, extra, longest = settled_jumps(segments, profile, units_per_mm)
    assert longest == 500
    assert len(settled) == len(segments) + extra
    holds = []                                   # each jump and the repeats that follow it
    for segment, previous in zip(settled, [None] + settled[:-1]):
        if segment[0] == "jump":
            if segment == previous:
                holds[-1] += 1
            else:
                holds.append(1)
    assert len(holds) == len(lengths_mm)
    for number, (length, count) in enumerate(zip(lengths_mm, holds)):
        need = 500 if number == 0 or length >= 5 else 240 + (500 - 240) * length / 5
        assert count * delay >= need - 1, (length, count, delay)      # whole µs, rounded up
    # Quicker than every jump held as long as the longest: the short ones wait less.
    assert sum(holds) * (math.ceil(delay / 10) + 1) < len(holds) * (50 + 1)


def test_jumps_held_once_wait_as_long_as_a_jump_across_the_field():
    """Held once each (a .job's, ``settle=False``), every jump waits what the first, from
    wherever the head was, may need: a jump corner to corner, 500 µs, though the job's own
    are short."""
    from galvoscan.profile.machine import default_profile
    profile = default_profile()
    segments = [("jump", 32768 + 100, 32768), ("mark", 32768 + 200, 32768),
                ("jump", 32768 + 300, 32768), ("mark", 32768 + 400, 32768)]
    settled, delay, extra, longest = settled_jumps(segments, profile, profile.units_per_mm,
                                                   settle=False)
    assert (settled, delay, extra, longest) == (segments, 500, 0, 500)
