"""SkyWriting against the delays and against nothing (galvoscan/analysis/sky.py, `galvoscan
analyze --sky`): an L marked on the simulated board, its frames through the galvo model. The
docs page's table is a fresh run's (generated, never written by hand), its figure is there and
the command writes one, and what its prose says of the runs and of the study's set-up holds."""

import inspect
import json
from pathlib import Path
import re

import pytest

from galvoscan.analysis.galvo import GalvoModel
from galvoscan.analysis.sky import LONG_RUNS, markdown_table, model_timelag_us, sky_job_dose
from galvoscan.cli import main
from galvoscan.profile.machine import default_profile
from galvoscan.settings.sky import NPOST_SHARE, NPREV_SHARE


DOCS = Path(__file__).parents[2] / "docs"
PAGE = (DOCS / "user" / "skywriting.md").read_text(encoding="utf-8")
TEXT = " ".join(PAGE.split())


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    """`galvoscan analyze --sky --json`'s rows, and the folder it wrote its figure in."""
    out = tmp_path_factory.mktemp("sky")
    capture = pytest.MonkeyPatch()
    import io
    import sys
    printed = io.StringIO()
    capture.setattr(sys, "stdout", printed)
    try:
        assert main(["analyze", "--sky", "--json", "--out", str(out)]) == 0
    finally:
        capture.undo()
    rows = json.loads(printed.getvalue())
    return rows, {r["run"]: r for r in rows}, out


def test_the_pages_table_is_a_fresh_run(study):
    rows, _, out = study
    assert markdown_table(rows) in PAGE
    assert (out / "sky.png").stat().st_size > 10_000


def test_what_the_page_says_of_the_runs_holds(study):
    _, rows, _ = study
    nothing, delays = rows["nothing"], rows["delays"]
    sky, long = rows["SkyWriting"], rows["SkyWriting, long runs"]
    # "Without delays the line starts with a burnt dot and the corner is rounded."
    assert nothing["start_peak"] > 2 and nothing["off_path_um"] > 5
    # "The delays even the start but not the corner, which they round as much."
    assert delays["start_peak"] <= 1.2 and delays["off_path_um"] == nothing["off_path_um"]
    # "SkyWriting marks the corner sharp (within a µm) and the start even."
    assert sky["off_path_um"] < 1 and long["off_path_um"] < 1 and sky["start_peak"] <= 1.2
    # Short runs: braking at the corner and the end; long runs: within 20 %.
    assert sky["corner_peak"] > 1.2 and sky["end_peak"] > 1.2
    assert max(long["start_peak"], long["corner_peak"], long["end_peak"]) <= 1.2
    # "SkyWriting's runs and the corner's jump cost that much more."
    assert nothing["estimate_ms"] < sky["estimate_ms"] < long["estimate_ms"]
    # The laser delays SkyWriting sets: Timelag, the galvo model's tracking error.
    timelag = model_timelag_us(GalvoModel.from_step_times())
    assert sky["laser_on_delay_us"] == sky["laser_off_delay_us"] == timelag


def test_the_pages_set_up_is_the_studys():
    length = inspect.signature(sky_job_dose).parameters["length_mm"].default
    from galvoscan.cli import parser
    args = parser().parse_args(["analyze", "--sky"])        # what `analyze --sky` runs at
    assert f"an L ({length:g} mm along X, then {length:g} mm along Y, at " \
           f"{args.mark_speed:,.0f} mm/s)" in TEXT
    assert f"at spot scale (a {args.spot * 1000:g} µm spot)" in TEXT
    assert f"with runs of {LONG_RUNS} × Timelag" in TEXT
    assert f"left out: {NPREV_SHARE:g} × Timelag" in TEXT
    assert f"left out: {NPOST_SHARE:g} × Timelag" in TEXT
    assert f"some {default_profile().galvo.tracking_delay_us:g} µs" in TEXT
    figure = re.search(r"!\[[^]]*\]\(\.\./(analysis/sky\.png)\)", PAGE)
    assert figure and (DOCS / figure[1]).exists()
