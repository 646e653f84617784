"""An SVG's <text> (galvoscan/inputs/svg_text.py, usvg's layout read as outlines): the marks of
resvg's own test files against resvg's reference pictures of them (drawn by another build of
resvg, in Noto Sans, the suite's font, which these tests add to the fonts found); the issue's
cases measured on the marks; bad text never a crash."""

import json
from pathlib import Path
import xml.etree.ElementTree as ElementTree

from hypothesis import given, settings, strategies as st, HealthCheck
import numpy as np
import pytest

from galvoscan.geometry.drawing import DrawingError
from galvoscan.inputs import svg_text
from galvoscan.inputs.drawings import load_drawing

from drawings import load_svg
from sim_board import VECTOR_BOARD, quick_sim_board


DATA = Path(__file__).parent.parent / "data" / "resvg_text"
PX_PER_MM = 96 / 25.4               # the files have no width and height: user units are px
SIDE = 200                          # their viewBox, px
PICTURE = 300                       # the reference pictures' size: drawn at 1.5 px a px
SUPERSAMPLE = 4

#: The reference pictures' files, each marked with galvoscan and compared.
CASES = sorted(path.stem for path in DATA.glob("*.svg"))
#: Below this overlap (intersection over union of the ink, at the pictures' 300 px) the marks
#: are not the picture: measured 0.89 to 0.98 on these files (antialiased edges and the
#: reference's newer resvg); the same files with the attribute they test taken out (rotate,
#: dy, startOffset, word or letter spacing ignored) measured 0.11 to 0.39
#: (test_a_wrong_layout_is_caught).
MIN_OVERLAP = 0.85


@pytest.fixture
def noto_sans(monkeypatch):
    """The suite's Noto Sans among the fonts usvg reads."""
    found = svg_text._font_dirs
    monkeypatch.setattr(svg_text, "_font_dirs", lambda: found() + [str(DATA / "fonts")])
    svg_text.installed_families.cache_clear()
    yield
    svg_text.installed_families.cache_clear()


def _text_only(source, tmp_path):
    """The file with its shapes hidden (the crosshair, frame and textPath guides are not what
    is compared; a textPath still follows its hidden path)."""
    root = ElementTree.fromstring(source.read_bytes())
    for element in root.iter():
        if element.tag.rsplit("}", 1)[-1] in ("path", "rect", "line", "circle"):
            element.set("visibility", "hidden")
    path = tmp_path / source.name
    path.write_bytes(ElementTree.tostring(root))
    return path


def _filled(drawing):
    """The marks filled (even-odd: each contour flips the pixels inside it), on the reference
    picture's pixels, as coverage 0 to 1."""
    from PIL import Image, ImageDraw
    size = PICTURE * SUPERSAMPLE
    per_mm = PX_PER_MM * PICTURE / SIDE * SUPERSAMPLE
    ink = np.zeros((size, size), dtype=bool)
    for points, closed in zip(drawing.paths, drawing.closed):
        assert closed
        xy = [(x * per_mm, -y * per_mm) for x, y in points]
        layer = Image.new("1", (size, size), 0)
        ImageDraw.Draw(layer).polygon(xy, fill=1)
        ink ^= np.asarray(layer, dtype=bool)
    return ink.reshape(PICTURE, SUPERSAMPLE, PICTURE, SUPERSAMPLE).mean(axis=(1, 3))


def _reference(name):
    """The reference picture's text: its opacity where it is not the crosshair's or the
    guides' grey (the frame's border is cut off below); the text is drawn over them."""
    from PIL import Image
    rgba = np.asarray(Image.open(DATA / f"{name}.png").convert("RGBA"), dtype=float) / 255
    assert rgba.shape[:2] == (PICTURE, PICTURE)
    grey = np.abs(rgba[..., :3] - 128 / 255).max(axis=2) < 0.15
    return np.where(grey, 0.0, rgba[..., 3])


