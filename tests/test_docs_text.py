# amaranth: UnusedElaboratable=no
"""The README and the docs stay true: their pin tables, register map, commands, figures and
tables match the code. Each test reads the page that holds its table."""

import json
from pathlib import Path
import re

import pytest

from amaranth_boards.icebreaker import ICEBreakerPlatform

from galvoscan.analysis.study import Setup, run_spiral
from galvoscan.bench import DOCS_END, DOCS_START, docs_block, readme_table, write_docs
from galvoscan.cli import main
from galvoscan.cli.link import register_table
from galvoscan.correction.study import markdown_table, photo_sentence_values, run_study
from galvoscan.gateware.sources.spiral_table import SpiralTable
from galvoscan.gateware.top import GalvoScanTop

try:
    import tomllib  # novermin: tomli below where it is missing
except ModuleNotFoundError:                      # Python < 3.11
    import tomli as tomllib
from galvoscan.platforms.icebreaker import (ALARM_PMOD_PINS, INTERLOCK_PMOD_PIN,
                                           LASER_PMOD_PINS, SPI_PMOD_PINS, XY2_PMOD_PINS)
from galvoscan.platforms.ulx3s import wiring_table

from link_codec import FRAME_LINE_BITS


ROOT = Path(__file__).parent.parent
DOCS = ROOT / "docs"
README = (ROOT / "README.md").read_text()


def page(name):
    """The text of the docs page ``name`` (a path under docs/)."""
    return (DOCS / name).read_text()


def every_page():
    """The README and every docs page: (path, text)."""
    files = [ROOT / "README.md", *sorted(DOCS.rglob("*.md"))]
    return [(path, path.read_text()) for path in files if "_build" not in path.parts]


def pmod_fpga_pin(number, pmod_pin):
    """FPGA pin of a PMOD pin, from amaranth-boards' iCEBreaker definition."""
    connector, = (c for c in ICEBreakerPlatform.connectors
                  if (c.name, c.number) == ("pmod", number))
    return int(connector.mapping[str(pmod_pin)])


def test_pin_table_matches_the_platform():
    rows = re.findall(r"^\| (\d+) \| (\d+) \| `xy2_(\w+)` \|$", page("hardware/wiring.md"), re.M)
    assert rows
    assert {signal: int(pmod) for pmod, _, signal in rows} == XY2_PMOD_PINS
    for pmod, fpga, _ in rows:
        assert pmod_fpga_pin(0, pmod) == int(fpga)


def test_spi_pin_table_matches_the_platform():
    rows = re.findall(r"^\| (\d+) \| (\d+) \| `spi_(\w+)`", page("hardware/wiring.md"), re.M)
    assert rows
    assert {signal: int(pmod) for pmod, _, signal in rows} == \
        {name: pin for name, (pin, _) in SPI_PMOD_PINS.items()}
    for pmod, fpga, _ in rows:
        assert pmod_fpga_pin(1, pmod) == int(fpga)


def test_register_table_is_the_register_map():
    assert register_table() in page("reference/registers.md")


def test_ci_runs_the_readme_test_command():
    commands = re.findall(r"```sh\n(.+?)\n```", README)
    assert len(commands) == 2
    ci = (ROOT / ".ci" / "run").read_text()
    assert commands[1] in ci
    assert "pytest -W error" in commands[1]
    assert "galvoscan build" in commands[0] and "galvoscan sim" in commands[0]


def test_pictures_exist():
    """Every picture a page shows is in the repository (where the page's link says), and every
    figure in docs/ is shown somewhere."""
    shown = set()
    for path, text in every_page():
        for picture in re.findall(r"\]\(([^)\s]+\.png)\)", text):
            assert (path.parent / picture).is_file(), (path, picture)
            shown.add((path.parent / picture).resolve())
    figures = {path.resolve() for path in DOCS.rglob("*.png") if "_build" not in path.parts}
    assert shown == figures


def test_laser_pin_table_matches_the_platform():
    rows = re.findall(r"^\| PMOD(\w+) ([\d, ]+) \| ([\d, ]+) \| `(\w+)[^`]*`",
                      page("hardware/wiring.md"), re.M)
    connectors = {"2": 2, "1A": 0, "1B": 1}
    seen = {}
    for connector, pmod_pins, fpga_pins, signal in rows:
        pmod_pins = [int(p) for p in pmod_pins.split(",")]
        fpga_pins = [int(p) for p in fpga_pins.split(",")]
        number = connectors[connector]
        for pmod, fpga in zip(pmod_pins, fpga_pins):
            assert pmod_fpga_pin(number, pmod) == fpga
        seen.setdefault(signal, []).extend((number, p) for p in pmod_pins)
    for name, (number, pins, _) in LASER_PMOD_PINS.items():
        assert seen[f"laser_{name}"] == [(number, int(p)) for p in pins.split()]
    assert seen["interlock_open"] == [(INTERLOCK_PMOD_PIN[0], int(INTERLOCK_PMOD_PIN[1]))]
    assert seen["laser_alarm"] == [(ALARM_PMOD_PINS[0], int(p)) for p in ALARM_PMOD_PINS[1].split()]


