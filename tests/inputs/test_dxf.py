"""The DXF reader (galvoscan/inputs/dxf.py): entities with known geometry, checked against their
equations and the curves written out in tests/support/drawings.py, not against ezdxf's own evaluation."""

import math

import numpy as np
import pytest

from drawings import bezier, chord_midpoints, distance_to_curve, load_dxf, new_dxf


def test_dxf_line_circle_arc(tmp_path):
    tol = 0.01
    doc, msp = new_dxf()
    msp.add_line((1, 2), (11, 2))
    msp.add_circle((1, 2), 5)
    msp.add_arc((0, 0), 10, 0, 90)
    line, circle, arc = load_dxf(tmp_path, doc, tolerance_mm=tol).paths
    np.testing.assert_allclose(line, [[1, 2], [11, 2]])
    r = np.hypot(circle[:, 0] - 1, circle[:, 1] - 2)
    np.testing.assert_allclose(r, 5, rtol=1e-12)
    assert np.all(np.hypot(*(chord_midpoints(circle) - (1, 2)).T) >= 5 - tol)
    assert len(circle) - 1 <= 2 * math.pi / math.acos(1 - tol / 5) + 8
    np.testing.assert_allclose(np.hypot(*arc.T), 10, rtol=1e-12)
    np.testing.assert_allclose(arc[[0, -1]], [[10, 0], [0, 10]], atol=1e-9)
    assert np.all(arc >= -1e-9)             # the first quadrant only
    assert np.all(np.hypot(*chord_midpoints(arc).T) >= 10 - tol)


def test_dxf_closed_flags(tmp_path):
    doc, msp = new_dxf()
    msp.add_line((0, 0), (1, 0))
    msp.add_circle((0, 0), 1)
    msp.add_lwpolyline([(0, 0), (1, 0), (1, 1)], close=True)
    msp.add_lwpolyline([(0, 0), (1, 0), (1, 1)])
    msp.add_ellipse((0, 0), major_axis=(2, 0), ratio=0.5)
    msp.add_ellipse((0, 0), major_axis=(2, 0), ratio=0.5, start_param=0, end_param=1)
    msp.add_spline().set_closed([(0, 0, 0), (4, 0, 0), (4, 4, 0), (0, 4, 0)])
    d = load_dxf(tmp_path, doc)
    assert d.closed == (False, True, True, False, True, False, True)
    for path, closed in zip(d.paths, d.closed):
        assert np.array_equal(path[0], path[-1]) == closed


def test_dxf_ellipse_on_the_ellipse(tmp_path):
    tol = 0.01
    doc, msp = new_dxf()
    msp.add_ellipse((3, 4), major_axis=(6, 8), ratio=0.5)    # a = 10, b = 5, turned atan2(8, 6)
    (p,) = load_dxf(tmp_path, doc, tolerance_mm=tol).paths
    turn = math.atan2(8, 6)
    t = np.linspace(0, 2 * np.pi, 40001)
    curve = np.column_stack([3 + 10 * np.cos(t) * math.cos(turn) - 5 * np.sin(t) * math.sin(turn),
                             4 + 10 * np.cos(t) * math.sin(turn) + 5 * np.sin(t) * math.cos(turn)])
    assert distance_to_curve(p, curve).max() < 1e-6
    assert distance_to_curve(chord_midpoints(p), curve).max() <= tol + 1e-6


def test_dxf_closed_spline_is_the_periodic_b_spline(tmp_path):
    """ezdxf's own flattening of a closed (periodic) spline loops far outside it; a uniform
    cubic B-spline passes through (P[i] + 4 P[i+1] + P[i+2]) / 6 and stays in the hull."""
    tol = 0.01
    controls = np.array([(0, 0), (4, 0), (4, 4), (0, 4)], dtype=float)
    doc, msp = new_dxf()
    msp.add_spline().set_closed([(x, y, 0) for x, y in controls])
    d = load_dxf(tmp_path, doc, tolerance_mm=tol)
    (p,) = d.paths
    assert d.closed == (True,)
    assert p.min() >= -1e-9 and p.max() <= 4 + 1e-9
    for i in range(4):
        knot_point = (controls[i] + 4 * controls[(i + 1) % 4] + controls[(i + 2) % 4]) / 6
        assert distance_to_curve([knot_point], p)[0] <= tol


