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
    mark_mm, jump_mm = preview(out, [SQUARE, LINE], field_mm=110, spot_mm=0.05,
                               title="job.svg")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert mark_mm == pytest.approx(40 + 40)
    # Centre → (10, 10), then (10, 10) → (−30, 0).
    assert jump_mm == pytest.approx(np.hypot(10, 10) + np.hypot(40, 10))


def test_svg_legend_says_the_lengths(tmp_path):
    out = tmp_path / "job.svg"
    with matplotlib.rc_context({"svg.fonttype": "none"}):      # text as text, to search it
        preview(out, [SQUARE, LINE], field_mm=110, spot_mm=0.05, title="job.svg")
    text = out.read_text()
    assert "marks 80.0 mm (2 paths)" in text
    assert f"jumps {np.hypot(10, 10) + np.hypot(40, 10):.1f} mm" in text
    assert "field 110 mm" in text and "drawing 50.00 × 40.00 mm" in text


def test_without_jumps_and_empty(tmp_path):
    out = tmp_path / "nojumps.svg"
    with matplotlib.rc_context({"svg.fonttype": "none"}):
        preview(out, [SQUARE], jumps=False, field_mm=70, spot_mm=0.05)
        assert "jumps" not in out.read_text()
        preview(out, [], field_mm=70, spot_mm=0.05)
        assert "marks" not in out.read_text() and "field 70 mm" in out.read_text()


def test_pdf_by_suffix(tmp_path):
    out = tmp_path / "job.pdf"
    preview(out, [SQUARE], field_mm=110, spot_mm=0.05)
    assert out.read_bytes()[:5] == b"%PDF-"


def test_unwritable(tmp_path):
    with pytest.raises(ValueError, match="cannot write the preview"):
        preview(tmp_path / "job.unknown", [SQUARE], field_mm=110, spot_mm=0.05)
    with pytest.raises(ValueError, match="cannot write the preview"):
        preview(tmp_path / "missing" / "job.png", [SQUARE], field_mm=110, spot_mm=0.05)


def test_no_pyplot_figures_left(tmp_path):
    before = sys.modules.get("matplotlib.pyplot")
    open_before = before.get_fignums() if before else []
    preview(tmp_path / "job.png", [SQUARE], field_mm=110, spot_mm=0.05)
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
            preview(out, _hatch(34, spacing), field_mm=110, spot_mm=0.05)
        text = out.read_text()
        assert (_detail_mm(text) is not None) == (panels == 3), spacing
        if panels == 3:             # some 30 lines wide
            assert _detail_mm(text) == pytest.approx(30 * spacing, rel=0.2)
        assert "the drawing, zoomed in" in text


