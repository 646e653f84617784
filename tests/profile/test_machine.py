"""The machine profile (``galvoscan/profile/machine.py``): the template is the defaults, every key's
range is enforced at its edges, typos are caught with a suggestion, and nothing a user can put
in the file escapes as anything but a one-line ProfileError."""

import json
import math
import os
import re

from hypothesis import given, settings, strategies as st
import pytest

from galvoscan.correction.files import save_table
from galvoscan.gateware.field.correction_table import CorrectionTable
from galvoscan.profile.machine import (DEFAULT_PROFILE_NAME, ProfileError, default_profile,
                                       load_profile, parse_profile)
from galvoscan.profile.template import profile_text

from profile_files import DEFAULTS, toml


# What the profile must accept, written out here rather than imported, so that a change of a
# range in the module is a test failure to look at. (section, key): (low, high, whole number).
RANGES = {
    ("field", "size_mm"): (1, 2000, False),
    ("field", "z_units_per_mm"): (0, 65_535, False),
    ("link", "baud"): (300, 12_000_000, True),
    ("link", "timeout_s"): (0.01, 600, False),
    ("laser", "max_power_w"): (0.1, 10_000, False),
    ("laser", "spot_mm"): (0.001, 10, False),
    ("galvo", "jump_delay_us"): (0, 65_535, False),          # jump_delay 0 … 65535 µs
    ("galvo", "laser_on_delay_us"): (-19, 1023, False),      # laser_on_delay, signed
    ("galvo", "laser_off_delay_us"): (0, 1023, False),
    ("galvo", "mark_delay_us"): (0, 4095, False),
    ("galvo", "polygon_delay_us"): (0, 4095, False),
    ("galvo", "min_jump_delay_us"): (0, 65_535, False),      # the jump_delay register's
    ("galvo", "jump_length_limit_mm"): (0, 3000, False),
    ("galvo", "max_speed_mm_s"): (1, 100_000, False),
    ("galvo", "tracking_delay_us"): (0, 2000, False),
    ("defaults", "speed_mm_s"): (0.1, 100_000, False),
    ("defaults", "power_percent"): (0, 100, False),
    ("defaults", "prr_khz"): (20, 200, False),               # laser_prr 200 … 2000 × 100 Hz
    ("defaults", "passes"): (1, 1000, True),
    ("wobble", "across_um"): (0, 10_000, False),
    ("wobble", "along_um"): (0, 10_000, False),
    ("wobble", "freq_hz"): (1, 25_000, False),               # wob_freq 1 … 25 000 Hz
}
# Keys that are not numbers: (section, key): a valid value in TOML.
OTHER_KEYS = {
    ("field", "correction"): None,                            # tested with a real file below
    ("link", "port"): '"/dev/ttyUSB1"',
    ("link", "spi"): '"ftdi://ftdi:2232h/1"',
    ("laser", "prr_khz"): "[20, 200]",
    ("laser", "guide"): "false",
    ("galvo", "polygon_scaled"): "false",
    ("galvo", "head_check"): "true",
}
# Other keys a value at an edge needs, so that only the key under test can be refused.
COMPANIONS = {
    ("defaults", "speed_mm_s"): {("galvo", "max_speed_mm_s"): "100000"},
    ("galvo", "max_speed_mm_s"): {("defaults", "speed_mm_s"): "0.5"},
    ("galvo", "min_jump_delay_us"): {("galvo", "jump_delay_us"): "65535"},
}
def with_value(section, key, value):
    entries = dict(COMPANIONS.get((section, key), {}))
    entries[(section, key)] = value
    return toml(entries)


def refused(text, *pieces, path=DEFAULT_PROFILE_NAME):
    with pytest.raises(ProfileError) as error:
        parse_profile(text, path=path)
    message = str(error.value)
    assert len(message.splitlines()) == 1
    assert message.startswith(str(path))
    for piece in pieces:
        assert piece in message, (piece, message)
    return message


# --- the template ----------------------------------------------------------------------------

def test_template_is_the_defaults():
    profile = parse_profile(profile_text())
    assert profile == default_profile()
    assert profile.correction_table() is None
    resolved = {name: values for name, values in profile.as_dict().items()
                if name in DEFAULTS}
    for section in resolved.values():
        section.pop("correction_nodes", None)
    assert resolved == DEFAULTS