def test_dxf_bulge_polyline(tmp_path):
    """(0,0) → (10,0) bulge +1 (a counter-clockwise half circle, below the chord), → (10,10),
    → (0,10) bulge −1 (clockwise, also below its chord: into the square), closed."""
    tol = 0.01
    doc, msp = new_dxf()
    msp.add_lwpolyline([(0, 0, 1), (10, 0, 0), (10, 10, -1), (0, 10, 0)], format="xyb",
                       close=True)
    (p,) = load_dxf(tmp_path, doc, tolerance_mm=tol).paths
    on_bottom = np.isclose(np.hypot(p[:, 0] - 5, p[:, 1]), 5) & (p[:, 1] <= 1e-9)
    on_top = np.isclose(np.hypot(p[:, 0] - 5, p[:, 1] - 10), 5) & (p[:, 1] <= 10 + 1e-9)
    on_sides = np.isclose(p[:, 0], 0) | np.isclose(p[:, 0], 10)
    assert np.all(on_bottom | on_top | on_sides)
    # In order and without doubling back: the length is two half circles and two sides.
    length = np.sum(np.hypot(*np.diff(p, axis=0).T))
    assert 20 + 10 * math.pi - 0.1 <= length <= 20 + 10 * math.pi
    for corner in [(0, 0), (10, 0), (10, 10), (0, 10)]:
        assert np.min(np.hypot(*(p - corner).T)) < 1e-9


def test_dxf_spline_on_its_bezier_and_through_fit_points(tmp_path):
    tol = 0.01
    controls = [(0, 0), (0, 40), (60, 40), (60, 0)]
    fit = [(0, 0), (10, 5), (20, -3), (30, 8), (40, 0)]
    doc, msp = new_dxf()
    msp.add_open_spline(controls, degree=3)     # clamped, one span: the cubic Bézier
    msp.add_spline(fit)
    cubic, through = load_dxf(tmp_path, doc, tolerance_mm=tol).paths
    curve = bezier(controls, np.linspace(0, 1, 20001))
    assert distance_to_curve(cubic, curve).max() < 1e-4
    assert distance_to_curve(chord_midpoints(cubic), curve).max() <= tol + 1e-4
    dense = np.concatenate([np.linspace(a, b, 200) for a, b in zip(through[:-1], through[1:])])
    assert distance_to_curve(np.array(fit, float), dense).max() <= tol


def test_dxf_insert_scaled_rotated_and_nested(tmp_path):
    doc, msp = new_dxf()
    square = doc.blocks.new("SQUARE")
    square.add_lwpolyline([(0, 0), (10, 0), (10, 10), (0, 10)], close=True)
    square.add_line((0, 0), (5, 0))
    outer = doc.blocks.new("OUTER")
    outer.add_blockref("SQUARE", (20, 0))
    msp.add_blockref("SQUARE", (100, 50), dxfattribs={"xscale": 2, "yscale": 2, "rotation": 90})
    msp.add_blockref("OUTER", (0, 0), dxfattribs={"xscale": 3, "yscale": 3})
    d = load_dxf(tmp_path, doc)
    assert d.closed == (True, False, True, False)
    turned, line, nested, nested_line = d.paths
    # (x, y) → 2·(−y, x) + (100, 50)
    assert {tuple(np.round(q, 9)) for q in turned} == {(100, 50), (100, 70), (80, 70), (80, 50)}
    np.testing.assert_allclose(line, [[100, 50], [100, 60]], atol=1e-9)
    assert {tuple(np.round(q, 9)) for q in nested} == {(60, 0), (90, 0), (90, 30), (60, 30)}
    np.testing.assert_allclose(nested_line, [[60, 0], [75, 0]], atol=1e-9)


def test_dxf_insert_non_uniform_scale_keeps_shapes_closed(tmp_path):
    """A circle in a block stretched 2 × 1 and turned 30° is an ellipse, still closed; a
    closed bulge polyline stays one closed path. The block's base point is honoured."""
    tol = 0.01
    doc, msp = new_dxf()
    block = doc.blocks.new("B", base_point=(1, 1))
    block.add_circle((1, 1), 3)
    block.add_lwpolyline([(1, 1, 1), (11, 1, 0), (11, 11, 0)], format="xyb", close=True)
    msp.add_blockref("B", (50, 50), dxfattribs={"xscale": 2, "yscale": 1, "rotation": 30})
    d = load_dxf(tmp_path, doc, tolerance_mm=tol)
    assert d.closed == (True, True)
    ellipse, polyline = d.paths
    turn = math.radians(30)
    # Back into block coordinates (relative to the base point), then the circle's equation.
    back = (ellipse - 50) @ np.array([[math.cos(turn), -math.sin(turn)],
                                      [math.sin(turn), math.cos(turn)]])
    np.testing.assert_allclose(np.hypot(back[:, 0] / 2, back[:, 1]), 3, rtol=1e-9)
    mid = (chord_midpoints(ellipse) - 50) @ np.array([[math.cos(turn), -math.sin(turn)],
                                                       [math.sin(turn), math.cos(turn)]])
    t = np.linspace(0, 2 * np.pi, 40001)
    curve = np.column_stack([6 * np.cos(t), 3 * np.sin(t)])
    assert distance_to_curve(mid, curve).max() <= tol
    assert np.min(np.hypot(*(polyline - (50, 50)).T)) < 1e-9      # the base point's corner


