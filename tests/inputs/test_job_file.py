"""Vector job files and ``galvoscan sim --mode vector``."""

import csv
import json
import math

import pytest
from hypothesis import given, settings, strategies as st

from galvoscan.cli import main
from galvoscan.inputs.job_file import JobError, parse_job

from sim_board import quick_replay_job
from vector_model import job_model


def test_parse_job():
    text = "# a corner\njump 100 200\n\nMARK 0x10 20   # hex and upper case\n"
    assert parse_job(text) == [("jump", 100, 200), ("mark", 16, 20)]


@pytest.mark.parametrize("text, message", [
    ("move 1 2", "line 1: unknown command 'move'"),
    ("jump 1", "jump takes X and Y, not 1 values"),
    ("jump 1 2 3", "not 3 values"),
    ("mark 1 y", "'y' is not an integer"),
    ("jump 0 65536", "65536 is outside 0 … 65535"),
    ("jump -1 0", "-1 is outside"),
    ("# nothing\n\n", "no segments"),
])
def test_bad_jobs_name_the_line(text, message):
    with pytest.raises(JobError, match=message):
        parse_job(text)


@settings(max_examples=300, deadline=None)
@given(st.text(max_size=60))
def test_any_text_parses_or_says_why(text):
    try:
        segments = parse_job(text)
    except JobError as error:
        assert str(error).startswith("job")
    else:
        assert segments and all(op in ("jump", "mark") and 0 <= x <= 0xFFFF and 0 <= y <= 0xFFFF
                                for op, x, y in segments)


def test_sim_vector_job(tmp_path, capsys):
    job = tmp_path / "corner.job"
    job.write_text("jump 30000 30000\nmark 30300 30000\nmark 30300 30200\njump 32768 32768\n")
    points_csv = tmp_path / "points.csv"
    with quick_replay_job():
        code = main(["sim", "--mode", "vector", "--job", str(job), "--prr", "50",
                     "--pulses-per-point", "2", "--points-csv", str(points_csv), "--json"])
    report = json.loads(capsys.readouterr().out)
    assert code == 0
    assert report["pulses_per_marked_point"] == [2]
    # The points the command reports are the model's, pulses included (the first row is the
    # park position before the run).
    with points_csv.open() as f:
        rows = list(csv.DictReader(f))
    got = [((int(r["x"]), int(r["y"])), int(r["pulses"])) for r in rows][1:]
    expected = job_model([("jump", 30000, 30000), ("mark", 30300, 30000),
                          ("mark", 30300, 30200), ("jump", 32768, 32768)], 60, 2)
    assert got == expected
    assert report["marked_points"] == sum(1 for _, n in expected if n)


@pytest.mark.parametrize("argv, message", [
    (["--mode", "vector"], "needs --job FILE"),
    (["--mode", "vector", "--job", "/nonexistent.job"], "cannot read the job"),
    (["--job", "x.job", "--points", "3"], "--job is for --mode vector"),
    ([], "the spiral needs --points"),
])
def test_sim_rejects_bad_arguments(argv, message):
    with pytest.raises(SystemExit, match=message):
        main(["sim"] + argv)


def test_sim_vector_rejects_a_bad_job(tmp_path):
    job = tmp_path / "bad.job"
    job.write_text("jump 1 2\nzap 3 4\n")
    with pytest.raises(SystemExit, match="line 2: unknown command 'zap'"):
        main(["sim", "--mode", "vector", "--job", str(job)])


def test_a_job_files_plan_says_its_jumps(tmp_path, capsys):
    """A .job is marked as it is: its one pass's jumps in the plan are its own (they were
    said as 0.0 mm beside a total of tens of mm)."""
    job = tmp_path / "c.job"
    job.write_text("jump 30000 30000\nmark 31000 30000\njump 33000 33000\nmark 33000 34000\n")
    assert main(["mark", str(job), "--estimate"]) == 0
    out = capsys.readouterr().out
    # From the centre (32768) to (30000, 30000), then (31000, 30000) to (33000, 33000).
    units_per_mm = 65536 / 110
    jumps = (math.hypot(2768, 2768) + math.hypot(2000, 3000)) / units_per_mm
    assert f"one pass: jumps {jumps:.1f} mm in the drawing's order, {jumps:.1f} mm as " \
           f"ordered" in out