def test_template_file_round_trips(tmp_path):
    path = tmp_path / "galvoscan.toml"
    path.write_text(profile_text(), encoding="utf-8")
    profile = load_profile(path)
    assert profile == default_profile()
    assert profile.source == path


def _comment_above(lines, index):
    block = []
    for line in reversed(lines[:index]):
        if not line.startswith("#") or re.match(r"# \w+ = ", line):
            break
        block.append(line)
    return " ".join(reversed(block))


@pytest.mark.parametrize("section, key", [*RANGES, *OTHER_KEYS])
def test_template_explains_every_key(section, key):
    lines = profile_text().splitlines()
    index = next(i for i, line in enumerate(lines) if re.match(rf"(# )?{key} = ", line) and
                 lines[max(i for i in range(i + 1) if lines[i].startswith("["))] ==
                 f"[{section}]")
    comment = _comment_above(lines, index)
    assert len(comment) > 40, (key, comment)
    if (section, key) in RANGES:
        low, high, _ = RANGES[section, key]
        numbers = {float(n.replace("_", "")) for n in re.findall(r"-?[\d_.]+\d|-?\d", comment)}
        if (section, key) != ("defaults", "prr_khz"):      # "within [laser] prr_khz"
            assert {low, high} <= numbers, (key, comment)


def test_template_guide_comment_points_to_the_wiring():
    assert "the wiring table (docs/hardware/wiring.md)" in profile_text()


def test_every_key_is_known():
    every = {(s, k) for s, keys in DEFAULTS.items() for k in keys}
    assert every == set(RANGES) | set(OTHER_KEYS)


def test_empty_file_is_the_defaults():
    assert parse_profile("") == default_profile()
    assert parse_profile("[field]\n[laser]\n") == default_profile()


# --- ranges at their edges -------------------------------------------------------------------

def _outside(value, direction, whole):
    if whole:
        return value + direction
    return math.nextafter(float(value), direction * math.inf)


@pytest.mark.parametrize("section, key", list(RANGES))
def test_range_edges_accepted(section, key):
    low, high, whole = RANGES[section, key]
    for value in (low, high):
        profile = parse_profile(with_value(section, key, repr(value)))
        assert getattr(getattr(profile, section), key) == value
        if not whole:                           # written as a float: the same
            profile = parse_profile(with_value(section, key, repr(float(value))))
            assert getattr(getattr(profile, section), key) == value


@pytest.mark.parametrize("section, key", list(RANGES))
def test_range_just_outside_refused(section, key):
    low, high, whole = RANGES[section, key]
    for value in (_outside(low, -1, whole), _outside(high, +1, whole)):
        refused(with_value(section, key, repr(value)), f"[{section}] {key} must be",
                f"from {low:g} to {high:g}" if not whole else f"from {low} to {high}")


@pytest.mark.parametrize("section, key", list(RANGES))
def test_non_finite_refused(section, key):
    for value in ("nan", "inf", "-inf", "+nan"):
        refused(with_value(section, key, value), f"[{section}] {key} must be")


@pytest.mark.parametrize("section, key", list(RANGES))
def test_wrong_type_refused(section, key):
    for value in ('"fifty"', '"50"', "true", "false", "[50]", "{ a = 1 }", "1979-05-27",
                  "07:32:00"):
        message = refused(with_value(section, key, value), f"[{section}] {key} must be a ")
        assert "number" in message


def test_error_message_as_documented():
    message = refused('[laser]\nmax_power_w = "fifty"\n')
    assert message == ("galvoscan.toml: [laser] max_power_w must be a number from 0.1 to "
                       "10000 (W), not 'fifty'")


def test_whole_numbers():
    assert parse_profile("[link]\nbaud = 1e6\n").link.baud == 1_000_000
    assert isinstance(parse_profile("[link]\nbaud = 1e6\n").link.baud, int)
    assert parse_profile("[defaults]\npasses = 3.0\n").defaults.passes == 3
    refused("[defaults]\npasses = 1.5\n", "[defaults] passes must be a whole number")
    refused("[link]\nbaud = 115200.5\n", "[link] baud must be a whole number")