def _overlap(ours, reference):
    inner = np.zeros((PICTURE, PICTURE), dtype=bool)
    inner[6:-6, 6:-6] = True                            # (the frame's stroke)
    a, b = (ours > 0.5) & inner, (reference > 0.5) & inner
    return (a & b).sum() / max(1, (a | b).sum())


@pytest.mark.parametrize("name", CASES)
def test_marks_match_the_reference_picture(name, tmp_path, noto_sans):
    drawing = load_drawing(_text_only(DATA / f"{name}.svg", tmp_path))
    assert all(said.endswith(("hidden element", "hidden elements")) for said in drawing.skipped)
    assert not drawing.notes
    overlap = _overlap(_filled(drawing), _reference(name))
    assert overlap >= MIN_OVERLAP, f"{name}: overlap {overlap:.3f}"


@pytest.mark.parametrize("name, attribute", [("text-rotate", "rotate"),
                                             ("tspan-with-dy", "dy"),
                                             ("textPath-startOffset=30", "startOffset"),
                                             ("word-spacing-10", "word-spacing"),
                                             ("letter-spacing-3", "letter-spacing")])
def test_a_wrong_layout_is_caught(name, attribute, tmp_path, noto_sans):
    """The comparison's power: each file with the attribute it tests taken out (as a layout
    that ignored it would set it) falls well under the bound."""
    source = tmp_path / "source"
    source.mkdir()
    root = ElementTree.fromstring((DATA / f"{name}.svg").read_bytes())
    for element in root.iter():
        element.attrib.pop(attribute, None)
    (source / f"{name}.svg").write_bytes(ElementTree.tostring(root))
    drawing = load_drawing(_text_only(source / f"{name}.svg", tmp_path))
    overlap = _overlap(_filled(drawing), _reference(name))
    assert overlap < MIN_OVERLAP - 0.1


#: The overlap of the burn off the simulated board's wires with the reference picture: the
#: spot's discs on the hatch lines (0.2 mm apart) and the outline reach 0.1 mm past the glyphs'
#: edges, half a reference pixel; measured 0.88 on text-rotate (about 0.65 and 0.82 with
#: discs of 0.08 and 0.15 mm).
MIN_WIRE_OVERLAP = 0.8


@pytest.mark.slow
def test_marks_off_the_wires_match_the_reference_picture(tmp_path, capsys, noto_sans):
    """resvg's rotate test marked on the simulated board, hatched: the points off the XY2-100
    wires, each a disc of half the hatch spacing, against resvg's picture of the file."""
    from galvoscan.cli import main
    machine = tmp_path / "machine.toml"
    machine.write_text("[laser]\nspot_mm = 0.1\n[galvo]\njump_delay_us = 100\n")
    with quick_sim_board(**VECTOR_BOARD):
        assert main(["mark", str(_text_only(DATA / "text-rotate.svg", tmp_path)), "--hatch",
                     "0.2", "--origin", "page", "--speed", "2000", "--prr", "50",
                     "--machine", str(machine), "--sim", "--timeout", "600", "--json"]) == 0
    result = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert result["errors"] == result["underruns"] == 0
    marks = np.array(result["drawing_marks"])      # the SVG's own mm, Y down
    per_mm = PX_PER_MM * PICTURE / SIDE * SUPERSAMPLE
    size, r = PICTURE * SUPERSAMPLE, 0.1 * per_mm
    burnt = np.zeros((size, size), dtype=bool)
    yy, xx = np.mgrid[0:size, 0:size]
    for x, y in marks * per_mm:
        box = (slice(max(0, int(y - r - 1)), int(y + r + 2)),
               slice(max(0, int(x - r - 1)), int(x + r + 2)))
        burnt[box] |= (xx[box] - x) ** 2 + (yy[box] - y) ** 2 <= r * r
    coverage = burnt.reshape(PICTURE, SUPERSAMPLE, PICTURE, SUPERSAMPLE).mean(axis=(1, 3))
    assert _overlap(coverage, _reference("text-rotate")) >= MIN_WIRE_OVERLAP