def test_dxf_minsert_grid(tmp_path):
    doc, msp = new_dxf()
    doc.blocks.new("DOT").add_line((0, 0), (1, 0))
    msp.add_blockref("DOT", (0, 0)).grid(size=(2, 3), spacing=(10, 20))
    starts = {tuple(np.round(p[0], 9)) for p in load_dxf(tmp_path, doc).paths}
    assert starts == {(x, y) for x in (0, 20, 40) for y in (0, 10)}


@pytest.mark.parametrize("insunits, mm", [(1, 25.4), (2, 304.8), (4, 1.0), (5, 10.0),
                                          (6, 1000.0)])
def test_dxf_units(tmp_path, insunits, mm):
    doc, msp = new_dxf(units=insunits)
    msp.add_line((0, 0), (1, 2))
    (p,) = load_dxf(tmp_path, doc).paths
    np.testing.assert_allclose(p, [[0, 0], [mm, 2 * mm]], rtol=1e-15)


def test_dxf_unitless_is_mm_with_a_note(tmp_path):
    doc, msp = new_dxf(units=0)
    msp.add_line((0, 0), (7, 0))
    d = load_dxf(tmp_path, doc)
    np.testing.assert_allclose(d.paths[0], [[0, 0], [7, 0]])
    assert d.notes == ("DXF has no units ($INSUNITS 0): taken as mm",)


def test_dxf_skipped_entities_and_hidden_layers(tmp_path):
    doc, msp = new_dxf()
    msp.add_line((0, 0), (10, 0))
    msp.add_text("A")
    msp.add_text("B")
    msp.add_mtext("C")
    msp.add_point((3, 3))
    doc.layers.add("OFF").off()
    doc.layers.add("FROZEN").freeze()
    msp.add_line((0, 0), (0, 10), dxfattribs={"layer": "OFF"})
    msp.add_circle((0, 0), 3, dxfattribs={"layer": "FROZEN"})
    d = load_dxf(tmp_path, doc)
    assert len(d.paths) > 3                 # the line, and the texts' glyphs
    assert set(d.skipped) == {"1 POINT entity", "2 entities on a hidden layer"}


def test_dxf_hatch_boundaries_are_closed_shapes(tmp_path):
    """A HATCH is marked as its boundaries, each a closed shape that --hatch can fill: a
    polyline boundary as its corners, an arc edge on its circle, a bulge on its arc."""
    doc, msp = new_dxf()
    hatch = msp.add_hatch()
    hatch.paths.add_polyline_path([(0, 0), (10, 0), (10, 10), (0, 10)], is_closed=True)
    edges = hatch.paths.add_edge_path()
    edges.add_arc((5, 5), 2, 0, 360)
    bulged = msp.add_hatch()
    # A half-disc: from (20, 0) to (30, 0) with a bulge of 1 (a half circle of radius 5).
    bulged.paths.add_polyline_path([(20, 0, 1), (30, 0, 0)], is_closed=True)
    tol = 0.01
    d = load_dxf(tmp_path, doc, tolerance_mm=tol)
    assert d.closed == (True, True, True)
    square, circle, half = d.paths
    assert {tuple(p) for p in np.round(square, 9)} == {(0, 0), (10, 0), (10, 10), (0, 10)}
    assert np.allclose(np.hypot(*(circle - (5, 5)).T), 2, atol=1e-9)
    assert np.all(np.hypot(*(chord_midpoints(circle) - (5, 5)).T) >= 2 - tol - 1e-9)
    on_arc = half[np.abs(half[:, 1]) > 1e-9]
    assert len(on_arc) > 10 and np.allclose(np.hypot(*(on_arc - (25, 0)).T), 5, atol=1e-9)
    assert np.all(np.hypot(*(chord_midpoints(half) - (25, 0)).T)[np.abs(
        chord_midpoints(half)[:, 1]) > 1e-9] >= 5 - tol - 1e-9)


