"""Job files (galvoscan/cli/jobfile.py, `mark JOB.toml`, `mark … --save JOB.toml`): a job saved
from the command line plans as the command line does and marks the same wires; a file with a
typo, a value out of range or a wrong type gets one line naming the key, and random files get
nothing else."""

import json

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from galvoscan.cli import main
from galvoscan.cli.args import CLIError
from galvoscan.cli.jobfile import SECTIONS, load_job_file

from sim_board import VECTOR_BOARD, quick_sim_board


SVG = """<svg xmlns="http://www.w3.org/2000/svg" width="12mm" height="8mm" viewBox="0 0 12 8">
 <rect x="1" y="1" width="10" height="6" fill="none" stroke="#ff0000"/>
 <circle cx="6" cy="4" r="2" fill="none" stroke="#0000ff"/></svg>"""

#: A job with one of everything: a drawing with a layer, text, a code, a photo.
COMMAND = ["--offset=2,3", "--rotate", "10", "--hatch", "0.1,45", "--hatch", "0.1,135",
           "--layer", "#0000ff", "speed=503.5", "power=40", "hatch=0.2,0",
           "--text", "SN {serial:04d}", "--font", "hershey", "--height", "2",
           "--text-at=-20,-12", "--code", "qr", "--data", "LOT-7", "--size", "5",
           "--code-at=20,-12", "--image", "dots.png", "--width", "3", "--image-at=0,-20",
           "--dither", "ordered", "--speed", "1007.1", "--power", "25"]


