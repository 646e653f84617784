"""The settings schema (``galvoscan/settings``): each setting's range read and refused the
same way wherever it is used (the command line of every command, a job file, a layer, the
machine profile), ``--timeout`` one range that accepts what ``board --sim`` advises, every
machine-profile key a declaration, the schema's kinds read by any text, and the docs' tables
of the settings, the profile's keys and a layer's keys generated from the declarations."""

import argparse
import re
from pathlib import Path

import grimp
import pytest
from hypothesis import given, strategies as st

from galvoscan.cli import parser
from galvoscan.cli.job_options import SECTIONS, job_file_table
from galvoscan.gateware.host.regmap import BY_NAME
from galvoscan.plan import layer_keys
from galvoscan.profile import keys as profile_keys
from galvoscan.profile.machine import ProfileError, default_profile, parse_profile
from galvoscan.settings import fly, laser, machine
from galvoscan.settings.schema import (ProfileKey, Setting, SettingError, markdown_table,
                                       profile_table)

DOCS = Path(__file__).parents[2] / "docs"


def _option(argv_prefix, flag):
    """The argparse action of ``flag`` in the subcommand ``argv_prefix``."""
    top = parser()
    for name in argv_prefix:
        sub = next(a for a in top._actions if isinstance(a, argparse._SubParsersAction))
        top = sub.choices[name]
    return next(a for a in top._actions if flag in a.option_strings)


_EVERY_SETTING = [laser.SPEED, laser.POWER, laser.PRR, laser.PASSES, laser.WOBBLE,
                  laser.WOBBLE_ALONG, laser.WOBBLE_HZ, laser.TOLERANCE, laser.TIMEOUT]


@pytest.mark.parametrize("setting", _EVERY_SETTING, ids=lambda s: s.name)
def test_ends_accepted_and_outside_refused(setting):
    assert setting.parse(str(setting.low)) == setting.low
    assert setting.parse(str(setting.high)) == setting.high
    step = 1 if setting.kind == "integer" else max(abs(setting.high) * 1e-6, 1e-9)
    for outside in (setting.low - step, setting.high + step * 10):
        text = str(int(outside)) if setting.kind == "integer" else repr(outside)
        with pytest.raises(SettingError, match=f"^{setting.what.replace('(', '.').replace(')', '.')} must be from "):
            setting.parse(text)
    with pytest.raises(SettingError, match="must be an? (number|integer), not 'x'"):
        setting.parse("x")


@given(st.floats(allow_nan=True, allow_infinity=True))
def test_speed_by_any_number(value):
    inside = value == value and laser.SPEED.low <= value <= laser.SPEED.high
    if inside:
        assert laser.SPEED.parse(repr(value)) == value
    else:
        with pytest.raises(SettingError):
            laser.SPEED.parse(repr(value))


def test_a_setting_checks_itself():
    with pytest.raises(ValueError, match="range"):
        Setting("x_mm", "number", "mm", 2, 1, help="x", what="x")
    with pytest.raises(ValueError, match="default"):
        Setting("x_mm", "number", "mm", 0, 1, default=2, help="x", what="x")
    with pytest.raises(ValueError, match="kind"):
        Setting("x", "colour")
    with pytest.raises(ValueError, match="no range"):
        Setting("x", "bool", low=0, high=1)
    with pytest.raises(ValueError, match="choices"):
        Setting("x", "choice")
    with pytest.raises(ValueError, match="parts"):
        Setting("x", "numbers", metavar="A")
    with pytest.raises(ValueError, match="default"):
        Setting("x", "choice", choices=("a", "b"), default="c")
    with pytest.raises(ValueError, match="default"):
        ProfileKey("s", "x_mm", Setting("x_mm", "number", "mm", 0, 1, what="x"), default=2)
    with pytest.raises(ValueError, match="default"):
        ProfileKey("s", "x_mm", Setting("x_mm", "number", "mm", 0, 1, what="x"),
                   default=(0, 2), kind="pair")
    with pytest.raises(ValueError, match="a text of a number setting"):
        ProfileKey("s", "x_mm", Setting("x_mm", "number", "mm", 0, 1, what="x"), kind="text")


_YES_OR_NO = Setting("x", "bool")
_WORDS = {"yes": True, "true": True, "1": True, "on": True,
          "no": False, "false": False, "0": False, "off": False}


@given(st.one_of(st.sampled_from(list(_WORDS)).map(lambda w: f" {w.upper()} "),
                 st.text(max_size=6)))
def test_yes_or_no_by_any_word(text):
    """A yes-or-no setting takes its eight words in any case, and refuses any other."""
    if text.strip().lower() in _WORDS:
        assert _YES_OR_NO.parse(text) is _WORDS[text.strip().lower()]
    else:
        with pytest.raises(SettingError, match="^must be yes or no, not "):
            _YES_OR_NO.parse(text)
    assert _YES_OR_NO.check(True) is True
    with pytest.raises(SettingError):
        _YES_OR_NO.check(1)


