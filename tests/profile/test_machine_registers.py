"""The machine profile's derived numbers (``galvoscan/profile/machine.py``): kHz, %, µs and mm
turned into register values by hand-worked examples, out-of-range values refused in one line,
and the profile as JSON and as a frozen, hashable value."""

from fractions import Fraction
import json
import math

from hypothesis import given, settings, strategies as st
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


def rtc_jump_delay_us(short, long, limit, jump):
    """SCANLAB's RTC's variable jump delay, in exact fractions (``short``, ``long``,
    ``limit``, ``jump`` as decimal text): ``long`` for a jump of ``limit`` or longer (every
    jump when ``limit`` is 0), else ``short`` and the difference in proportion to the jump's
    length; the register's whole µs, rounded up and held to its 0 … 65535."""
    short, long, limit, jump = (Fraction(v) for v in (short, long, limit, jump))
    us = long if limit == 0 or jump >= limit else short + (long - short) * jump / limit
    return min(65535, math.ceil(us))


#: (profile lines, jump in mm, the jump delay register), worked by hand.
JUMP_US = [
    ("", "0", 240),                                          # the defaults: 240 µs at 0 …
    ("", "1", 292),                                          # 240 + 260 × 1/5
    ("", "2.5", 370),
    ("", "0.05", 243),                                       # 242.6, rounded up
    ("", "5", 500),                                          # … 500 µs from 5 mm on
    ("", "100", 500),
    ("jump_length_limit_mm = 0", "0", 500),                  # one delay for every jump
    ("jump_delay_us = 505.2\njump_length_limit_mm = 0", "0", 506),   # rounded up to a µs
    ("jump_delay_us = 10", "0", 10),                         # the short one its default's …
    ("jump_delay_us = 10", "3", 10),                         # … at most: 10 µs every jump
    ("min_jump_delay_us = 0\njump_length_limit_mm = 110", "55", 250),
    ("min_jump_delay_us = 10.05\njump_length_limit_mm = 100", "0", 11),
    ("jump_delay_us = 65535\nmin_jump_delay_us = 65535", "0", 65535),
]


def test_jump_delay_register():
    for galvo, jump_mm, us in JUMP_US:
        profile = parse_profile(f"[galvo]\n{galvo}\n")
        assert profile.jump_delay_register(float(jump_mm)) == us, (galvo, jump_mm)


@pytest.mark.parametrize("short, long, limit", [
    ("240", "500", "5"), ("20", "500", "110"), ("0", "65535", "2000"), ("100", "100", "5"),
    ("10", "85", "10"), ("0", "0", "3")])
def test_each_jump_waits_what_rtc_gives_it(short, long, limit):
    """Each jump's delay, for lengths from 0 past the limit, is RTC's rule's."""
    profile = parse_profile(f"[galvo]\nmin_jump_delay_us = {short}\njump_delay_us = {long}\n"
                            f"jump_length_limit_mm = {limit}\n")
    for jump in ("0", "0.05", "0.1", "0.3333", "1", "2.5", "4.99", "5", "7.5", "10", "55",
                 "110", "155.6", "2000"):
        assert profile.jump_delay_register(float(jump)) == \
            rtc_jump_delay_us(short, long, limit, jump), jump


@settings(max_examples=200, deadline=None)
@given(st.floats(0, 65535), st.floats(0, 65535), st.floats(0, 3000),
       st.floats(0, 4000, allow_nan=False))
def test_jump_delay_is_rtcs_and_grows_with_length(short, long, limit, jump):
    short, long = sorted((short, long))
    profile = parse_profile(f"[galvo]\nmin_jump_delay_us = {short!r}\n"
                            f"jump_delay_us = {long!r}\njump_length_limit_mm = {limit!r}\n")
    us = profile.jump_delay_register(jump)
    # (Less by one where the float sum lands within 1e-9 µs above a whole µs.)
    exact = rtc_jump_delay_us(repr(short), repr(long), repr(limit), repr(jump))
    assert exact - 1 <= us <= exact
    assert math.ceil(short - 1e-9) <= us <= math.ceil(long)
    assert profile.jump_delay_register(jump * 2) >= us


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
    assert data["derived"]["jump_delay_us_1mm"] == 292              # 240 + 260 × 1/5
    assert data["derived"]["default_prr_register"] == 500
    assert data["derived"]["default_power_register"] == 26
    assert data["source"] is None


def test_profile_is_frozen_and_hashable():
    profile = default_profile()
    with pytest.raises(AttributeError):
        profile.field = None
    assert hash(profile) == hash(parse_profile(profile_text()))
    assert isinstance(profile, MachineProfile)
