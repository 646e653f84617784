"""Text (galvoscan/inputs/text.py, `mark --text`): capital height, alignment, spacing and lines
measured on the shapes; the marks off the simulated board's wires against matplotlib's own
rendering of the same font (Agg fills the glyph curves itself: none of our flattening,
hatching, placement or board is in it); and an SVG's <text> (laid out by usvg, svg_text.py, read by
drawing.py) against matplotlib's own extents of its glyphs."""

import json

import numpy as np
import pytest

from galvoscan.cli import main
from galvoscan.geometry.field import PlanError
from galvoscan.inputs.text import TextSpec, text_drawing

from drawings import load_svg
from sim_board import VECTOR_BOARD, quick_sim_board


@pytest.mark.parametrize("font", [None, "hershey", "hershey:timesr"])
def test_capital_height_alignment_spacing_and_lines(font):
    h = text_drawing(TextSpec("H", 5, font=font)).bounds()
    assert h[1] == pytest.approx(0, abs=1e-9) and h[3] == pytest.approx(5, abs=1e-9)
    left = text_drawing(TextSpec("MARK", 4, font=font)).bounds()
    right = text_drawing(TextSpec("MARK", 4, font=font, align="right")).bounds()
    centre = text_drawing(TextSpec("MARK", 4, font=font, align="centre")).bounds()
    assert left[0] == pytest.approx(0, abs=1e-9) and right[2] == pytest.approx(0, abs=1e-9)
    assert right[2] - right[0] == pytest.approx(left[2] - left[0])
    assert centre[0] + centre[2] == pytest.approx(0, abs=1e-9)
    wide = text_drawing(TextSpec("MARK", 4, font=font, letter_spacing_mm=1)).bounds()
    assert (wide[2] - wide[0]) - (left[2] - left[0]) == pytest.approx(3, abs=0.05)
    two = text_drawing(TextSpec("H\nH", 5, font=font, line_spacing=1.5)).bounds()
    assert two[1] == pytest.approx(-7.5, abs=1e-9) and two[3] == pytest.approx(5, abs=1e-9)


def test_outlines_are_closed_and_strokes_open():
    outline = text_drawing(TextSpec("O", 5))
    assert outline.closed == (True, True)                 # the O and its counter
    strokes = text_drawing(TextSpec("O", 5, font="hershey"))
    assert not any(strokes.closed)


@pytest.mark.parametrize("kwargs, words", [
    (dict(text="  ", height_mm=5), "empty"),
    (dict(text="x", height_mm=0), "from 0.1 to 500"),
    (dict(text="x", height_mm=5, align="top"), "left, centre or right"),
    (dict(text="x", height_mm=5, font="/nonexistent/font.ttf"), "not found"),
    (dict(text="x", height_mm=5, font="No Such Font Family"), "is not installed"),
    (dict(text="x", height_mm=5, font="hershey:nonesuch"), "Hershey font 'nonesuch'"),
])
def test_impossible_text_is_one_line(kwargs, words):
    with pytest.raises(PlanError, match=words):
        text_drawing(TextSpec(**kwargs))


