"""Serial numbers (galvoscan/inputs/serial.py; `{serial}` in `mark --text` and `--data`): the
counter file beside the profile, read, refused when damaged, advanced only for a part marked
to its end, through the real serial link into a served simulated board."""

import json
import signal
import subprocess
import sys

import pytest

from galvoscan.cli import main
from galvoscan.geometry.field import PlanError
from galvoscan.inputs.serial import counter_path, load_counter, uses_serial

from cli_processes import BOARD, CLIENT      # a command through a served simulated board


def test_the_counter_beside_the_profile(tmp_path):
    profile = tmp_path / "station.toml"
    assert counter_path(profile) == tmp_path / "station.serial.toml"
    counter = load_counter(profile)
    assert (counter.next, counter.step) == (1, 1) and not counter.path.exists()
    counter = load_counter(profile, start=40, step=5)
    assert counter.numbers(3) == [40, 45, 50]
    counter.advance()
    again = load_counter(profile)
    assert (again.next, again.step) == (45, 5)
    assert not list(tmp_path.glob("*.new"))          # written whole, then moved over


@pytest.mark.parametrize("text, words", [
    ("next = 'seven'\n", "is not a whole number"),
    ("next = -1\n", "is not a whole number"),
    ("next = 3\ncolour = 1\n", "unknown key 'colour'"),
    ("next = [\n", "not a serial counter"),
])
def test_a_damaged_counter_is_one_line(tmp_path, text, words):
    profile = tmp_path / "station.toml"
    counter_path(profile).write_text(text)
    with pytest.raises(PlanError, match=words):
        load_counter(profile)


def test_which_texts_hold_a_serial():
    assert uses_serial("SN {serial:04d}") and uses_serial(None, "{serial}")
    assert not uses_serial("{date:%Y}", None) and not uses_serial("{{serial}}")


def test_serials_in_the_plan_and_their_refusals(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["mark", "--text", "SN {serial:04d}", "--serial-start", "41", "--repeat", "3",
                 "--estimate"]) == 0
    out = capsys.readouterr().out
    assert "serials 41 … 43" in out
    assert not (tmp_path / "galvoscan.serial.toml").exists()     # a plan takes no number
    with pytest.raises(SystemExit, match="are for a {serial} field"):
        main(["mark", "--text", "SN", "--serial-start", "4", "--estimate"])
    with pytest.raises(SystemExit, match="an image holds one part"):
        main(["store", "--text", "SN {serial}", "--repeat", "2", "-o", "x.img"])


@pytest.mark.slow
def test_each_part_marked_on_a_board_takes_its_number(tmp_path):
    """Two parts marked through the serial link into a served simulated board: each says its
    serial, and the counter beside the profile has advanced by two."""
    profile = tmp_path / "station.toml"
    profile.write_text("[laser]\nspot_mm = 0.2\n[galvo]\njump_delay_us = 100\n")
    mark = subprocess.Popen(
        [sys.executable, "-c", CLIENT, "mark", "--text", "{serial}", "--font", "hershey",
         "--height", "0.5", "--serial-start", "7", "--repeat", "2", "--speed", "2000",
         "--machine", str(profile), "--timeout", "120"],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    board = subprocess.Popen([sys.executable, "-c", BOARD, "board", "--sim"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        port = board.stdout.readline().rsplit(" on ", 1)[1].strip()
        out, err = mark.communicate(port + "\n", timeout=600)
        assert mark.returncode == 0, err
        assert "part 1 of 2, serial 7: marked" in out and "part 2 of 2, serial 8: marked" in out
        assert load_counter(profile).next == 9
    finally:
        if mark.poll() is None:
            mark.kill()
            mark.communicate()
        board.send_signal(signal.SIGINT)
        board.communicate(timeout=600)


def test_a_counter_that_cannot_be_kept_is_one_line(tmp_path):
    """A counter whose folder is gone (or cannot be written) is refused before a part is
    marked; one that fails after a part is marked says the number to go on from."""
    from galvoscan.inputs.serial import SerialCounter
    lost = SerialCounter(path=tmp_path / "gone" / "station.serial.toml", next=41)
    with pytest.raises(PlanError, match="the serial counter cannot be written .*nothing was "
                                        "sent"):
        lost.check_writable()
    with pytest.raises(PlanError, match="the part was marked, but the counter could not be "
                                        "written .*--serial-start 42"):
        lost.advance()
    kept = SerialCounter(path=tmp_path / "station.serial.toml", next=41)
    kept.check_writable()
    assert not list(tmp_path.iterdir())     # the check leaves nothing behind


def test_repeated_parts_are_planned_once_unless_numbered(tmp_path, monkeypatch, capsys):
    """--repeat of the same part plans it once (100,000 plans took minutes and a gigabyte);
    numbered parts are each planned with their number. The time of all parts is said."""
    import galvoscan.cli.mark as mark
    monkeypatch.chdir(tmp_path)
    planned = []
    plan = mark._plan
    monkeypatch.setattr(mark, "_plan", lambda *a, **k: planned.append(a) or plan(*a, **k))
    assert main(["mark", "--text", "AB", "--font", "hershey", "--repeat", "5000",
                 "--estimate", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert len(planned) == 1 and record["parts"] == 5000
    assert record["estimate_all_parts_s"] == pytest.approx(5000 * record["estimate_s"], rel=1e-6)
    planned.clear()
    assert main(["mark", "--text", "{serial}", "--font", "hershey", "--repeat", "4",
                 "--estimate", "--json"]) == 0
    assert len(planned) == 4


@pytest.mark.slow
def test_sim_json_of_repeated_parts_is_every_parts(tmp_path, monkeypatch, capsys):
    """--sim --json of two parts: segments, jumps, length and counters are both parts' (twice
    one part's), as the marks and pulses off the wires are."""
    from sim_board import VECTOR_BOARD, quick_sim_board
    monkeypatch.chdir(tmp_path)
    args = ["mark", "--text", "AB", "--font", "hershey", "--height", "1", "--speed", "1007.1",
            "--sim", "--timeout", "600", "--json"]
    runs = []
    with quick_sim_board(**VECTOR_BOARD):
        for repeat in ("1", "2"):
            assert main([*args, "--repeat", repeat]) == 0
            runs.append(json.loads(capsys.readouterr().out.strip().splitlines()[-1]))
    one, both = runs
    for key in ("segments", "jumps", "pulses"):
        assert both[key] == 2 * one[key], key
    assert both["mark_length_mm"] == pytest.approx(2 * one["mark_length_mm"], abs=1e-3)
    assert len(both["marks"]) == 2 * len(one["marks"]) and both["parts"] == 2
    assert both["errors"] == both["underruns"] == 0
