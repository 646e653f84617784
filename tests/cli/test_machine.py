"""``galvoscan machine init`` / ``show`` and the ``--machine`` option the job commands share
(``galvoscan/cli/machine.py``)."""

import argparse
import json
import subprocess
import sys

import pytest

from galvoscan.cli import main
from galvoscan.cli.args import CLIError
from galvoscan.cli.machine import add_machine_option, profile_from
from galvoscan.correction.files import save_table
from galvoscan.gateware.field.correction_table import CorrectionTable
from galvoscan.profile.machine import default_profile
from galvoscan.profile.template import profile_text


@pytest.fixture
def here(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    return tmp_path


def one_line_error(capsys, argv):
    """The error of a command that must fail: one line, no traceback."""
    with pytest.raises(SystemExit) as exit:
        main(argv)
    assert exit.value.code not in (0, None)
    err = capsys.readouterr().err.strip() or str(exit.value)
    assert "Traceback" not in err
    lines = err.splitlines()
    assert len(lines) == 1, lines
    return lines[0]


# --- init ------------------------------------------------------------------------------------

def test_init_writes_the_template(here, capsys):
    assert main(["machine", "init"]) == 0
    assert (here / "galvoscan.toml").read_text(encoding="utf-8") == profile_text()
    out = capsys.readouterr().out
    assert "galvoscan.toml" in out
    for key in ("port", "size_mm", "max_power_w"):
        assert key in out


def test_init_refuses_to_overwrite(here, capsys):
    path = here / "galvoscan.toml"
    path.write_text("# my machine\n[field]\nsize_mm = 175\n")
    line = one_line_error(capsys, ["machine", "init"])
    assert "galvoscan.toml" in line and "--force" in line
    assert path.read_text() == "# my machine\n[field]\nsize_mm = 175\n"


def test_second_init_refuses(here, capsys):
    assert main(["machine", "init"]) == 0
    capsys.readouterr()
    one_line_error(capsys, ["machine", "init"])
    assert (here / "galvoscan.toml").read_text(encoding="utf-8") == profile_text()


def test_init_force_overwrites(here, capsys):
    path = here / "galvoscan.toml"
    path.write_text("[field]\nsize_mm = 175\n")
    assert main(["machine", "init", "--force"]) == 0
    assert path.read_text(encoding="utf-8") == profile_text()


def test_init_into_a_new_folder(here, capsys):
    assert main(["machine", "init", "machines/fiber-20w.toml"]) == 0
    assert (here / "machines" / "fiber-20w.toml").read_text(encoding="utf-8") == profile_text()
    assert "--machine machines/fiber-20w.toml" in capsys.readouterr().out


def test_init_refuses_a_folder(here, capsys):
    (here / "box").mkdir()
    with pytest.raises(SystemExit) as exit:
        main(["machine", "init", "box"])
    assert exit.value.code != 0
    assert "Traceback" not in capsys.readouterr().err


# --- show ------------------------------------------------------------------------------------

def test_show_prints_user_units(here, capsys):
    main(["machine", "init"])
    capsys.readouterr()
    assert main(["machine", "show"]) == 0
    captured = capsys.readouterr()
    out = captured.out
    assert captured.err == ""                  # the file is there: no note
    assert "galvoscan.toml" in out
    for piece in ("110 × 110 mm", "595.782 galvo units per mm", "20 W", "20 … 200 kHz",
                  "0.05 mm", "240 µs (a jump of 0) … 500 µs (one of 5 mm or longer)",
                  # 240 + 260 × 0.1/5 = 245.2 µs, rounded up; 240 + 260 × 1/5; the long one
                  "0.1 / 1 / 10 mm jump  246 / 292 / 500 µs",
                  "laser on / off delay", "100 / 50 µs", "10000 mm/s", "1000 mm/s",
                  "10 %", "laser_power 26", "50 kHz (laser_prr 500)", "identity table"):
        assert piece in out, piece


def test_show_json_parses(here, capsys):
    (here / "m.toml").write_text('[link]\nport = "/dev/ttyUSB1"\n'
                                 '[galvo]\njump_delay_us = 700\nmin_jump_delay_us = 300\n'
                                 'jump_length_limit_mm = 20\n')
    assert main(["machine", "show", "--machine", "m.toml", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["source"] == "m.toml"
    assert data["link"]["port"] == "/dev/ttyUSB1"
    assert data["field"]["size_mm"] == 110
    assert data["laser"]["prr_khz"] == [20, 200]
    assert data["derived"]["jump_delay_us_0mm"] == 300
    assert data["derived"]["jump_delay_us_1mm"] == 320             # 300 + 400 × 1/20 µs
    assert data["derived"]["jump_delay_us_10mm"] == 500            # 300 + 400 × 10/20 µs
    assert data["galvo"]["jump_length_limit_mm"] == 20
    assert data["derived"]["delay_registers"]["laser_on_delay"] == 100
    assert data["derived"]["units_per_mm"] == pytest.approx(65536 / 110)


def test_show_without_a_file_uses_the_defaults(here, capsys):
    assert main(["machine", "show", "--json"]) == 0
    captured = capsys.readouterr()
    assert json.loads(captured.out)["source"] is None
    note = captured.err.strip().splitlines()
    assert len(note) == 1
    assert "no ./galvoscan.toml" in note[0] and "110 mm field" in note[0] and \
        "galvoscan machine init" in note[0]


def test_show_correction_table(here, capsys):
    save_table(here / "lens.json", CorrectionTable.identity(9))
    (here / "galvoscan.toml").write_text('[field]\ncorrection = "lens.json"\n')
    assert main(["machine", "show"]) == 0
    out = capsys.readouterr().out
    assert str(here / "lens.json") in out and "9 × 9 nodes" in out


@pytest.mark.parametrize("text, piece", [
    ('[laser]\nmax_power_w = "fifty"\n', "[laser] max_power_w must be a number"),
    ("[defaults]\nspeed_mms = 100\n", "did you mean speed_mm_s?"),
    ("[field]\nsize_mm = \n", "not valid TOML"),
    ('[field]\ncorrection = "missing.cor"\n', "[field] correction"),
])
def test_show_bad_profile_one_line(here, capsys, text, piece):
    (here / "bad.toml").write_text(text)
    line = one_line_error(capsys, ["machine", "show", "--machine", "bad.toml"])
    assert line.startswith("galvoscan machine show: error: bad.toml")
    assert piece in line


def test_show_bad_default_file_one_line(here, capsys):
    (here / "galvoscan.toml").write_text("[lazer]\n")
    line = one_line_error(capsys, ["machine", "show"])
    assert "galvoscan.toml" in line and "did you mean [laser]?" in line


def test_show_missing_file_one_line(here, capsys):
    line = one_line_error(capsys, ["machine", "show", "--machine", "nope.toml"])
    assert "nope.toml" in line and "no such file" in line


def test_show_folder_one_line(here, capsys):
    (here / "box").mkdir()
    assert "is a folder" in one_line_error(capsys, ["machine", "show", "--machine", "box"])


def test_bad_profile_in_a_real_process(here):
    """The whole program: exit status 2 (refused before any work) and exactly one line on
    stderr, naming the command."""
    (here / "bad.toml").write_bytes(b"[laser]\nspot_mm = 0\n")
    done = subprocess.run([sys.executable, "-m", "galvoscan.cli", "machine", "show",
                           "--machine", "bad.toml"], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 2
    assert done.stderr.splitlines() == [
        "galvoscan machine show: error: bad.toml: [laser] spot_mm must be a number from "
        "0.001 to 10 (mm), not 0"]
    assert done.stdout == ""


# --- the helper the job commands use ---------------------------------------------------------

def _parser():
    parser = argparse.ArgumentParser()
    add_machine_option(parser)
    return parser


def test_profile_from_a_named_file(here, capsys):
    (here / "m.toml").write_text("[field]\nsize_mm = 175\n")
    profile = profile_from(_parser().parse_args(["--machine", "m.toml"]))
    assert profile.field.size_mm == 175
    assert capsys.readouterr().err == ""


def test_profile_from_the_default_file(here, capsys):
    (here / "galvoscan.toml").write_text("[laser]\nmax_power_w = 50\n")
    assert profile_from(_parser().parse_args([])).laser.max_power_w == 50
    assert capsys.readouterr().err == ""


def test_profile_from_nothing_is_the_default_with_a_note(here, capsys):
    assert profile_from(_parser().parse_args([])) == default_profile()
    assert capsys.readouterr().err.count("\n") == 1


def test_profile_from_a_bad_file_is_a_cli_error(here):
    (here / "m.toml").write_text("[galvo]\njump_delay_us = 70000\n")
    with pytest.raises(CLIError) as error:
        profile_from(_parser().parse_args(["--machine", "m.toml"]))
    assert error.value.code == 2
    assert str(error.value).startswith("galvoscan: error: m.toml: [galvo] jump_delay_us")


@pytest.mark.parametrize("text, key", [
    ("laser_on_delay_us = -20", "laser_on_delay_us"),        # beyond the board's reach
    ("laser_off_delay_us = 1024", "laser_off_delay_us"),
    ("mark_delay_us = -1", "mark_delay_us"),
    ("polygon_delay_us = 4096", "polygon_delay_us"),
    ("polygon_delay_us = \"100\"", "polygon_delay_us"),
    ("polygon_scaled = 1", "polygon_scaled"),
    ("mark_delay_us = nan", "mark_delay_us"),
])
def test_bad_delays_in_a_profile_are_one_line_errors(here, text, key):
    (here / "m.toml").write_text(f"[galvo]\n{text}\n")
    with pytest.raises(CLIError) as error:
        profile_from(_parser().parse_args(["--machine", "m.toml"]))
    message = str(error.value)
    assert message.startswith(f"galvoscan: error: m.toml: [galvo] {key}")
    assert "\n" not in message and "Traceback" not in message


def test_machine_needs_a_subcommand(capsys):
    with pytest.raises(SystemExit) as exit:
        main(["machine"])
    assert exit.value.code == 2