def test_sampling_table_is_what_the_analysis_measures():
    """The results page's Gaussian-against-uniform figures come from `galvoscan analyze`."""
    results = page("results/analyses.md")
    setup = Setup()
    gaussian = run_spiral(setup).metrics
    uniform = run_spiral(setup, table=SpiralTable(sampling="uniform"),
                         dwell=gaussian["dwell"]).metrics
    assert f"| 50 × 20 mm, dwell {gaussian['dwell']} ({gaussian['duration_s']:.2f} s a pattern)" \
        in results
    assert f"| CV of 1 mm blocks | **{gaussian['cv_1mm']:.2f}** | {uniform['cv_1mm']:.2f} |" \
        in results
    assert (f"| edge / centre dose (mean, p99) | {gaussian['edge_centre']:.2f}, "
            f"{gaussian['edge_peak']:.2f} | {uniform['edge_centre']:.2f}, "
            f"{uniform['edge_peak']:.2f} |") in results


def test_correction_table_is_what_the_study_measures():
    """The correction page's residual table and photo figures come from `galvoscan correct
    study`."""
    correction = page("user/correction.md")
    study = run_study()
    assert markdown_table(study) in correction
    values = photo_sentence_values(study)
    assert (f"to within {values['PHOTO_MAX']} units (mean {values['PHOTO_MEAN']}; "
            f"{values['PHOTO_UPP']} units a pixel)") in correction
    assert f"removes {values['PHOTO_REMOVED']} of the mean error" in correction


def test_benchmark_table_is_what_bench_recorded():
    """One benchmark table, written by `galvoscan bench --docs` from docs/bench.json."""
    result = json.loads((ROOT / "docs" / "bench.json").read_text())
    assert docs_block(result) in page("reference/benchmarks.md")
    assert sum(text.count("| what | figure |") for _, text in every_page()) == 1


def test_ulx3s_wiring_is_the_platforms():
    """The ULX3S's pin table, in the README and on the wiring page, is the platform's
    (tests/platforms/test_ulx3s.py holds the platform to the pins its build places)."""
    table = wiring_table()
    assert table in README
    assert table in page("hardware/wiring.md")


def test_boards_table_is_what_bench_recorded():
    """The README's boards: each one's logic, Fmax and clock as `galvoscan bench` measured
    its default bitstream, and the ULX3S link's rate."""
    result = json.loads((DOCS / "bench.json").read_text())
    rows = {row[0]: row for row in re.findall(
        r"^\| (iCEBreaker|iCEstick|ULX3S) \|.*\| (\d+) / (\d+) ([\w ]+?) \| ([\d.]+) MHz "
        r"\(([\d.]+) MHz\) \|$", README, re.M)}
    assert set(rows) == {"iCEBreaker", "iCEstick", "ULX3S"}
    for name, label in (("iCEBreaker", "icebreaker"), ("iCEstick", "icestick"),
                        ("ULX3S", "ulx3s")):
        board = result["boards"][label]
        _, used, available, logic, fmax, clock = rows[name]
        assert (int(used), int(available)) == (board["luts"], board["luts_available"])
        assert logic == board.get("logic", "logic cells")
        assert (float(fmax), float(clock)) == (round(board["fmax_mhz"], 1), board["clock_mhz"])
    segments = result["link"]["stream_ulx3s"]["segments_per_s"]
    assert f"UART at 3 Mbaud: {round(segments, -2):,.0f} segments/s" in README


def test_readme_speeds_are_what_bench_recorded():
    result = json.loads((DOCS / "bench.json").read_text())
    assert readme_table(result) in README


def test_every_port_of_the_top_is_listed():
    top = GalvoScanTop(clk_freq=12e6)
    architecture = page("design/architecture.md")
    paragraph = architecture[architecture.index("- **System top**"):]
    paragraph = paragraph[:paragraph.index("\n\n")]
    for name in top.signature.members:
        assert f"`{name}" in paragraph, name