@pytest.fixture
def job_folder(tmp_path, monkeypatch):
    from PIL import Image
    (tmp_path / "logo.svg").write_text(SVG)
    Image.linear_gradient("L").resize((30, 20)).save(tmp_path / "dots.png")
    (tmp_path / "machine.toml").write_text("[laser]\nspot_mm = 0.1\n")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def _estimate(capsys, *args):
    assert main(["mark", *args, "--machine", "machine.toml", "--estimate", "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_saved_job_plans_as_its_command_line(job_folder, capsys):
    """The job saved, run from another folder (paths are the file's), plans to the same
    segments, lengths, layers and time; saved again it is the same file."""
    (job_folder / "jobs").mkdir()
    direct = _estimate(capsys, "logo.svg", *COMMAND, "--save", "jobs/one.toml")
    saved = (job_folder / "jobs" / "one.toml").read_text()
    assert 'file = "../logo.svg"' in saved and 'match = "#0000ff"' in saved
    again = _estimate(capsys, "jobs/one.toml")
    for key in ("segments", "mark_mm", "jump_mm", "bounds_mm", "estimate_s"):
        assert again[key] == direct[key], key
    assert [layer["match"] for layer in again["layers"]] == ["#0000ff", "the rest"]
    assert again["layers"][0]["power_percent"] == 40
    assert again["layers"][1]["power_percent"] == 25
    _estimate(capsys, "jobs/one.toml", "--save", "jobs/two.toml")
    assert (job_folder / "jobs" / "two.toml").read_text().split("\n", 1)[1] == \
        saved.split("\n", 1)[1]
    # A run's own --speed and --power still win over the file's.
    faster = _estimate(capsys, "jobs/one.toml", "--power", "60")
    assert faster["layers"][1]["power_percent"] == 60


@pytest.mark.parametrize("text, words", [
    ("[job]\nsped = 100\n[[text]]\ntext = 'A'\n",
     r"\[job\]: 'sped' is not a setting of \[job\] \(did you mean 'speed'\?\)"),
    ("[jobs]\nspeed = 100\n", r"\[jobs\] is not a section of a job file \(did you mean \[job\]\?\)"),
    ("[job]\nspeed = 0\n[[text]]\ntext = 'A'\n", r"\[job\]\.speed: speed must be from 0\.1"),
    ("[[text]]\ntext = 'A'\nalign = 'middle'\n", r"\[\[text\]\] 1\.align must be one of left"),
    ("[[drawing]]\nfile = 'logo.svg'\noffset = 'left'\n", r"offset must be X,Y in mm"),
    ("[[drawing]]\nfile = 'logo.svg'\noffset = [1, true]\n", r"must be numbers"),
    ("[[image]]\nfile = 'dots.png'\nwidth = 3\none_way = 1\n", r"one_way must be true or false"),
    ("[[layer]]\nspeed = 100\n", r"\[\[layer\]\] 1: a layer needs match"),
    ("[[layer]]\nmatch = 'x'\nspeeed = 100\n", r"'speeed' is not a layer setting"),
    ("[[code]]\nkind = 'qr'\ndata = 'x'\nsize = 5\nlayer = 3\n", r"layer must be a layer's name"),
    ("[job]\nspeed = 100\n", r"nothing to mark"),
    ("speed = = 1", r"not valid TOML"),
    ("[[drawing]]\nfile = 'missing.svg'\n", r"missing.svg: no such file"),
    ("[[text]]\ntext = 'A'\nlayer = 'Nope'\n", r"put on layer 'Nope', which is not one of"),
    ("[job]\nport = '/dev/ttyUSB0'\n[[text]]\ntext = 'A'\n",
     r"'port' belongs to a run, not to the job: give --port on the command line"),
    ("[[code]]\nkind = 'qr'\ndata = 'x'\n", r"\[\[code\]\] 1: --code needs --data TEXT and --size"),
    ("[[image]]\nfile = 'nowhere.png'\nwidth = 3\n", r"\[\[image\]\] 1: .*nowhere.png: no such file"),
    ("[[drawing]]\nfile = 'gone.svg'\n", r"bad.toml \[\[drawing\]\] 1: .*gone.svg: no such file"),
    ("[[drawing]]\n", r"\[\[drawing\]\] 1 needs file = … \(the SVG, DXF or .job"),
    ("[[image]]\nwidth = 5\n", r"\[\[image\]\] 1 needs file"),
    ("[[text]]\nheight = 3\n", r"\[\[text\]\] 1 needs text = … \(the text to mark\)"),
    ("[[code]]\ndata = 'x'\n", r"\[\[code\]\] 1 needs kind"),
])
def test_bad_job_files_are_one_line(job_folder, capsys, text, words):
    (job_folder / "bad.toml").write_text(text)
    with pytest.raises(SystemExit) as stopped:
        main(["mark", "bad.toml", "--estimate"])
    import re
    message = str(stopped.value.code if not isinstance(stopped.value, CLIError)
                  else stopped.value)
    message += capsys.readouterr().err
    assert re.search(words, message), message
    assert "Traceback" not in message


def test_the_files_options_stay_in_the_file(job_folder, capsys):
    (job_folder / "j.toml").write_text("[[text]]\ntext = 'A'\n")
    with pytest.raises(SystemExit, match="--height is the job file's: put it in j.toml"):
        main(["mark", "j.toml", "--height", "3", "--estimate"])
    # Its fill too: a run may change only the speed, power, PRR and passes.
    with pytest.raises(SystemExit, match="--hatch is the job file's"):
        main(["mark", "j.toml", "--hatch", "0.2", "--estimate"])
    with pytest.raises(SystemExit, match="--layer is the job file's"):
        main(["mark", "j.toml", "--layer", "Logo", "speed=500", "--estimate"])
    # --save makes the folder it is asked to write in.
    assert main(["mark", "j.toml", "--save", "new/folder/k.toml", "--estimate"]) == 0
    assert (job_folder / "new" / "folder" / "k.toml").exists()
    (job_folder / "x.job").write_text("J 0 0\n")
    with pytest.raises(SystemExit, match="a .job is in galvo units .* no job to --save"):
        main(["mark", "x.job", "--save", "x.toml", "--estimate"])
    with pytest.raises(SystemExit):
        main(["mark", "j.toml", "--save", "j.json", "--estimate"])
    assert "a job file ends in .toml, not 'j.json'" in capsys.readouterr().err


_keys = st.sampled_from(sorted({k for keys in SECTIONS.values() for k in keys} | {"match"}))
_scalars = st.one_of(st.integers(-10 ** 9, 10 ** 9), st.floats(allow_nan=False), st.booleans(),
                     st.text(max_size=12), st.sampled_from(["0.05,45", "qr", "hershey",
                                                              "dots.png", "logo.svg", "#ff0000"]))
_values = st.one_of(_scalars, st.lists(_scalars, max_size=3))
_tables = st.dictionaries(st.one_of(_keys, st.text(min_size=1, max_size=8)), _values,
                          max_size=5)
_documents = st.dictionaries(
    st.one_of(st.sampled_from([*SECTIONS, "layer"]), st.text(min_size=1, max_size=8)),
    st.one_of(_tables, st.lists(_tables, min_size=1, max_size=3)), max_size=4)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(document=_documents)
def test_random_job_files_load_or_are_one_line(job_folder, document):
    """Any TOML document: it loads, or a CLIError of one line (nothing else escapes)."""
    import tomli_w
    path = job_folder / "random.toml"
    try:
        path.write_text(tomli_w.dumps(document))
    except (TypeError, ValueError):
        return                              # not a TOML document (tomli_w refuses it)
    try:
        load_job_file(path)
    except CLIError as error:
        assert "\n" not in str(error)


@pytest.mark.slow
def test_a_job_file_marks_the_wires_its_command_line_does(job_folder, capsys):
    """The saved job on the simulated board: the same marks off the wires as the command
    line's own run."""
    small = ["--text", "AB", "--font", "hershey", "--height", "2", "--code", "qr", "--data",
             "7", "--size", "3", "--code-at=8,0", "--speed", "1007.1", "--prr", "50"]
    runs = []
    with quick_sim_board(**VECTOR_BOARD):
        for args in (["logo.svg", *small, "--save", "small.toml"], ["small.toml"]):
            assert main(["mark", *args, "--machine", "machine.toml", "--sim", "--timeout",
                         "600", "--json"]) == 0
            runs.append(json.loads(capsys.readouterr().out.strip().splitlines()[-1]))
    assert runs[0]["marks"] == runs[1]["marks"] and len(runs[0]["marks"]) > 100
    assert runs[1]["errors"] == runs[1]["underruns"] == 0


def test_the_readmes_plate_plans(tmp_path, monkeypatch, capsys):
    """docs/marking/plate.toml, the marking page's picture: it plans, in its three layers, the
    serial counter left alone by a plan."""
    from pathlib import Path
    plate = Path(__file__).resolve().parents[2] / "docs" / "marking" / "plate.toml"
    monkeypatch.chdir(tmp_path)
    assert main(["mark", str(plate), "--estimate", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert [layer["match"] for layer in record["layers"]] == ["#d62728", "Text", "the rest"]
    assert list(tmp_path.iterdir()) == []
