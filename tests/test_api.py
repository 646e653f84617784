"""The Python API (``galvoscan/api.py``): its runnable example marks what geometry says it
must, and a job built without the command line is refused with the command line's lines."""

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

from galvoscan import api
from galvoscan.cli import main
from galvoscan.profile.machine import default_profile
from galvoscan.settings.schema import SettingError

EXAMPLE = Path(__file__).parent.parent / "docs" / "examples" / "first_job.py"


def test_first_job_example():
    """The example's 10 mm square centred at (5, -3) mm, at 1000 mm/s: 40 mm of line, its
    marks off the wires spanning 0 … 10 mm by -8 … 2 mm (to a galvo unit), and, the laser
    pulsing all along it at the profile's PRR, as many pulses as 40 ms of it (to 5 %)."""
    done = subprocess.run([sys.executable, str(EXAMPLE)], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr
    out = done.stdout
    planned = re.search(r"planned: (\d+) segments, ([\d.]+) mm marked, estimated ([\d.]+) s",
                        out)
    assert planned, out
    assert float(planned[2]) == pytest.approx(4 * 10.0, abs=0.01)
    assert float(planned[3]) >= 4 * 10.0 / 1000        # at least the marking itself
    marked = re.search(r"marked: (\d+) segments, (\d+) pulses, as planned", out)
    assert marked, out
    prr_hz = default_profile().defaults.prr_khz * 1e3
    assert int(marked[2]) == pytest.approx(40e-3 * prr_hz, rel=0.05)
    bounds = re.search(r"marks: x (\S+) … (\S+) mm, y (\S+) … (\S+) mm", out)
    assert bounds, out
    unit_mm = default_profile().field.size_mm / 65536
    assert [float(v) for v in bounds.groups()] == pytest.approx([0, 10, -8, 2],
                                                                abs=2 * unit_mm)


def test_job_settings_refused_as_the_command_line_does():
    drawing = api.Text("A", font="hershey")
    with pytest.raises(SettingError, match=r"^speed must be from 0\.1 to 100e3, not 0\.0$"):
        api.Job(texts=[drawing], speed_mm_s=0.0)
    with pytest.raises(SettingError, match=r"^passes must be an integer, not 1\.5$"):
        api.Job(texts=[drawing], passes=1.5)
    with pytest.raises(api.PlanError, match="something to mark"):
        api.plan(api.Job())


def test_text_and_code_planned_without_the_command_line():
    """A Hershey text 5 mm high and a 10 mm QR code, planned: inside their places, the
    serial filled in."""
    job = api.Job(texts=[api.Text("SN {serial:03d}", height_mm=5, at_mm=(-20, 10),
                                  font="hershey")],
                  codes=[api.Code("qr", "{serial}", 10, at_mm=(15, -15))])
    plan = api.plan(job, serial=7)
    xmin, ymin, xmax, ymax = plan.vector_job.bounds_mm
    assert xmin == pytest.approx(-20, abs=1) and ymax >= 10 + 4      # text from (-20, 10) up
    assert xmax == pytest.approx(20, abs=0.5) and ymin == pytest.approx(-20, abs=0.5)
    assert plan.estimate_s > 0 and plan.mark_mm > 0
    with pytest.raises(api.PlanError, match=r"\{nope\} is not a field"):
        api.plan(api.Job(texts=[api.Text("{nope}")]))


@pytest.mark.parametrize("layer, message", [
    (api.Layer("red", delays_us=(("laser_on_delay", 5000),)),
     r"^layer 1 \('red'\): laser_on_delay: laser on delay must be from -19 to 1023, not "
     r"5000$"),
    (api.Layer("red", delays_us=(("bogus", 3),)),
     r"^layer 1 \('red'\): 'bogus' is not a delay a layer may set \(the delays: "),
    (api.Layer("red", outline="no"), r"^layer 1 .*: outline: .*yes or no, not 'no'$"),
    (api.Layer("red", speed_mm_s="fast"), r"^layer 1 .*: speed: speed must be a number"),
    (api.Layer("red", hatch="0.05,45"), r"^layer 1 .*: hatch must be a tuple of its sets"),
    (api.Layer("red", pulses_per_point=0), r"^layer 1 .*: pulses: .*from 1 to 255, not 0$"),
])
def test_a_programs_layer_is_held_to_the_layer_keys(layer, message, tmp_path):
    """A :class:`~galvoscan.api.Layer` a program makes is checked as a ``[[layer]]`` table
    is, before anything is planned: a delay out of its register's range, a register that is
    no delay, a text where a yes or no belongs (``outline="no"`` marked the outlines) are
    one line, not registers sent to a board or a TypeError."""
    drawing = tmp_path / "red.svg"
    drawing.write_text('<svg xmlns="http://www.w3.org/2000/svg" width="10mm" height="10mm" '
                       'viewBox="0 0 10 10"><rect width="10" height="10" fill="none" '
                       'stroke="red"/></svg>')
    job = api.Job(drawings=[api.Drawing(str(drawing))], layers=[layer])
    with pytest.raises(ValueError, match=message):
        api.plan(job)
    good = api.Layer("red", delays_us=(("laser_on_delay", 50),), outline=False,
                     hatch=api.layer_from_table({"match": "red", "hatch": "0.1,45"}).hatch)
    plan = api.plan(api.Job(drawings=[api.Drawing(str(drawing))], layers=[good]))
    assert ("laser_on_delay", 50) in plan.vector_job.layers[0].settings.delays_us


def test_a_layer_from_a_table_without_the_command_line():
    """A ``[[layer]]`` table, as a program gives it, is read by the API with the job file's
    key table (the command line not imported) and refused with its lines; the layer plans."""
    code = ("import sys\n"
            "from galvoscan import api\n"
            "layer = api.layer_from_table({'match': '#F00', 'speed': 500, 'outline': False,\n"
            "                              'hatch': ['0.1,0', '0.1,90'], 'laser_on_delay': -10})\n"
            "print(repr(layer))\n"
            "print(sorted(m for m in sys.modules if m.startswith('galvoscan.cli')))\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr
    layer, cli = done.stdout.splitlines()
    assert cli == "[]"
    assert layer == repr(api.Layer("#ff0000", speed_mm_s=500.0, outline=False,
                                   hatch=(api.HatchSet(0.1), api.HatchSet(0.1, 90.0)),
                                   delays_us=(("laser_on_delay", -10),)))
    with pytest.raises(ValueError, match=r"^layer 2 \('red'\): pulses: pulses per point must "
                                         r"be from 1 to 255, not 0$"):
        api.layer_from_table({"match": "red", "pulses": 0}, "layer 2")
    with pytest.raises(ValueError, match=r"^\[\[layer\]\] \('red'\): 'sped' is not a layer "
                                         r"setting \(did you mean 'speed'\?\)"):
        api.layer_from_table({"match": "red", "sped": 500})
    with pytest.raises(ValueError, match=r"hatch_lines: must be serpentine, oneway, joined, "
                                         r"not 'zigzag'$"):
        api.layer_from_table({"match": "red", "hatch_lines": "zigzag"})
    text = api.Text("I", font="hershey", height_mm=2, layer="Slow")
    plan = api.plan(api.Job(texts=[text], layers=[api.layer_from_table(
        {"match": "Slow", "speed": 503.5, "pulses": 2})]))
    (only,) = plan.vector_job.layers
    assert only.settings.speed_mm_s == 503.5 and only.job.pitch.pulses_per_point == 2


def test_wobble_from_the_job_else_the_profile():
    """A job's wobble is its own (a circle when only across is given), else the profile's;
    one that would reach past the field is refused in one line."""
    text = api.Text("I", font="hershey", height_mm=2)
    plan = api.plan(api.Job(texts=[text], wobble_um=100, wobble_hz=2000))
    unit_um = default_profile().field.size_mm / 65536 * 1000
    registers = plan.vector_job.registers
    assert plan.wobbles
    assert registers["wob_across"] == pytest.approx(100 / unit_um, abs=1)
    assert registers["wob_along"] == registers["wob_across"]
    assert registers["wob_freq"] == 2000
    assert not api.plan(api.Job(texts=[text])).wobbles        # the default profile: none
    edge = api.Text("I", font="hershey", height_mm=2, at_mm=(54.5, 0))
    with pytest.raises(api.PlanError, match="reaches past the field"):
        api.plan(api.Job(texts=[edge], wobble_um=2000))


def test_mark_is_the_api(tmp_path, capsys, monkeypatch):
    """``mark --estimate --json`` of a text and a code plans what the API plans for the same
    job: the same segments, length, bounds and time."""
    monkeypatch.chdir(tmp_path)                          # no machine profile: the default
    assert main(["mark", "--text", "AB", "--font", "hershey", "--height", "4",
                 "--text-at=-10,5", "--code", "datamatrix", "--data", "7", "--size", "6",
                 "--code-at", "12,-8", "--speed", "800", "--passes", "2", "--estimate",
                 "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    plan = api.plan(api.Job(texts=[api.Text("AB", font="hershey", height_mm=4,
                                            at_mm=(-10, 5))],
                            codes=[api.Code("datamatrix", "7", 6, at_mm=(12, -8))],
                            speed_mm_s=800, passes=2))
    assert record["segments"] == len(plan.segments)
    assert record["mark_mm"] == pytest.approx(plan.mark_mm, abs=1e-3)
    assert record["bounds_mm"] == pytest.approx(list(plan.vector_job.bounds_mm), abs=1e-3)
    assert record["estimate_s"] == pytest.approx(plan.estimate_s, abs=1e-6)