# --- the cases, in the installed fonts --------------------------------------------------

def _contours(drawing):
    return sorted((round(float(p[:, 0].min()), 3), len(p)) for p in drawing.paths)


def test_tab_newline_and_return_are_never_glyphs(tmp_path):
    """Whitespace characters are spaces (SVG's xml:space rules), never a box: the letters'
    contours and no more; another control character is left out with a note."""
    letters = load_svg(tmp_path, '<text x="5" y="50" font-size="10">ABCD</text>')
    spaced = load_svg(tmp_path, '<text x="5" y="50" font-size="10">A&#9;B&#10;C&#13;D</text>')
    kept = load_svg(tmp_path, '<text x="5" y="50" font-size="10" xml:space="preserve">'
                              'A&#9;B&#10;C&#13;D</text>')
    for drawing in (spaced, kept):
        assert len(drawing.paths) == len(letters.paths) and not drawing.skipped
    control = load_svg(tmp_path, '<text x="5" y="50" font-size="10">A&#127;B&#133;CD</text>')
    assert _contours(control) == _contours(letters)
    assert "2 control characters in <text> left out (never a glyph)" in control.notes


def test_a_character_no_font_has_is_left_out_and_said(tmp_path):
    """A character no installed font has (an unassigned code point, one of the last private
    plane's) is no box (.notdef, or Last Resort's block name), and no other letter is set in
    a box's font: said in a note."""
    letters = load_svg(tmp_path, '<text x="5" y="50" font-size="10">AB</text>')
    boxed = load_svg(tmp_path, '<text x="5" y="50" font-size="10">A&#x378;&#x10FFFD;B</text>')
    assert len(boxed.paths) == len(letters.paths)
    assert boxed.notes == ("2 characters in <text> that no installed font has "
                           "('\\u0378\\U0010fffd') left out",)


def test_mixed_sizes_follow_on(tmp_path):
    """A larger tspan's glyph after a smaller one's and before the next: none on another."""
    d = load_svg(tmp_path, '<text x="5" y="50" font-size="10">L<tspan font-size="30">I'
                           '</tspan>T</text>')
    spans = sorted((p[:, 0].min(), p[:, 0].max()) for p in d.paths)
    assert len(spans) == 3
    assert all(left[1] < right[0] for left, right in zip(spans, spans[1:]))
    heights = [np.ptp(p[:, 1]) for p in sorted(d.paths, key=lambda p: p[:, 0].min())]
    assert heights[1] == pytest.approx(3 * heights[2], rel=0.05)


def test_a_missing_font_is_replaced_by_its_generic_family_and_said(tmp_path):
    """A family that is not installed: the next of its list, else sans-serif (DejaVu Sans),
    the same outlines as asked by that name; a note names the substitute."""
    generic = load_svg(tmp_path, '<text x="5" y="50" font-family="sans-serif">Mark</text>')
    missing = load_svg(tmp_path, '<text x="5" y="50" font-family="No Such Font 1234">'
                                 'Mark</text>')
    assert not missing.skipped and len(missing.paths) == len(generic.paths)
    np.testing.assert_allclose(missing.bounds(), generic.bounds(), atol=1e-6)
    assert missing.notes == ("font 'No Such Font 1234' is not installed: set in DejaVu Sans "
                             "(sans-serif) in its place",)
    serif = load_svg(tmp_path, '<text x="5" y="50" font-family="DejaVu Serif">Mark</text>')
    listed = load_svg(tmp_path, '<text x="5" y="50" style="font-family: \'No Such\', '
                                'DejaVu Serif">Mark</text>')
    np.testing.assert_allclose(listed.bounds(), serif.bounds(), atol=1e-6)
    assert listed.notes == ("font 'No Such' is not installed: set in DejaVu Serif in its place",)
    sheet = load_svg(tmp_path, '<style>.plate { font-family: "No Such Font 1234" }</style>'
                               '<text class="plate" x="5" y="50">Mark</text>')
    np.testing.assert_allclose(sheet.bounds(), generic.bounds(), atol=1e-6)
    assert sheet.notes == missing.notes