def test_docs_cite_papers_not_private_files():
    """A reader can follow every reference: the papers by name, no files outside the repo."""
    for path, text in every_page():
        assert "SPEC" not in text, path
        assert not re.search(r"\b00[0134]'s\b|\(00[0134]\)|\b00[0134] \(paper\)", text), path
    references = page("references.md")
    for author in ("Dai Jinyue", "Wan Hui", "Liao Ping", "Zhu Tieshuang"):
        assert author in references


def test_profile_page_lists_the_profiles_tables(tmp_path):
    """The profile page's table has a row for each table `machine init` writes, and no other."""
    written = tmp_path / "galvoscan.toml"
    assert main(["machine", "init", str(written)]) == 0
    tables = set(tomllib.loads(written.read_text()))
    rows = re.findall(r"^\| `\[(\w+)\]` \|", page("user/profile.md"), re.M)
    assert sorted(rows) == sorted(tables)


def test_readme_links_to_every_page():
    """The README's map of the docs names every page, and every file it links to is there."""
    links = re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", README)
    local = [link for link in links if "://" not in link]
    for link in local:
        assert (ROOT / link).exists(), link
    pages = {path.relative_to(ROOT).as_posix() for path in DOCS.rglob("*.md")
             if "_build" not in path.parts and path.name != "index.md"}
    assert pages <= set(local), pages - set(local)


def heading_anchors(text):
    """The anchors MyST makes of a page's headings (``myst_heading_anchors``): lower case,
    punctuation dropped, spaces as hyphens."""
    return {re.sub(r"[^\w\- ]", "", title).strip().lower().replace(" ", "-")
            for title in re.findall(r"^#{1,3} (.+)$", text, re.M)}


def test_readme_anchors_into_the_docs_resolve():
    """The README is not part of the Sphinx build, so its links to a heading are checked here."""
    anchored = re.findall(r"\]\((docs/[^)#\s]+\.md)#([^)\s]+)\)", README)
    assert anchored
    for link, anchor in anchored:
        assert anchor in heading_anchors((ROOT / link).read_text()), (link, anchor)


def test_bench_docs_rewrites_the_table_and_keeps_the_prose(tmp_path):
    """`bench --docs PAGE` replaces what lies between the marker lines and nothing else."""
    text = page("reference/benchmarks.md")
    before, after = text[:text.index(DOCS_START)], text[text.index(DOCS_END) + len(DOCS_END):]
    result = json.loads((DOCS / "bench.json").read_text())
    result["date"] = "2031-01-02"
    copy = tmp_path / "benchmarks.md"
    copy.write_text(text)
    write_docs(copy, result)
    assert copy.read_text() == before + docs_block(result) + after
    assert "on 2031-01-02:" in copy.read_text()


@pytest.mark.parametrize("content, extra, message", [
    ("# Benchmarks\n\nno table here\n", [], "has no benchmark table to rewrite"),
    (None, ["--quick"], "--docs takes a full run's figures"),
])
def test_bench_docs_refuses_before_the_run(tmp_path, capsys, content, extra, message):
    """A page without the marker lines, or a quick run, is one line before any measuring."""
    target = tmp_path / "benchmarks.md"
    target.write_text(page("reference/benchmarks.md") if content is None else content)
    with pytest.raises(SystemExit) as exit:
        main(["bench", "--docs", str(target), *extra])
    assert exit.value.code not in (0, None)
    err = capsys.readouterr().err
    assert message in str(exit.value) + err
    # The refusal alone: no step of the run was started.
    assert err.splitlines() == [line for line in err.splitlines()
                                if line.startswith("galvoscan bench: error: ")]


def test_marking_pages_photo_figures_are_the_plans(tmp_path):
    """The marking page's figures for a photo under the default jump delays and under one delay
    for every jump are what planning the tests' grey photo gives, and its link time is the
    link's."""
    from galvoscan import api
    from galvoscan.profile.machine import default_profile, parse_profile
    from photos import grey_photo
    text = " ".join(page("user/marking.md").split())
    found = re.search(r"A 30 mm photo of smooth grey shading \(400 × 300 px, the tests' "
                      r"`grey_photo`\) plans in ([\d.]+) s and ([\d,]+) segments, against "
                      r"([\d.]+) s and ([\d,]+) with 500 µs after every jump", text)
    assert found, "the marking page's photo figures"
    defaults = re.search(r"by default (\d+) µs for a jump of 0, (\d+) µs from (\d+) mm on", text)
    galvo = default_profile().galvo
    assert defaults and tuple(map(float, defaults.groups())) == (
        galvo.min_jump_delay_us, galvo.jump_delay_us, galvo.jump_length_limit_mm)
    job = api.Job(photos=(api.Photo(str(grey_photo(tmp_path / "grey.png")), 30.0,
                                    lines="runs"),))
    for profile, (seconds, segments) in ((default_profile(), found.group(1, 2)),
                                         (parse_profile("[galvo]\njump_length_limit_mm = 0\n"),
                                          found.group(3, 4))):
        planned = api.plan(job, profile).vector_job
        assert (f"{planned.estimate_s:.1f}", f"{len(planned.segments):,}") == (seconds, segments)
    link = re.search(r"the link at 1 Mbaud takes (\d+) µs to bring a jump and its mark", text)
    assert link and int(link[1]) == round(2 * FRAME_LINE_BITS / 1_000_000 * 1e6)