def test_huge_integer_refused_not_overflowing():
    refused("[field]\nsize_mm = " + "9" * 400 + "\n", "[field] size_mm must be")
    refused("[link]\nbaud = -" + "9" * 400 + "\n", "[link] baud must be")


def test_laser_prr_accepted():
    for value in ("[20, 200]", "[50, 50]", "[20.0, 199.9]", "[30, 100]"):
        low, high = json.loads(value)
        text = f"[laser]\nprr_khz = {value}\n[defaults]\nprr_khz = {low}\n"
        assert parse_profile(text).laser.prr_khz == (low, high)


LASER_PRR_REFUSED = [
    ("[19.999, 200]", "each from 20 to 200 (kHz)"),
    ("[20, 200.001]", "each from 20 to 200 (kHz)"),
    ("[60, 50]", "lowest ≤ highest"),
    ("[20]", "two numbers"),
    ("[20, 100, 200]", "two numbers"),
    ("50", "two numbers"),
    ('["20", 200]', "two numbers"),
    ("[true, 200]", "two numbers"),
    ("[nan, 200]", "two numbers"),
    ("[]", "two numbers"),
]


def test_laser_prr_refused():
    for value, piece in LASER_PRR_REFUSED:
        refused(f"[laser]\nprr_khz = {value}\n", "[laser] prr_khz must be", piece)


def test_default_prr_within_the_lasers():
    text = "[laser]\nprr_khz = [30, 100]\n[defaults]\nprr_khz = {}\n"
    assert parse_profile(text.format(30)).defaults.prr_khz == 30
    assert parse_profile(text.format(100)).defaults.prr_khz == 100
    refused(text.format(29.9), "[defaults] prr_khz", "[laser] prr_khz")
    refused(text.format(100.1), "[defaults] prr_khz", "[laser] prr_khz")
    # The laser's narrower range with the default 50 kHz outside it:
    refused("[laser]\nprr_khz = [60, 100]\n", "[defaults] prr_khz")


def test_default_speed_at_most_the_galvos():
    text = "[galvo]\nmax_speed_mm_s = 2000\n[defaults]\nspeed_mm_s = {}\n"
    assert parse_profile(text.format(2000)).defaults.speed_mm_s == 2000
    refused(text.format(2000.5), "[defaults] speed_mm_s", "max_speed_mm_s")


OTHER_TYPES_REFUSED = [
    ("laser", "guide", "1", "true or false"),
    ("laser", "guide", '"yes"', "true or false"),
    ("link", "port", "5", "text in quotes"),
    ("link", "port", '""', "text in quotes"),
    ("link", "port", "true", "text in quotes"),
    ("link", "spi", "[1]", "text in quotes"),
    ("field", "correction", "3", "file name in quotes"),
    ("field", "correction", '"  "', "file name in quotes"),
]


def test_other_types_refused():
    for section, key, value, piece in OTHER_TYPES_REFUSED:
        refused(toml({(section, key): value}), f"[{section}] {key} must be", piece)


def test_text_keys():
    profile = parse_profile('[link]\nport = "COM4"\nbaud = 115200\ntimeout_s = 2\n')
    assert (profile.link.port, profile.link.baud, profile.link.timeout_s) == ("COM4", 115200, 2)
    assert parse_profile('[link]\nspi = "ftdi://ftdi:2232h/1"\n').link.spi == \
        "ftdi://ftdi:2232h/1"
    assert parse_profile("[laser]\nguide = false\n").laser.guide is False


def test_port_and_spi_refused_together():
    refused('[link]\nport = "/dev/ttyUSB1"\nspi = "ftdi://ftdi:2232h/1"\n', "port", "spi")


# --- unknown names ---------------------------------------------------------------------------

def test_unknown_key_suggests_the_near_one():
    message = refused("[defaults]\nspeed_mms = 500\n", "speed_mms", "did you mean speed_mm_s?")
    for known in ("speed_mm_s", "power_percent", "prr_khz", "passes"):
        assert known in message