def test_groups_are_named_in_their_colours(tmp_path):
    out = tmp_path / "layers.svg"
    with matplotlib.rc_context({"svg.fonttype": "none"}):
        preview(out, [SQUARE, LINE], field_mm=110, spot_mm=0.05,
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
        preview(out, dots + [LINE], field_mm=110, spot_mm=0.05)
    assert "marks 40.0 mm (6 paths), 5 dots" in out.read_text()


def test_a_fine_hatch_in_one_corner_gets_its_detail_panel(tmp_path):
    """The density is the densest part's, not the drawing's mean: a small fine hatch in a
    corner of a large sparse drawing still gets its detail panel, on it."""
    out = tmp_path / "corner.svg"
    sparse = [np.array([[-20.0, -20], [20, -20], [20, 20], [-20, 20], [-20, -20]])]
    with matplotlib.rc_context({"svg.fonttype": "none"}):
        preview(out, sparse + [p + (15, 15) for p in _hatch(3, 0.05)], field_mm=110,
                spot_mm=0.05)
    assert _detail_mm(out.read_text()) == pytest.approx(30 * 0.05, rel=0.2)


# --- a photo's preview shows its dose ---------------------------------------------------------
#
# The preview is read back as a picture (Pillow), not through matplotlib: the drawing's box (the
# dotted tab:blue rectangle round the marks) is found in its pixels, the photo's area cut out by
# it, and its darkness, averaged over 1 mm cells, held against the source picture's.

#: The photo's size: mm, and pixels of the source picture (a cell of 50 µm each).
PHOTO_MM = (20, 15)
PHOTO_PX = (400, 300)
#: Source pixels of black frame round each test picture: its edge cells are dark, so the marks'
#: box (cell centres) is the photo's area less half a cell each side, whatever is inside.
FRAME_PX = 3


def _framed(grey):
    """``grey`` (0 black … 255 white, rows from the top) with a black frame, as a picture."""
    from PIL import Image
    grey = np.array(grey, dtype=float)
    grey[:FRAME_PX], grey[-FRAME_PX:], grey[:, :FRAME_PX], grey[:, -FRAME_PX:] = 0, 0, 0, 0
    return Image.fromarray(np.clip(grey, 0, 255).astype(np.uint8))


def _shading():
    """Smooth shading over the whole range: light and dark lobes, a ramp across."""
    h, w = PHOTO_PX[1], PHOTO_PX[0]
    y, x = np.mgrid[0:h, 0:w] + 0.5
    lobes = np.sin(2 * np.pi * x / w) * np.cos(np.pi * y / h)
    return _framed(255 * (0.5 + 0.4 * lobes + 0.1 * (x / w - 0.5)))


def _shapes():
    """Black shapes on white: a disc, a bar, a triangle, a thin ring."""
    from PIL import Image, ImageDraw
    picture = Image.new("L", PHOTO_PX, 255)
    draw = ImageDraw.Draw(picture)
    draw.ellipse((40, 40, 170, 170), fill=0)
    draw.rectangle((220, 60, 370, 110), fill=0)
    draw.polygon([(60, 280), (200, 190), (340, 280)], fill=0)
    draw.ellipse((240, 150, 340, 250), outline=0, width=12)
    return _framed(np.asarray(picture))


def _blue_box(rgb):
    """``(left, top, right, bottom)`` pixel centres of the largest dotted tab:blue rectangle in
    ``rgb``: the zoomed panel's drawing box. Its top and bottom edges are the two rows whose
    long runs of blue span the same columns, the widest such pair (the field panel's box is
    smaller; a detail panel shows one edge at most, a legend's handle is short)."""
    r, g, b = (rgb[..., k].astype(int) for k in range(3))
    blue = (b - r > 50) & (b > g)           # tab:blue (31, 119, 180), over white or black
    spans = {}
    for row in np.flatnonzero(blue.sum(axis=1) > 40):
        columns = np.flatnonzero(blue[row])
        breaks = np.flatnonzero(np.diff(columns) > 8)       # a dotted line's gaps are short
        starts = np.concatenate([[0], breaks + 1])
        ends = np.concatenate([breaks, [len(columns) - 1]])
        longest = np.argmax(columns[ends] - columns[starts])
        spans[row] = (columns[starts[longest]], columns[ends[longest]])
    best = None
    for top, (a0, a1) in spans.items():
        for bottom, (b0, b1) in spans.items():
            if bottom - top > 40 and abs(a0 - b0) <= 3 and abs(a1 - b1) <= 3 and \
                    (best is None or a1 - a0 > best[2] - best[0]):
                best = (min(a0, b0), top, max(a1, b1), bottom)
    assert best is not None, "no drawing box found in the preview"
    return best


def _cells(picture, size):
    """``picture`` (Pillow, any mode) as darkness 0 … 1 averaged over ``size`` cells."""
    from PIL import Image
    grey = picture.convert("L").resize(size, Image.Resampling.BOX)
    return 1 - np.asarray(grey, dtype=float) / 255


def preview_against_source(png, source, box_mm=None, spot_mm=0.05):
    """Pearson's r between the preview's darkness over the photo's area and the source
    picture's, on 1 mm cells (the frame's ring of cells left out: it is in both). The photo
    is centred at (0, 0); ``box_mm``: the drawing's box ``(x0, y0, x1, y1)``, mm (None: the
    photo's marks', through its edge cells' centres, half a cell in from its edge)."""
    from PIL import Image
    rgb = np.asarray(Image.open(png).convert("RGB"))
    left, top, right, bottom = _blue_box(rgb)
    w, h = PHOTO_MM
    x0, y0, x1, y1 = box_mm or (-w / 2 + spot_mm / 2, -h / 2 + spot_mm / 2,
                                w / 2 - spot_mm / 2, h / 2 - spot_mm / 2)
    per_mm_x, per_mm_y = (right - left) / (x1 - x0), (bottom - top) / (y1 - y0)
    assert per_mm_x == pytest.approx(per_mm_y, rel=0.02)      # the box found is the drawing's
    area = Image.fromarray(rgb).crop((left + (-w / 2 - x0) * per_mm_x,
                                      top + (y1 - h / 2) * per_mm_y,
                                      left + (w / 2 - x0) * per_mm_x,
                                      top + (y1 + h / 2) * per_mm_y))
    shown, wanted = _cells(area, PHOTO_MM)[1:-1, 1:-1], _cells(source, PHOTO_MM)[1:-1, 1:-1]
    return np.corrcoef(shown.ravel(), wanted.ravel())[0, 1]


#: The least correlation a photo's preview keeps with its source. Measured, drawn at the spot's
#: size: r = 0.996 (shading) and 0.9999 (shapes) zoomed in, the saved job's the same, and 0.998
#: (shading) in a field panel at a quarter of a pixel a row. Drawn in points as before (0.7 pt
#: lines, 2 pt dots, 0.5 pt jumps): the shading's r was -0.44 zoomed in, its preview the dose
#: inverted, and -0.12 in the field panel, a black block; black shapes on white stay solid
#: either way (0.999).
MIN_R = 0.9


@pytest.mark.parametrize("picture", [_shading, _shapes], ids=["shading", "shapes"])
def test_a_photos_preview_shows_its_dose(tmp_path, monkeypatch, picture):
    """``mark --image … --preview`` and the job it saves, run again with ``--preview``: each
    preview's darkness over the photo, on 1 mm cells, follows the source picture's."""
    from galvoscan.cli import main
    monkeypatch.chdir(tmp_path)
    source = picture()
    source.save("photo.png")
    assert main(["mark", "--image", "photo.png", "--width", str(PHOTO_MM[0]), "--estimate",
                 "--preview", "direct.png", "--save", "job.toml"]) == 0
    assert main(["mark", "job.toml", "--estimate", "--preview", "saved.png"]) == 0
    for png in ("direct.png", "saved.png"):
        r = preview_against_source(tmp_path / png, source)
        assert r >= MIN_R, (png, r)


def test_marks_are_the_spots_width_in_millimetres(tmp_path):
    """A line is drawn as wide as the spot, and a dot as its disc, in the drawing's millimetres
    as the picture's pixels measure them (the box round the marks gives the scale), whatever
    the spot: not a width in points."""
    from PIL import Image
    square = np.array([[-10.0, -10], [10, -10], [10, 10], [-10, 10], [-10, -10]])
    dot = np.array([[0.0, 0], [0, 0]])
    for spot_mm in (0.5, 1.5):
        out = tmp_path / f"spot{spot_mm}.png"
        preview(out, [square, dot], field_mm=110, spot_mm=spot_mm)
        rgb = np.asarray(Image.open(out).convert("RGB"))
        left, top, right, bottom = _blue_box(rgb)
        per_mm = (right - left) / 20
        dark = rgb.min(axis=2) < 128
        # Across the top edge, midway between the corners: the stroke's width.
        centre_x, centre_y = (left + right) // 2, (top + bottom) // 2
        band = slice(int(top - 2 * spot_mm * per_mm), int(top + 2 * spot_mm * per_mm))
        assert dark[band, centre_x + 5].sum() == pytest.approx(spot_mm * per_mm, abs=1.5)
        # The dot, alone at the centre: a disc the spot across.
        reach = int(spot_mm * per_mm)
        disc = dark[centre_y - reach:centre_y + reach + 1, centre_x - reach:centre_x + reach + 1]
        assert disc.sum() == pytest.approx(np.pi / 4 * (spot_mm * per_mm) ** 2, rel=0.15)


def test_a_photo_in_a_field_wide_job_shows_its_dose(tmp_path):
    """A photo in a job that spans the field (two dots at its corners): no zoomed panel, the
    photo drawn in the field panel at some 5 pixels a mm, its rows a quarter of a pixel
    apart. Its darkness still follows the source's: the strokes' area shades each pixel, and
    the jumps across its light gaps are thinned, not laid over them a hairline each."""
    from galvoscan import api
    source = _shading()
    source.save(tmp_path / "photo.png")
    plan = api.plan(api.Job(photos=(api.Photo(str(tmp_path / "photo.png"), PHOTO_MM[0]),)))
    corners = [np.array([[-46.0, -46], [-46, -46]]), np.array([[46.0, 46], [46, 46]])]
    out = tmp_path / "field.png"
    preview(out, list(plan.vector_job.paths_mm) + corners, field_mm=110, spot_mm=0.05)
    r = preview_against_source(out, source, box_mm=(-46, -46, 46, 46))
    assert r >= MIN_R, r