_PAIR = Setting("x_khz", "pair", "kHz", 20, 200, what="x")


@given(st.floats(allow_nan=True, allow_infinity=True),
       st.floats(allow_nan=True, allow_infinity=True))
def test_a_pair_by_any_numbers(low, high):
    """A pair takes two numbers, each in range, the first not above the second."""
    inside = all(v == v and 20 <= v <= 200 for v in (low, high)) and low <= high
    for text in (f"{low!r},{high!r}", f"[{low!r}, {high!r}]"):
        if inside:
            assert _PAIR.parse(text) == (low, high)
        else:
            with pytest.raises(SettingError, match="^x must be "):
                _PAIR.parse(text)
    if inside:
        assert _PAIR.check((low, high)) == (low, high)


_CHOICE = Setting("x", "choice", choices=("serpentine", "oneway"), make=str.upper)


@given(st.one_of(st.sampled_from(_CHOICE.choices), st.text(max_size=10)))
def test_a_choice_by_any_word(text):
    """A choice takes its words as they are written (made into its value), and refuses any
    other with the list of them."""
    if text in _CHOICE.choices:
        assert _CHOICE.parse(text) == text.upper()
    else:
        with pytest.raises(SettingError, match=r"^must be serpentine, oneway, not "):
            _CHOICE.parse(text)


def _span(spacing, count=None):
    if spacing <= 0:
        raise ValueError(f"spacing {spacing:g}: must be above 0")
    return spacing, count


_NUMBERS = Setting("x", "numbers", "mm, rings", what="--x", metavar="SPACING[,COUNT]",
                   parts=("number", "integer"), make=_span)


@given(st.text(alphabet="0123456789.,-e x", max_size=10))
def test_numbers_by_any_text(text):
    """Up to as many numbers as its parts, each of its part's kind, the first needed; a value
    its maker refuses is said with the maker's reason."""
    parts = text.replace(" ", "").split(",")
    try:
        if not 1 <= len(parts) <= 2:
            raise ValueError
        values = [float(parts[0]), *(int(p) for p in parts[1:])]
    except ValueError:
        with pytest.raises(SettingError) as refused:
            _NUMBERS.parse(text)
        assert str(refused.value) == f"--x must be SPACING[,COUNT] (mm, rings), not {text!r}"
        return
    if values[0] > 0:
        made = _NUMBERS.parse(text)
        assert made == tuple(values + [None] * (2 - len(values)))
        assert _NUMBERS.check(text) == made           # a program's text, read alike
    else:
        with pytest.raises(SettingError, match=r"^--x .*: spacing .*: must be above 0$"):
            _NUMBERS.parse(text)


@pytest.mark.parametrize("command", [("read",), ("send",), ("mark",), ("clean",),
                                     ("test-grid",)])
def test_one_timeout(command):
    """Every command's ``--timeout`` is the one setting, and takes the longest answer timeout
    the simulated board advises (600 s, ``SimulatedBoard.answer_timeout_s``'s ceiling)."""
    action = _option(command, "--timeout")
    assert action.type("600") == 600.0
    with pytest.raises(argparse.ArgumentTypeError, match="timeout must be from 0.01 to 600"):
        action.type("601")
    assert "0.01 … 600" in action.help


@pytest.mark.parametrize("command", [("mark",), ("clean",)])
@pytest.mark.parametrize("setting", [laser.SPEED, laser.POWER], ids=lambda s: s.name)
def test_job_options_are_the_settings(command, setting):
    action = _option(command, setting.flag)
    with pytest.raises(argparse.ArgumentTypeError) as refused:
        action.type(str(setting.high * 2))
    with pytest.raises(SettingError) as same:
        setting.parse(str(setting.high * 2))
    assert str(refused.value) == str(same.value)


@pytest.mark.parametrize("flag, setting", [("--speeds", laser.SPEED),
                                           ("--powers", laser.POWER)])
def test_grid_axes_are_the_settings(flag, setting):
    """test-grid's axes take their settings' ends, and nothing past them."""
    action = _option(("test-grid",), flag)
    assert action.type(f"{setting.low}:{setting.high}:2") == [setting.low, setting.high]
    with pytest.raises(argparse.ArgumentTypeError, match=f"{flag} must be from"):
        action.type(f"{setting.low}:{setting.high * 1.01}:2")


#: Every key of the profile, as ``(section, key)`` (for the tests' names).
_PROFILE_KEYS = {(key.section, key.name): key for keys in machine.PROFILE.values()
                 for key in keys}


@pytest.mark.parametrize("section, name", [k for k, key in _PROFILE_KEYS.items()
                                           if key.setting.ranged])