def test_unknown_key_without_a_near_one_lists_the_known():
    message = refused("[laser]\nwavelength_nm = 1064\n", "[laser] wavelength_nm")
    assert "did you mean" not in message
    assert "max_power_w, prr_khz, spot_mm, guide" in message


def test_key_in_the_wrong_section():
    refused("[laser]\njump_delay_us = 300\n", "[laser] jump_delay_us",
            "did you mean [galvo] jump_delay_us?")


def test_a_short_jump_waiting_longer_than_a_long_one_refused():
    refused("[galvo]\nmin_jump_delay_us = 600\n", "[galvo] min_jump_delay_us must be at most "
            "jump_delay_us (500 µs", "not 600")
    refused("[galvo]\njump_delay_us = 100\nmin_jump_delay_us = 100.5\n", "at most jump_delay_us "
            "(100 µs", "not 100.5")
    # Left out, its default gives way to a shorter jump delay: that after every jump.
    profile = parse_profile("[galvo]\njump_delay_us = 100\n")
    assert profile.galvo.min_jump_delay_us == 100 and not profile.variable_jump_delay


@settings(max_examples=60, deadline=None)
@given(st.sampled_from(["min_jump_delay_us", "jump_length_limit_mm", "jump_delay_us"]),
       st.one_of(st.floats(max_value=-1e-9), st.floats(min_value=70000), st.just(math.nan),
                 st.text("ab5 .-", max_size=5), st.booleans()))
def test_bad_jump_delays_refused(key, value):
    """Negative, too long, not a number: one line naming the key."""
    written = json.dumps(value) if isinstance(value, (str, bool)) else repr(value)
    text = f"[galvo]\n{key} = {written}\n"
    refused(text, f"[galvo] {key} must be")


def test_the_old_settling_key_says_what_replaced_it():
    refused("[galvo]\nsettle_us_per_mm = 0\n", "[galvo] settle_us_per_mm is no longer a key",
            "min_jump_delay_us", "jump_length_limit_mm = 0")


def test_unknown_section_suggests_the_near_one():
    refused("[lazer]\nmax_power_w = 20\n", "unknown section [lazer]", "did you mean [laser]?",
            "[field], [link], [laser], [galvo], [defaults]")
    refused("[machine]\n", "unknown section [machine]", "[field]")


def test_key_outside_a_section():
    refused("size_mm = 110\n", "size_mm", "[field]")
    refused("prr_khz = 50\n", "prr_khz", "[laser] or [defaults]")
    refused("sise_mm = 110\n", "sise_mm", "did you mean size_mm")


def test_section_that_is_not_a_table():
    refused("laser = 5\n", "[laser] must be a section")
    refused("[[laser]]\nmax_power_w = 5\n", "[[laser]]")
    refused("[laser.max_power_w]\n", "[laser] max_power_w must be a number")


def test_odd_key_names_are_quoted():
    message = refused('[laser]\n"max power" = 5\n')
    assert "'max power'" in message


# --- TOML and the file -----------------------------------------------------------------------

def test_syntax_error_names_the_line():
    refused("[field]\nsize_mm = 110\nbaud 5\n", "not valid TOML", "line 3")
    refused("[field]\nsize_mm = 110\nsize_mm = 120\n", "not valid TOML")


def test_deep_nesting_is_a_profile_error():
    refused("a = " + "[" * 5000 + "]" * 5000 + "\n", "not valid TOML")


def test_missing_file(tmp_path):
    with pytest.raises(ProfileError, match="no such file"):
        load_profile(tmp_path / "nope.toml")


def test_folder(tmp_path):
    with pytest.raises(ProfileError, match="is a folder"):
        load_profile(tmp_path)


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0,
                    reason="needs file permissions that bind (not root)")
def test_unreadable(tmp_path):
    path = tmp_path / "galvoscan.toml"
    path.write_text("")
    path.chmod(0)
    try:
        with pytest.raises(ProfileError, match="cannot read"):
            load_profile(path)
    finally:
        path.chmod(0o600)


def test_not_utf8_names_the_line(tmp_path):
    path = tmp_path / "galvoscan.toml"
    path.write_bytes(b"[laser]\n# 20 W \xb5s\nmax_power_w = 20\n")
    with pytest.raises(ProfileError, match=r"line 2: not UTF-8"):
        load_profile(path)