def test_the_fields_and_their_refusal(capsys):
    assert main(["mark", "--text", "made {date:%Y}", "--estimate", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["segments"] > 10
    with pytest.raises(SystemExit, match=r"\{nope\} is not a field galvoscan knows "
                                         r"\(\{serial\}, "):
        main(["mark", "--text", "SN {nope}", "--estimate"])
    with pytest.raises(SystemExit, match=r"a field written wrong \(unmatched '\{'"):
        main(["mark", "--text", "SN {serial:04d", "--estimate"])
    with pytest.raises(SystemExit, match="--font is for --text"):
        main(["mark", "--code", "qr", "--data", "x", "--size", "5", "--font", "hershey",
              "--estimate"])


def test_bare_date_and_time_fields_read_as_a_person_writes_them():
    """{date} is the ISO date and {time} hours and minutes (Python's own would give the
    microseconds); a format given is strftime's."""
    import re
    from galvoscan.cli.content import fields
    assert re.fullmatch(r"\d{4}-\d\d-\d\d \d\d:\d\d", fields("{date} {time}"))
    assert re.fullmatch(r"\d\d\.\d\d\.\d{4}", fields("{date:%d.%m.%Y}"))
    assert fields("SN {serial:05d}", serial=42) == "SN 00042"


def _image(marks, bounds, *, radius_mm, px_mm=0.02):
    x0, y0, x1, y1 = bounds
    w, h = int((x1 - x0) / px_mm) + 1, int((y1 - y0) / px_mm) + 1
    image = np.zeros((h, w), bool)
    yy, xx = np.mgrid[0:h, 0:w]
    r = radius_mm / px_mm
    for x, y in marks:
        cx, cy = (x - x0) / px_mm, (y1 - y) / px_mm
        box = (slice(max(0, int(cy - r - 1)), int(cy + r + 2)),
               slice(max(0, int(cx - r - 1)), int(cx + r + 2)))
        image[box] |= (xx[box] - cx) ** 2 + (yy[box] - cy) ** 2 <= r * r
    return image


def _rendered(text, height, bounds, px_mm=0.02):
    """matplotlib's Agg rendering of the text's glyphs at ``height`` mm capitals, its own
    curves, on the same pixels (left-aligned by the ink, as `mark` sets a line)."""
    import matplotlib
    matplotlib.use("Agg")
    from matplotlib.figure import Figure
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.patches import PathPatch
    from matplotlib.textpath import TextPath
    from matplotlib.font_manager import FontProperties
    prop = FontProperties(family="DejaVu Sans", size=100)
    cap = TextPath((0, 0), "H", prop=prop).get_extents().height
    ink = TextPath((0, 0), text, prop=prop).get_extents()
    path = TextPath((-ink.x0, 0), text, prop=prop)          # its ink from x = 0, as marked
    x0, y0, x1, y1 = bounds
    w, h = int((x1 - x0) / px_mm) + 1, int((y1 - y0) / px_mm) + 1
    figure = Figure(figsize=(w / 100, h / 100), dpi=100)
    FigureCanvasAgg(figure)
    axes = figure.add_axes((0, 0, 1, 1))
    axes.set_xlim(x0 * cap / height, x1 * cap / height)
    axes.set_ylim(y0 * cap / height, y1 * cap / height)
    axes.axis("off")
    axes.add_patch(PathPatch(path, facecolor="black", edgecolor="none"))
    figure.canvas.draw()
    pixels = np.asarray(figure.canvas.buffer_rgba())[..., 0]
    return pixels[:h, :w] < 128


@pytest.mark.slow
def test_marked_text_covers_the_glyphs_off_the_wires(tmp_path, capsys):
    """ "LOT 7" in DejaVu Sans at 2 mm, marked on the simulated board: the spot's discs on
    the marks off the wires fill matplotlib's own rendering of the glyphs and go no further
    than the spot reaches past their edges."""
    machine = tmp_path / "machine.toml"
    machine.write_text("[laser]\nspot_mm = 0.1\n[galvo]\njump_delay_us = 100\n")
    with quick_sim_board(**VECTOR_BOARD):
        assert main(["mark", "--text", "LOT 7", "--height", "2", "--speed", "2000", "--prr",
                     "50", "--machine", str(machine), "--sim", "--timeout", "600",
                     "--json"]) == 0
    result = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert result["errors"] == result["underruns"] == 0
    marks = np.array(result["drawing_marks"])
    bounds = (-0.5, -1.0, 8.0, 3.0)
    marked = _image(marks, bounds, radius_mm=0.05)          # the 0.1 mm spot on each mark
    glyphs = _rendered("LOT 7", 2, bounds)
    # The outline is marked on the glyphs' edges: the burn reaches half a spot past them.
    from skimage.morphology import dilation, disk
    reach = dilation(glyphs, disk(3))                        # 0.06 mm
    assert (marked & reach).sum() / marked.sum() > 0.99      # nothing marked off the glyphs
    assert (marked & glyphs).sum() / glyphs.sum() > 0.98     # the glyphs filled


@pytest.mark.parametrize("font, words", [(None, "'日本' are not in DejaVuSans.ttf"),
                                         ("hershey", "'日' is not in the Hershey font futural")])
def test_a_character_not_in_the_font_is_one_line(font, words):
    """Not a box for a glyph the font lacks, nor a letter dropped: refused, naming it."""
    with pytest.raises(PlanError, match=words):
        text_drawing(TextSpec("A日本" if font is None else "A日", 5, font=font))


def test_a_file_that_is_no_font_is_one_line(tmp_path):
    (tmp_path / "logo.png").write_bytes(b"\x89PNG\r\n\x1a\n" + b"\0" * 64)
    with pytest.raises(PlanError, match="logo.png: not a font .* that can be read"):
        text_drawing(TextSpec("A", 5, font=str(tmp_path / "logo.png")))


def test_svg_text_is_marked_in_its_font(tmp_path):
    """A <text> in an installed font: its glyphs as closed outlines where matplotlib's own
    TextPath puts them (em = font-size, baseline at y, anchored by text-anchor), through the
    element's transform; each outline closed, for --hatch to fill."""
    from matplotlib.font_manager import FontProperties, findfont
    from matplotlib.textpath import TextPath
    d = load_svg(tmp_path, '<text x="10" y="20" font-family="DejaVu Sans" font-size="8" '
                           'text-anchor="middle">Hg</text>')
    assert d.closed and all(d.closed) and not d.skipped
    font = FontProperties(fname=findfont(FontProperties(family="DejaVu Sans")), size=8)
    ink = TextPath((0, 0), "Hg", prop=font).get_extents()
    # The SVG's px are mm here (viewBox = mm); its Y runs down, the drawing's up.
    xmin, ymin, xmax, ymax = d.bounds()
    assert ymax == pytest.approx(-20 + ink.y1, abs=0.02)       # the H's top above the base
    assert ymin == pytest.approx(-20 + ink.y0, abs=0.02)       # the g's tail below it
    assert (xmax - xmin) == pytest.approx(ink.x1 - ink.x0, abs=0.02)
    turned = load_svg(tmp_path, '<text x="0" y="0" font-size="8" '
                                'transform="translate(30 30) rotate(90)">Hg</text>')
    # Turned a quarter (clockwise on the page, Y down): the line runs down the page.
    txmin, tymin, txmax, tymax = turned.bounds()
    assert (tymax - tymin) == pytest.approx(xmax - xmin, abs=0.05)
    # It starts at y = 30 on the page (-30 here), the H's left bearing further on.
    assert tymax == pytest.approx(-30 - ink.x0, abs=0.02)
    # rotate(90) takes the page's up (-y) to +x: the ink to the right of x = 30.
    assert (txmax + txmin) / 2 == pytest.approx(30 + (ink.y0 + ink.y1) / 2, abs=0.02)


def test_svg_tspans_and_font_lists(tmp_path):
    """Each <tspan> at its own place; the first installed family of a CSS list wins; a
    weight picks the bold face (wider strokes: more ink)."""
    d = load_svg(tmp_path, '<text font-family="\'No Such\', DejaVu Sans" font-size="5">'
                           '<tspan x="0" y="10">A</tspan><tspan x="20" y="10">A</tspan></text>')
    xs = [p[:, 0].mean() for p in d.paths]
    assert min(xs) < 5 and max(xs) > 20 and not d.skipped
    import shapely
    from shapely.geometry import Polygon

    def ink(weight):
        drawing = load_svg(tmp_path, f'<text x="0" y="10" font-size="10" '
                                     f'font-weight="{weight}">I</text>')
        return shapely.unary_union([Polygon(p) for p in drawing.paths]).area
    assert ink("bold") > 1.2 * ink("normal")


def test_svg_tspans_follow_on_from_the_text_before(tmp_path):
    """A <tspan> without an x starts where the text before it ends (and its dx on), as a
    browser sets it, and so does the text after it; not on top of the first word."""
    from matplotlib.font_manager import FontProperties, findfont
    from matplotlib.textpath import TextToPath
    prop = FontProperties(fname=findfont(FontProperties(family=["sans-serif"])), size=4)
    width = TextToPath().get_text_width_height_descent("Bold|", prop, ismath=False)[0] - \
        TextToPath().get_text_width_height_descent("|", prop, ismath=False)[0]
    alone = load_svg(tmp_path, '<text x="1" y="10" font-size="4">Bold</text>')
    flowed = load_svg(tmp_path, '<text x="1" y="10" font-size="4">Bold<tspan dx="2">I</tspan>'
                                ' I</text>')
    # The I's stem (its outline's left edge) is past Bold's advance and the dx.
    extra = [p for p in flowed.paths if p[:, 0].min() > alone.bounds()[2] + 0.5]
    assert len(extra) == 2
    first_i = min(p[:, 0].min() for p in extra)
    assert first_i == pytest.approx(1 + width + 2, abs=0.6)
    assert max(p[:, 0].min() for p in extra) > first_i + 1     # " I" after it, a space on