def test_dxf_hatch_of_edges_either_way_is_one_closed_shape(tmp_path):
    """An edge boundary whose edges run either way (a line back, an ellipse, a line) is one
    closed shape through every edge, the ellipse on the ellipse."""
    doc, msp = new_dxf()
    hatch = msp.add_hatch()
    edges = hatch.paths.add_edge_path()
    edges.add_line((0, 0), (20, 0))
    edges.add_line((20, 10), (20, 0))                   # drawn backwards
    edges.add_ellipse((10, 10), major_axis=(10, 0), ratio=0.5, start_angle=0, end_angle=180)
    edges.add_line((0, 10), (0, 0))
    tol = 0.01
    (shape,) = load_dxf(tmp_path, doc, tolerance_mm=tol).paths
    corners = {(0, 0), (20, 0), (20, 10), (0, 10)}
    assert corners <= {tuple(p) for p in np.round(shape, 9)}
    top = shape[shape[:, 1] > 10 + 1e-9]
    assert len(top) > 10
    assert np.allclose(((top[:, 0] - 10) / 10) ** 2 + ((top[:, 1] - 10) / 5) ** 2, 1, atol=1e-9)
    steps = np.hypot(*np.diff(shape, axis=0).T)
    assert steps.max() <= 20 + 1e-9                     # no jump across the shape



def test_dxf_text_is_marked_as_its_glyphs(tmp_path):
    """TEXT, MTEXT (its lines) and a block reference's ATTRIB as closed glyph outlines: a
    TEXT's height is its capitals' (DXF's rule), where it is put; an MTEXT's second line
    below its first."""
    doc, msp = new_dxf()
    msp.add_text("HELL", height=5, dxfattribs={"insert": (10, 20)})     # flat letters
    d = load_dxf(tmp_path, doc)
    xmin, ymin, xmax, ymax = d.bounds()
    assert ymax - ymin == pytest.approx(5, rel=0.01) and ymin == pytest.approx(20, abs=0.05)
    assert xmin == pytest.approx(10, abs=0.8) and xmax - xmin > 12
    assert all(d.closed) and not d.skipped
    doc, msp = new_dxf()
    mtext = msp.add_mtext("TOP\\PLOW", dxfattribs={"char_height": 3})
    mtext.set_location((0, 0))
    d = load_dxf(tmp_path, doc)
    tops = sorted(p[:, 1].max() for p in d.paths)
    assert tops[-1] - tops[0] > 3           # two lines, one under the other
    doc, msp = new_dxf()
    block = doc.blocks.new("PLATE")
    block.add_line((0, 0), (30, 0))
    block.add_attdef("SN", (0, 2), dxfattribs={"height": 2})
    ref = msp.add_blockref("PLATE", (100, 100))
    ref.add_auto_attribs({"SN": "0042"})
    d = load_dxf(tmp_path, doc)
    glyphs = [p for p in d.paths if len(p) > 2]
    assert glyphs and min(p[:, 1].min() for p in glyphs) == pytest.approx(102, abs=0.2)
    assert d.skipped == ("1 attribute definition",)


def test_dxf_text_in_a_missing_font_or_with_missing_characters(tmp_path):
    """A style's font that is not installed is said (ezdxf marks the text in another); a text
    whose characters the font lacks is left out naming them, not marked as boxes."""
    doc, msp = new_dxf()
    doc.styles.add("NOFONT", font="nosuchfont.ttf")
    msp.add_text("OK", height=3, dxfattribs={"style": "NOFONT"})
    msp.add_text("日本", height=3, dxfattribs={"insert": (0, 10)})
    msp.add_line((0, 0), (1, 1))
    d = load_dxf(tmp_path, doc)
    said = " | ".join(d.skipped)
    assert "text entity in font nosuchfont.ttf, not installed: marked in" in said
    assert "text entity left out: '日本' not in font" in said
    assert max(p[:, 1].max() for p in d.paths) < 5          # the 日本 at y = 10 is not there


def test_a_drawing_too_large_names_the_units_the_file_gives(tmp_path):
    """ezdxf's new files are in metres: a 30 mm line drawn as 30 is 30 m, and the refusal
    says the size, the file's units, and the ways out."""
    from galvoscan.geometry.drawing import DrawingError
    doc, msp = new_dxf(units=6)
    msp.add_line((0, 0), (30, 0))
    with pytest.raises(DrawingError, match=r": 30 × 0 m \(its \$INSUNITS 6, metres\), more "
                                           r"than 10 m: give --units mm if its numbers are "
                                           r"millimetres, or --scale 0.33 or less$"):
        load_dxf(tmp_path, doc)