def test_byte_order_mark_accepted(tmp_path):
    path = tmp_path / "galvoscan.toml"
    path.write_bytes(b"\xef\xbb\xbf" + profile_text().encode("utf-8"))
    assert load_profile(path) == default_profile()


def test_file_errors_name_the_file(tmp_path):
    path = tmp_path / "m.toml"
    path.write_text("[laser]\nspot_mm = 0\n")
    with pytest.raises(ProfileError) as error:
        load_profile(path)
    assert str(error.value).startswith(f"{path}: [laser] spot_mm must be")


# --- the correction table --------------------------------------------------------------------

@pytest.fixture
def lens_table(tmp_path):
    folder = tmp_path / "machine" / "tables"
    folder.mkdir(parents=True)
    table = CorrectionTable.identity(5).with_node(2, 2, 7, -3)
    save_table(folder / "lens.json", table, source="test")
    return folder / "lens.json"


def test_correction_relative_to_the_profile(tmp_path, monkeypatch, lens_table):
    profile_path = tmp_path / "machine" / "galvoscan.toml"
    profile_path.write_text('[field]\ncorrection = "tables/lens.json"\n')
    monkeypatch.chdir(tmp_path)                      # not the profile's folder
    profile = load_profile("machine/galvoscan.toml")
    assert profile.field.correction == lens_table
    assert profile.field.correction.is_absolute()
    table = profile.correction_table()
    assert table.n == 5 and table.dx[2, 2] == 7 and table.dy[2, 2] == -3
    assert profile.as_dict()["field"]["correction_nodes"] == 5
    assert profile != default_profile()


def test_correction_absolute_path(tmp_path, lens_table):
    path = tmp_path / "elsewhere.toml"
    path.write_text(f"[field]\ncorrection = {json.dumps(str(lens_table))}\n")
    assert load_profile(path).correction_table().n == 5


def test_correction_missing(tmp_path):
    path = tmp_path / "galvoscan.toml"
    path.write_text('[field]\ncorrection = "lens.cor"\n')
    with pytest.raises(ProfileError) as error:
        load_profile(path)
    message = str(error.value)
    assert "[field] correction" in message and str(tmp_path / "lens.cor") in message
    assert "\n" not in message


@pytest.mark.parametrize("name, content", [
    ("lens.json", b"{not json"),
    ("lens.json", b'{"format": "something else"}'),
    ("lens.ctb", b"\x00" * 10),
    ("lens.cor", b"garbage"),
    ("lens.txt", b"1 2 3"),
])
def test_correction_unreadable_table(tmp_path, name, content):
    (tmp_path / name).write_bytes(content)
    path = tmp_path / "galvoscan.toml"
    path.write_text(f'[field]\ncorrection = "{name}"\n')
    with pytest.raises(ProfileError) as error:
        load_profile(path)
    assert "[field] correction" in str(error.value) and "\n" not in str(error.value)


def test_correction_folder(tmp_path):
    (tmp_path / "tables").mkdir()
    path = tmp_path / "galvoscan.toml"
    path.write_text('[field]\ncorrection = "tables"\n')
    with pytest.raises(ProfileError, match=r"\[field\] correction: .* is a folder"):
        load_profile(path)


def test_the_tracking_delay_is_the_galvo_models():
    """The default tracking delay is the lag of the galvo model (Wan et al.'s JD1403, fitted
    to its step times) behind a set point moving at constant speed: a critically damped
    servo's 2/ωn, measured here by following a ramp."""
    import numpy as np
    from galvoscan.analysis.galvo import GalvoModel
    galvo = GalvoModel.from_step_times()
    frames = np.arange(400) * 3.0                 # 3 units a 10 µs frame: a slow ramp
    path = galvo.follow(frames, frames * 0)
    t = np.arange(len(path.x)) * path.dt
    # Late in the ramp the mirror is where the set point was a lag ago.
    speed = 3.0 / 10e-6
    lag_s = (frames[-1] - path.x[-1]) / speed
    assert default_profile().galvo.tracking_delay_us == pytest.approx(lag_s * 1e6, abs=5)
    assert t[-1] > 10 * lag_s
