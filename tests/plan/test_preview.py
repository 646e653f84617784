"""The preview picture: written in the format of its suffix, with the lengths in its legend
worked out here, and no pyplot state left behind."""

import sys

import matplotlib
import numpy as np
import pytest

from galvoscan.plan.preview import preview


SQUARE = np.array([[10.0, 10], [20, 10], [20, 20], [10, 20], [10, 10]])
LINE = np.array([[-30.0, 0], [-30, 40]])


def test_png_is_written(tmp_path):
    out = tmp_path / "job.png"
    mark_mm, jump_mm = preview(out, [SQUARE, LINE], field_mm=110, title="job.svg")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert mark_mm == pytest.approx(40 + 40)
    # Centre → (10, 10), then (10, 10) → (−30, 0).
    assert jump_mm == pytest.approx(np.hypot(10, 10) + np.hypot(40, 10))


def test_svg_legend_says_the_lengths(tmp_path):
    out = tmp_path / "job.svg"
    with matplotlib.rc_context({"svg.fonttype": "none"}):      # text as text, to search it
        preview(out, [SQUARE, LINE], field_mm=110, title="job.svg")
    text = out.read_text()
    assert "marks 80.0 mm (2 paths)" in text
    assert f"jumps {np.hypot(10, 10) + np.hypot(40, 10):.1f} mm" in text
    assert "field 110 mm" in text and "drawing 50.00 × 40.00 mm" in text


def test_without_jumps_and_empty(tmp_path):
    out = tmp_path / "nojumps.svg"
    with matplotlib.rc_context({"svg.fonttype": "none"}):
        preview(out, [SQUARE], jumps=False, field_mm=70)
        assert "jumps" not in out.read_text()
        preview(out, [], field_mm=70)
        assert "marks" not in out.read_text() and "field 70 mm" in out.read_text()


def test_pdf_by_suffix(tmp_path):
    out = tmp_path / "job.pdf"
    preview(out, [SQUARE], field_mm=110)
    assert out.read_bytes()[:5] == b"%PDF-"


def test_unwritable(tmp_path):
    with pytest.raises(ValueError, match="cannot write the preview"):
        preview(tmp_path / "job.unknown", [SQUARE], field_mm=110)
    with pytest.raises(ValueError, match="cannot write the preview"):
        preview(tmp_path / "missing" / "job.png", [SQUARE], field_mm=110)


def test_no_pyplot_figures_left(tmp_path):
    before = sys.modules.get("matplotlib.pyplot")
    open_before = before.get_fignums() if before else []
    preview(tmp_path / "job.png", [SQUARE], field_mm=110)
    after = sys.modules.get("matplotlib.pyplot")
    if after is not None:
        assert after.get_fignums() == open_before


def _detail_mm(text):
    """The detail panel's width its title gives, mm (None: no detail panel)."""
    import re
    found = re.search(r"a detail, ([0-9.]+) mm wide", text)
    return float(found.group(1)) if found else None


def _hatch(side, spacing):
    return [np.array([[0.0, y], [side, y]]) for y in np.arange(0, side, spacing)]


def test_a_fine_hatch_gets_a_detail_panel(tmp_path):
    """Lines 0.1 mm apart over 34 mm run together even zoomed in: a third panel shows a
    detail some 30 lines wide; lines 2 mm apart need none."""
    for spacing, panels in [(0.1, 3), (2.0, 2)]:
        out = tmp_path / f"hatch{spacing}.svg"
        with matplotlib.rc_context({"svg.fonttype": "none"}):
            preview(out, _hatch(34, spacing), field_mm=110)
        text = out.read_text()
        assert (_detail_mm(text) is not None) == (panels == 3), spacing
        if panels == 3:             # some 30 lines wide
            assert _detail_mm(text) == pytest.approx(30 * spacing, rel=0.2)
        assert "the drawing, zoomed in" in text


def test_groups_are_named_in_their_colours(tmp_path):
    out = tmp_path / "layers.svg"
    with matplotlib.rc_context({"svg.fonttype": "none"}):
        preview(out, [SQUARE, LINE], field_mm=110,
                groups=[("Cut: 40.0 mm", "#ff0000", [SQUARE]), ("the rest: 40.0 mm", "black",
                                                               [LINE])])
    text = out.read_text()
    assert "Cut: 40.0 mm" in text and "the rest: 40.0 mm" in text
    assert "#ff0000" in text


def test_dots_are_drawn_and_counted(tmp_path):
    """Marks of no length (a dotted code's modules) are drawn as dots and counted."""
    out = tmp_path / "dots.svg"
    dots = [np.array([[x, 0.0], [x, 0.0]]) for x in range(5)]
    with matplotlib.rc_context({"svg.fonttype": "none"}):
        preview(out, dots + [LINE], field_mm=110)
    assert "marks 40.0 mm (6 paths), 5 dots" in out.read_text()


def test_a_fine_hatch_in_one_corner_gets_its_detail_panel(tmp_path):
    """The density is the densest part's, not the drawing's mean: a small fine hatch in a
    corner of a large sparse drawing still gets its detail panel, on it."""
    out = tmp_path / "corner.svg"
    sparse = [np.array([[-20.0, -20], [20, -20], [20, 20], [-20, 20], [-20, -20]])]
    with matplotlib.rc_context({"svg.fonttype": "none"}):
        preview(out, sparse + [p + (15, 15) for p in _hatch(3, 0.05)], field_mm=110)
    assert _detail_mm(out.read_text()) == pytest.approx(30 * 0.05, rel=0.2)
