"""The machine profile's derived numbers (``galvoscan/profile/machine.py``): kHz, %, µs and mm
turned into register values by hand-worked examples, out-of-range values refused in one line,
and the profile as JSON and as a frozen, hashable value."""

import json
import math

import pytest

from galvoscan.profile.machine import MachineProfile, default_profile, parse_profile
from galvoscan.profile.template import profile_text


def test_register_conversions_by_hand():
    profile = default_profile()
    assert profile.prr_register(50) == 500
    assert profile.prr_register(20) == 200
    assert profile.prr_register(200) == 2000
    assert profile.prr_register(33.3) == 333
    assert profile.power_register(100) == 255
    assert profile.power_register(0) == 0
    assert profile.power_register(50) == 128                 # 127.5, half up
    assert profile.power_register(10) == 26                  # 25.5
    assert profile.power_w(100) == 20
    assert profile.units_per_mm == 65536 / 110
    assert parse_profile("[field]\nsize_mm = 65.536\n").units_per_mm == pytest.approx(1000)


def test_prr_outside_refused():
    for khz in (19.9, 200.1, math.nan, math.inf, "50", True, None):
        with pytest.raises(ValueError) as error:
            default_profile().prr_register(khz)
        assert "\n" not in str(error.value) and "kHz" in str(error.value)


def test_prr_outside_a_narrower_laser_refused():
    profile = parse_profile("[laser]\nprr_khz = [30, 100]\n[defaults]\nprr_khz = 30\n")
    assert profile.prr_register(30) == 300
    assert profile.prr_register(100) == 1000
    with pytest.raises(ValueError, match=r"30 … 100 kHz \(\[laser\] prr_khz"):
        profile.prr_register(20)
    # Rounding to 100 Hz steps stays inside a range that does not end on one.
    odd = parse_profile("[laser]\nprr_khz = [30.04, 99.96]\n[defaults]\nprr_khz = 50\n")
    assert odd.prr_register(30.04) == 301
    assert odd.prr_register(99.96) == 999


def test_power_outside_refused():
    for percent in (-0.1, 100.1, math.nan, "10", False):
        with pytest.raises(ValueError):
            default_profile().power_register(percent)


JUMP_US = [
    ("", 0, 500),
    ("", 100, 500),
    ("jump_delay_us = 505.2", 0, 506),                       # rounded up to a µs
    ("jump_delay_us = 10", 0, 10),
    ("jump_delay_us = 10\nsettle_us_per_mm = 0.5", 0.1, 11),  # 10.05 µs
    ("settle_us_per_mm = 20", 10, 700),                      # 500 + 200 µs
    ("settle_us_per_mm = 3", 1 / 3, 501),                    # 501 µs
    ("jump_delay_us = 65535", 0, 65535),
    ("jump_delay_us = 65535\nsettle_us_per_mm = 10000", 2000, 65535),   # clamped
]


def test_jump_delay_register():
    for galvo, jump_mm, us in JUMP_US:
        profile = parse_profile(f"[galvo]\n{galvo}\n")
        assert profile.jump_delay_register(jump_mm) == us, (galvo, jump_mm)


def test_jump_length_refused():
    for jump_mm in (-1, math.nan, math.inf, "1"):
        with pytest.raises(ValueError):
            default_profile().jump_delay_register(jump_mm)


def test_delay_registers_from_the_profile():
    """The delays go to their registers in µs, to the nearest; a negative laser-on delay as
    the signed value the client encodes."""
    profile = parse_profile("[galvo]\nlaser_on_delay_us = -12.6\nlaser_off_delay_us = 80.5\n"
                            "mark_delay_us = 0\npolygon_delay_us = 4095\npolygon_scaled = false\n")
    assert profile.delay_registers() == {"laser_on_delay": -13, "laser_off_delay": 81,
                                         "mark_delay": 0, "polygon_delay": 4095,
                                         "polygon_scaled": 0}
    assert default_profile().delay_registers() == {
        "laser_on_delay": 100, "laser_off_delay": 50, "mark_delay": 100, "polygon_delay": 0,
        "polygon_scaled": 1}


def test_as_dict_is_json():
    data = json.loads(json.dumps(default_profile().as_dict()))
    assert data["derived"]["jump_delay_us_10mm"] == 500
    assert data["derived"]["default_prr_register"] == 500
    assert data["derived"]["default_power_register"] == 26
    assert data["source"] is None


def test_profile_is_frozen_and_hashable():
    profile = default_profile()
    with pytest.raises(AttributeError):
        profile.field = None
    assert hash(profile) == hash(parse_profile(profile_text()))
    assert isinstance(profile, MachineProfile)