def test_marking_pages_pixel_line_figures_are_the_readme_photos_plans():
    """The marking page's figures for the README's photo, as pixel lines and as runs, are
    what planning it gives."""
    from galvoscan import api
    text = " ".join(page("user/marking.md").split())
    found = re.search(r"The 30 mm photo of the README plans as ([\d,]+) lines in ([\d,]+) "
                      r"segments \(link words\), ([\d.]+) s of board time at ([\d,]+) mm/s; as "
                      r"runs, ([\d,]+) marks and their jumps in ([\d,]+) segments, ([\d.]+) s "
                      r"at ([\d,]+) mm/s", text)
    assert found, "the marking page's pixel-line figures"
    hopper = str(ROOT / "docs" / "marking" / "hopper.jpg")
    pixels = api.plan(api.Job(photos=(api.Photo(hopper, 30.0),))).vector_job
    runs = api.plan(api.Job(photos=(api.Photo(hopper, 30.0, lines="runs"),))).vector_job
    assert found.groups() == (
        f"{sum(op == 'line' for op, *_ in pixels.segments):,}", f"{len(pixels.segments):,}",
        f"{pixels.estimate_s:.1f}", f"{pixels.pitch.speed_mm_s:,.0f}",
        f"{len(runs.paths_mm):,}",
        f"{len(runs.segments):,}", f"{runs.estimate_s:.1f}", f"{runs.pitch.speed_mm_s:,.0f}")


def test_first_jobs_plan_is_what_mark_prints(tmp_path, capsys, monkeypatch):
    """The first-job page's plan of the logo is what `mark` prints for its command today."""
    block = re.search(r"```text\n\.venv/bin/galvoscan (mark docs/marking/logo\.svg [^\n]*)\n"
                      r"(.*?)```", page("user/first-job.md"), re.S)
    assert block, "the first-job page's mark command"
    args = block[1].split()
    args[args.index("--preview") + 1] = str(tmp_path / "logo.png")
    args[1] = str(ROOT / args[1])
    monkeypatch.chdir(tmp_path)                  # no galvoscan.toml: the default profile
    assert main(args) == 0
    printed = capsys.readouterr().out.replace(str(tmp_path / "logo.png"), "logo.png")
    assert printed == block[2]


def test_the_readmes_photo_is_what_its_command_draws(tmp_path, monkeypatch):
    """The README's photo example: its source is matplotlib's sample photograph, and its
    preview is what the command beside it draws today (the same size, the same picture: the
    darkness of 20-pixel blocks alike to r > 0.99, so that a new matplotlib's anti-aliasing
    does not fail it, where a preview of another job would)."""
    import matplotlib.cbook
    import numpy as np
    from PIL import Image
    command = re.search(r"\.venv/bin/galvoscan (mark --image docs/marking/hopper\.jpg [^\n`]*)",
                        README)
    assert command, "the README's photo command"
    args = command[1].split()
    assert args[-2:] == ["--preview", "hopper-preview.png"]
    sample = Path(matplotlib.cbook.get_sample_data("grace_hopper.jpg", asfileobj=False))
    assert (ROOT / "docs" / "marking" / "hopper.jpg").read_bytes() == sample.read_bytes()
    args[args.index("--image") + 1] = str(ROOT / "docs" / "marking" / "hopper.jpg")
    args[-1] = str(tmp_path / "hopper-preview.png")
    monkeypatch.chdir(tmp_path)                  # no galvoscan.toml: the default profile
    assert main(args) == 0

    def grey(path):
        with Image.open(path) as image:
            return np.asarray(image.convert("L"), dtype=float)

    def blocks(pixels):
        h, w = (s - s % 20 for s in pixels.shape)
        return pixels[:h, :w].reshape(h // 20, 20, w // 20, 20).mean(axis=(1, 3)).ravel()

    drawn = grey(tmp_path / "hopper-preview.png")
    committed = grey(ROOT / "docs" / "marking" / "hopper-preview.png")
    assert drawn.shape == committed.shape
    assert np.corrcoef(blocks(drawn), blocks(committed))[0, 1] > 0.99