def test_text_spaced_past_any_scale_is_one_line(tmp_path):
    """Letters spaced 10^10 px apart: a drawing too large at any scale, refused in one line
    (found by the test below: the refusal failed on having no scale to offer)."""
    with pytest.raises(DrawingError, match=r"more than 10 m") as refusal:
        load_svg(tmp_path, '<text x="5" y="50" letter-spacing="1e10">ab</text>')
    assert "\n" not in str(refusal.value)


def test_too_much_text_is_one_line(tmp_path):
    with pytest.raises(DrawingError, match=r"hold 20,001 characters: 20,000 at most$"):
        load_svg(tmp_path, f'<text x="5" y="50">{"a" * 20_001}</text>')


_XML_CHARACTERS = st.characters(blacklist_categories=("Cs",), min_codepoint=1).filter(
    lambda ch: ch in "\t\n\r" or ord(ch) >= 0x20 and ch not in "\ufffe\uffff")
_LISTS = st.text(alphabet="0123456789.,- e%x", max_size=20)


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(content=st.text(alphabet=_XML_CHARACTERS, max_size=40), rotate=_LISTS, dy=_LISTS,
       size=_LISTS, spacing=_LISTS,
       family=st.text(alphabet=st.sampled_from("abc ,'\"-;:}"), max_size=16),
       space=st.sampled_from(["default", "preserve", "junk"]))
def test_bad_text_is_marked_or_one_line(tmp_path, content, rotate, dy, size, spacing, family,
                                        space):
    """Any text and any dy, rotate, font-size and letter-spacing lists, font-family and
    xml:space: a drawing, or one line."""
    from xml.sax.saxutils import escape, quoteattr
    body = (f'<text x="5" y="50" rotate={quoteattr(rotate)} font-size={quoteattr(size)} '
            f'font-family={quoteattr(family)} style={quoteattr("font-family:" + family)} '
            f'letter-spacing={quoteattr(spacing)} xml:space="{space}">'
            f'{escape(content)}<tspan dy={quoteattr(dy)}>{escape(content[::-1])}</tspan>'
            f'</text><rect width="1" height="1"/>')
    try:
        drawing = load_svg(tmp_path, body)
    except DrawingError as error:
        assert "\n" not in str(error)
    else:
        assert all(np.isfinite(p).all() for p in drawing.paths)


def test_text_in_a_use_and_a_layer(tmp_path):
    """A text a <use> copies is marked where the copy is, on the use's layer; a text in an
    Inkscape layer is on it; a text in <defs> alone is not marked."""
    d = load_svg(tmp_path, '<defs><text id="t" x="0" y="10" font-size="8">A</text></defs>'
                           '<g inkscape:groupmode="layer" inkscape:label="Copies" '
                           'xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape">'
                           '<use xlink:href="#t" x="20"/></g>'
                           '<g inkscape:groupmode="layer" inkscape:label="Words" '
                           'xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape">'
                           '<text x="50" y="10" font-size="8" fill="#ff0000">B</text></g>')
    layers = {style.layer for style in d.styles}
    assert layers == {"Copies", "Words"} and not d.skipped
    copies = [p for p, s in zip(d.paths, d.styles) if s.layer == "Copies"]
    assert min(p[:, 0].min() for p in copies) > 20            # moved by the use, not at 0
    words = [s for s in d.styles if s.layer == "Words"]
    assert {s.colour for s in words} == {"#ff0000"}


def test_a_file_usvg_refuses_leaves_its_text_out_counted(tmp_path):
    """usvg reads no SVG of zero size: its texts are counted as left out, with usvg's
    reason; the shapes svgelements reads are still marked."""
    d = load_svg(tmp_path, '<text x="5" y="50">A</text><rect width="3" height="3"/>',
                 size='width="0" height="0"')
    assert len(d.paths) == 1
    assert d.skipped == ("1 text element left out (SVG has an invalid size.)",)