def test_parts_on_a_line_through_the_api(tmp_path):
    """`api.Job(wait_input="part", set_output="done")` on a simulated board with I/O in the
    queue: refused in one line, nothing sent, while the board has no part sensor (it would
    wait for good); with one, marked once a part came, and the "done" pulse whole in
    `board.io_changes` (rise and fall, 2 ms apart) when `api.run` returns."""
    from sim_board import IO_BOARD
    board = api.SimulatedBoard(backend="compiled", **IO_BOARD)
    line = tmp_path / "line.svg"
    line.write_text('<svg xmlns="http://www.w3.org/2000/svg" width="4mm" height="1mm" '
                    'viewBox="0 0 4 1"><path d="M0 0.5 H4" stroke="#000" fill="none"/></svg>')
    job = api.Job(drawings=[api.Drawing(str(line))], wait_input="part", set_output="done",
                  output_pulse_ms=2)
    plan = api.plan(job)
    assert plan.io.line().startswith("I/O: each part waits for input part")
    sent = len(board.bytes_in)
    with pytest.raises(ValueError, match="the simulated board has no part sensor") as refused:
        api.run(plan, board)
    assert "\n" not in str(refused.value) and len(board.bytes_in) == sent
    board.parts_arrive(first_s=2e-3, every_s=10e-3, seen_s=1e-3)
    report = api.run(plan, board)
    assert report.clean and report.pulses > 0
    # The marks began after a part came (the sensor's own description: one every 10 ms).
    sensor = board.part_sensor
    first = board.pulses[0] / board.clk_freq - sensor.start_s - sensor.first_s
    assert first >= 0 and first % sensor.every_s < 1e-3
    (rise, high), (fall, low) = board.io_changes
    assert (high, low) == (1, 0) and rise > board.pulses[-1]
    assert abs((fall - rise) / board.clk_freq - 2e-3) <= 20e-6
