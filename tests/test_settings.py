"""The settings schema (``galvoscan/settings``): each setting's range read and refused the
same way wherever it is used (the command line of every command, a job file, a layer, the
machine profile), and ``--timeout`` one range that accepts what ``board --sim`` advises."""

import argparse
import subprocess
import sys
from pathlib import Path

import grimp
import pytest
from hypothesis import given, strategies as st

from galvoscan.cli import parser
from galvoscan.cli.job_options import SECTIONS, job_file_table
from galvoscan.profile.machine import ProfileError, parse_profile
from galvoscan.settings import laser
from galvoscan.settings.schema import Setting, SettingError, markdown_table


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


@pytest.mark.parametrize("section, key", list(laser.PROFILE_KEYS))
def test_profile_keys_are_the_settings(section, key):
    """A profile key refuses just outside its setting's range, and takes its ends."""
    setting = laser.PROFILE_KEYS[section, key]
    above = setting.high + (1 if setting.kind == "integer" else setting.high * 1e-3)
    value = f"[{setting.low}, {setting.high}]" if key == "prr_khz" and section == "laser" \
        else repr(setting.high)
    if (section, key) == ("defaults", "speed_mm_s"):      # at most [galvo] max_speed_mm_s
        value = f"{value}\n[galvo]\nmax_speed_mm_s = {value}"
    parse_profile(f"[{section}]\n{key} = {value}\n")
    with pytest.raises(ProfileError, match=f"{key} must be"):
        parse_profile(f"[{section}]\n{key} = {above!r}\n")


def test_docs_table_is_the_settings():
    """docs/reference/settings.md's table is generated from the settings (never edited by hand)."""
    docs = (Path(__file__).parent.parent / "docs" / "reference" / "settings.md").read_text(encoding="utf-8")
    assert markdown_table(laser.ALL) in docs


def test_job_file_table_is_the_options():
    """The job-file page's table of a job file's keys is generated from the job options; each
    key it lists is one a job file takes."""
    page = (Path(__file__).parent.parent / "docs" / "user" / "job-files.md").read_text(
        encoding="utf-8")
    assert job_file_table() in page
    for section, keys in SECTIONS.items():
        for key in keys:
            assert f"`{key}`" in job_file_table()


@pytest.mark.parametrize("importer, imported", [
    ("galvoscan.settings", "galvoscan.cli"),          # the schema sits below the CLI
    ("galvoscan.api", "galvoscan.cli"),               # the API needs no command line
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