def test_profile_keys_are_the_settings(section, name):
    """A profile key takes its setting's ends, and refuses just outside them."""
    key = _PROFILE_KEYS[section, name]
    step = 1 if key.kind == "integer" else max(abs(key.high) * 1e-3, 1e-3)
    value = f"[{key.low!r}, {key.high!r}]" if key.kind == "pair" else repr(key.high)
    if (section, name) == ("defaults", "speed_mm_s"):      # at most [galvo] max_speed_mm_s
        value = f"{value}\n[galvo]\nmax_speed_mm_s = {value}"
    if (section, name) == ("galvo", "min_jump_delay_us"):    # at most jump_delay_us
        value = f"{value}\njump_delay_us = {value}"
    parse_profile(f"[{section}]\n{name} = {value}\n")
    for outside in (key.high + step, key.low - step):
        with pytest.raises(ProfileError, match=f"{name} must be"):
            parse_profile(f"[{section}]\n{name} = {outside!r}\n")


def test_every_profile_key_is_a_declaration():
    """The profile reads the declared keys and no others: each a setting declared in
    galvoscan.settings (none written in galvoscan.profile), its defaults the profile's."""
    assert profile_keys.SECTIONS is machine.PROFILE
    declared = {id(value) for module in (laser, machine, fly) for value in vars(module).values()
                if isinstance(value, Setting)}
    profile = default_profile()
    for (section, name), key in _PROFILE_KEYS.items():
        assert isinstance(key, ProfileKey) and key.section == section
        assert id(key.setting) in declared, (section, name)
        assert getattr(getattr(profile, section), name) == key.default, (section, name)
        assert key.help and key.kind


def test_the_profiles_delay_keys_are_the_registers():
    """[galvo]'s delays are the registers a layer sets: their ranges the register map's."""
    for key, register in profile_keys.DELAY_KEYS.items():
        found = _PROFILE_KEYS["galvo", key]
        assert (found.low, found.high) == (BY_NAME[register].low, BY_NAME[register].high)
    assert profile_keys.JUMP_DELAY_RANGE_US == (BY_NAME["jump_delay"].low,
                                                BY_NAME["jump_delay"].high)


def test_profile_docs_table_is_the_declarations():
    """The settings page's table of the profile's keys is generated from the declarations."""
    page = (DOCS / "reference" / "settings.md").read_text(encoding="utf-8")
    assert profile_table(machine.PROFILE) in page


def test_docs_table_is_the_settings():
    """docs/reference/settings.md's table is generated from the settings (never edited by hand)."""
    docs = (DOCS / "reference" / "settings.md").read_text(encoding="utf-8")
    assert markdown_table(laser.ALL) in docs


def test_layer_docs_table_is_the_declarations():
    """The settings page's table of a layer's keys is generated from the key table, and the
    marking page's list of them names each key and no other."""
    page = (DOCS / "reference" / "settings.md").read_text(encoding="utf-8")
    assert layer_keys.markdown_table() in page
    marking = (DOCS / "user" / "marking.md").read_text(encoding="utf-8")
    listed = re.search(r"The keys: (.+?); what a layer leaves out", marking, re.S)
    assert listed, "the marking page's list of a layer's keys"
    words = re.sub(r"\([^)]*\)", "", listed[1])          # what is said of a key, in brackets
    assert re.findall(r"`(\w+)`", words) == list(layer_keys.LAYER_KEYS)


def test_job_file_table_is_the_options():
    """The job-file page's table of a job file's keys is generated from the job options; each
    key it lists is one a job file takes."""
    page = (Path(__file__).parents[2] / "docs" / "user" / "job-files.md").read_text(
        encoding="utf-8")
    assert job_file_table() in page
    for section, keys in SECTIONS.items():
        for key in keys:
            assert f"`{key}`" in job_file_table()


@pytest.mark.parametrize("importer, imported", [
    ("galvoscan.settings", "galvoscan.cli"),          # the schema sits below the CLI
    ("galvoscan.api", "galvoscan.cli"),               # the API needs no command line
    ("galvoscan.plan.layer_keys", "galvoscan.cli"),   # nor a layer's key table
    ("galvoscan.cli.jobfile", "galvoscan.cli.mark"),  # job files read the option table
    ("galvoscan.cli.job_options", "galvoscan.cli.mark"),
])
def test_imports_in_dependency_order(importer, imported):
    """No import chain, at module top or in a function, from ``importer`` to ``imported``."""
    graph = grimp.build_graph("galvoscan", cache_dir=None)
    importers = [m for m in graph.modules if m == importer or m.startswith(importer + ".")]
    for module in importers:
        for target in [m for m in graph.modules
                       if m == imported or m.startswith(imported + ".")]:
            assert graph.find_shortest_chain(importer=module, imported=target) is None, \
                (module, target)
