"""Loading drawings: SVG and DXF files with known geometry, checked against the analytic shapes
(not against the libraries), and bad files, which must give a DrawingError and nothing else."""

import math
import os

import ezdxf
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from galvoscan.jobs.drawing import Drawing, DrawingError, load_drawing


# svgelements converts mm with 96 px/in × 0.0393701 in/mm (not 1/25.4): 0.54 ppm off, so SVG
# positions are compared to 0.1 µm (54 nm at 100 mm) and lengths to 0.6 ppm.
SVG_MM = 0.6e-6
SVG_ATOL = 1e-4


def svg(body, *, size='width="100mm" height="100mm" viewBox="0 0 100 100"'):
    return (f'<svg xmlns="http://www.w3.org/2000/svg" '
            f'xmlns:xlink="http://www.w3.org/1999/xlink" {size}>{body}</svg>')


def load_svg(tmp_path, body, name="t.svg", **kwargs):
    size = kwargs.pop("size", None)
    path = tmp_path / name
    path.write_text(svg(body) if size is None else svg(body, size=size))
    return load_drawing(path, **kwargs)


def new_dxf(units=4):
    doc = ezdxf.new("R2010", units=units)
    return doc, doc.modelspace()


def load_dxf(tmp_path, doc, name="t.dxf", **kwargs):
    path = tmp_path / name
    doc.saveas(path)
    return load_drawing(path, **kwargs)


def chord_midpoints(points):
    return (points[1:] + points[:-1]) / 2


def distance_to_curve(points, curve):
    """Distance from each point to a curve given as a dense polyline (an (m, 2) array)."""
    a, ab = curve[:-1], np.diff(curve, axis=0)
    a, ab = a[np.any(ab != 0, axis=1)], ab[np.any(ab != 0, axis=1)]
    out = []
    for p in np.asarray(points, dtype=float):
        t = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.einsum("ij,ij->i", ab, ab), 0, 1)
        out.append(np.min(np.hypot(*(a + t[:, None] * ab - p).T)))
    return np.array(out)


def bezier(controls, t):
    """De Casteljau, written out here so the check does not use the loader's evaluation."""
    p = [np.asarray(c, dtype=float) for c in controls]
    t = np.asarray(t)[:, None]
    while len(p) > 1:
        p = [(1 - t) * a + t * b for a, b in zip(p[:-1], p[1:])]
    return p[0]


# --- SVG geometry -----------------------------------------------------------------------------

def test_svg_rect_is_a_closed_10mm_square_y_up(tmp_path):
    d = load_svg(tmp_path, '<rect x="10" y="20" width="10" height="10"/>')
    assert isinstance(d, Drawing) and d.name == "t.svg"
    assert d.closed == (True,)
    (p,) = d.paths
    assert p.shape == (5, 2) and np.array_equal(p[0], p[-1])
    corners = {(10, -20), (20, -20), (20, -30), (10, -30)}
    assert {tuple(np.round(q, 4)) for q in p} == corners
    np.testing.assert_allclose(d.bounds(), (10, -30, 20, -20), atol=SVG_ATOL)
    assert not p.flags.writeable


@pytest.mark.parametrize("tolerance_mm", [0.1, 0.01, 0.001])
def test_svg_circle_chords_within_tolerance(tmp_path, tolerance_mm):
    d = load_svg(tmp_path, '<circle cx="50" cy="50" r="5"/>', tolerance_mm=tolerance_mm)
    (p,) = d.paths
    assert d.closed == (True,)
    r = np.hypot(p[:, 0] - 50, p[:, 1] + 50)
    np.testing.assert_allclose(r, 5, atol=SVG_ATOL)
    assert np.all(np.hypot(*(chord_midpoints(p) - (50, -50)).T) >= 5 - tolerance_mm - SVG_ATOL)
    fewest = math.pi / math.acos(1 - tolerance_mm / 5)        # chords of exactly the tolerance
    assert fewest <= len(p) - 1 <= 2 * fewest + 8


def test_svg_path_arc_and_cubic_within_tolerance(tmp_path):
    tol = 0.01
    d = load_svg(tmp_path, '<path d="M 10 50 A 20 20 0 0 1 50 50"/>'
                           '<path d="M 0 0 C 0 40 60 40 60 0"/>', tolerance_mm=tol)
    arc, cubic = d.paths
    assert d.closed == (False, False)
    # The arc: centre (30, 50), radius 20, over the top (SVG y down: y < 50, so Y up > -50).
    r = np.hypot(arc[:, 0] - 30, arc[:, 1] + 50)
    np.testing.assert_allclose(r, 20, atol=SVG_ATOL)
    assert np.all(arc[:, 1] >= -50 - SVG_ATOL)
    assert np.all(np.hypot(*(chord_midpoints(arc) - (30, -50)).T) >= 20 - tol - SVG_ATOL)
    # The cubic against de Casteljau on the same control points (flipped to Y up).
    curve = bezier([(0, 0), (0, -40), (60, -40), (60, 0)], np.linspace(0, 1, 20001))
    assert distance_to_curve(cubic, curve).max() < 1e-4
    assert distance_to_curve(chord_midpoints(cubic), curve).max() <= tol + 1e-4


def test_svg_skewed_ellipse_is_the_true_ellipse(tmp_path):
    """svgelements' Arc.point is 0.75 mm off here; the loader must not be."""
    tol = 0.01
    d = load_svg(tmp_path, '<ellipse cx="50" cy="25" rx="10" ry="5" transform="skewX(20)"/>',
                 tolerance_mm=tol)
    (p,) = d.paths
    t = np.linspace(0, 2 * np.pi, 40001)
    k = math.tan(math.radians(20))
    curve = np.column_stack([50 + 10 * np.cos(t) + k * (25 + 5 * np.sin(t)),
                             -(25 + 5 * np.sin(t))])
    assert distance_to_curve(p, curve).max() < 2e-4
    assert distance_to_curve(chord_midpoints(p), curve).max() <= tol + 2e-4


@pytest.mark.parametrize("transform, centre", [
    ("translate(100,0) scale(-1,1)", (70, 50)),                 # mirrored: sweep flips
    ("rotate(30 30 50) scale(1,1)", (30, 50)),
])
def test_svg_half_circle_arcs_keep_their_side(tmp_path, transform, centre):
    """A half circle lands on its end both ways round, so only the sweep says which way."""
    d = load_svg(tmp_path, f'<path d="M 10 50 A 20 20 0 0 1 50 50" transform="{transform}"/>')
    (arc,) = d.paths
    np.testing.assert_allclose(np.hypot(arc[:, 0] - centre[0], arc[:, 1] + centre[1]), 20,
                               atol=SVG_ATOL)
    # Its middle point is the top of the circle (SVG y - 20) turned with the transform.
    turn = math.radians(30) if "rotate" in transform else 0.0
    top = (centre[0] + 20 * math.sin(turn), -(centre[1] - 20 * math.cos(turn)))
    assert np.min(np.hypot(*(arc - top).T)) < 0.2


def test_svg_nested_group_transforms(tmp_path):
    d = load_svg(tmp_path, '<g transform="translate(30,40)"><g transform="rotate(90)">'
                           '<line x1="0" y1="0" x2="5" y2="0" transform="scale(2)"/></g></g>')
    (p,) = d.paths
    # (0,0)→(10,0) scaled, turned 90° (y down: +x goes to +y), moved: (30,40)→(30,50).
    np.testing.assert_allclose(p, [[30, -40], [30, -50]], atol=SVG_ATOL)


@pytest.mark.parametrize("size, mm_per_unit", [
    ('width="100mm" height="100mm" viewBox="0 0 100 100"', 1.0),
    ('width="50mm" height="50mm" viewBox="0 0 100 100"', 0.5),
    ('width="1in" height="1in" viewBox="0 0 100 100"', 0.254),
    ('', 25.4 / 96),                                            # no units: px at 96 ppi
])
def test_svg_units(tmp_path, size, mm_per_unit):
    d = load_svg(tmp_path, '<line x1="0" y1="0" x2="96" y2="0"/>', size=size)
    (p,) = d.paths
    assert p[1, 0] - p[0, 0] == pytest.approx(96 * mm_per_unit, rel=SVG_MM)


def test_svg_y_up(tmp_path):
    d = load_svg(tmp_path, '<line x1="0" y1="10" x2="0" y2="90"/>')
    (p,) = d.paths
    assert p[0, 1] > p[1, 1]                # down the page is down the field


def test_svg_path_with_hole_gives_two_closed_paths(tmp_path):
    d = load_svg(tmp_path, '<path d="M0,0 H10 V10 H0 Z M3,3 H7 V7 H3 Z" fill-rule="evenodd"/>')
    assert d.closed == (True, True)
    assert [len(p) for p in d.paths] == [5, 5]


def test_svg_open_path_that_returns_to_its_start_is_closed(tmp_path):
    d = load_svg(tmp_path, '<polyline points="0,0 0,0 5,0 5,0 5,5 0,0"/>'
                           '<polyline points="0,0 0,0 5,0 5,0 5,5"/>')
    assert d.closed == (True, False)
    assert [len(p) for p in d.paths] == [4, 3]          # consecutive duplicates removed


def test_svg_skipped_and_hidden(tmp_path):
    d = load_svg(tmp_path, '<text x="1" y="1">a</text><text x="1" y="5">b</text>'
                           '<image href="x.png" width="5" height="5"/>'
                           '<line x1="0" y1="0" x2="5" y2="5"/>'
                           '<line x1="1" y1="1" x2="1" y2="1"/>'
                           '<g style="display:none"><rect width="50" height="50"/></g>'
                           '<rect width="60" height="60" visibility="hidden"/>'
                           '<defs><rect id="r" width="70" height="70"/></defs>')
    assert len(d.paths) == 1
    assert set(d.skipped) == {"2 text elements (convert text to paths)", "1 image element",
                              "1 hidden element", "1 zero-length path"}


def test_svg_use_of_a_def_is_marked(tmp_path):
    d = load_svg(tmp_path, '<defs><rect id="r" width="10" height="10"/></defs>'
                           '<use xlink:href="#r" x="20" y="0"/>')
    (p,) = d.paths
    np.testing.assert_allclose(d.bounds(), (20, -10, 30, 0), atol=SVG_ATOL)


# --- DXF geometry -----------------------------------------------------------------------------

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
    hatch = msp.add_hatch()
    hatch.paths.add_polyline_path([(0, 0), (1, 0), (1, 1)])
    msp.add_point((3, 3))
    doc.layers.add("OFF").off()
    doc.layers.add("FROZEN").freeze()
    msp.add_line((0, 0), (0, 10), dxfattribs={"layer": "OFF"})
    msp.add_circle((0, 0), 3, dxfattribs={"layer": "FROZEN"})
    d = load_dxf(tmp_path, doc)
    assert len(d.paths) == 1
    assert set(d.skipped) == {"3 text entities (explode text to lines)", "1 HATCH entity",
                              "1 POINT entity", "2 entities on a hidden layer"}


# --- bad input --------------------------------------------------------------------------------

def refused(path, match=None):
    with pytest.raises(DrawingError) as info:
        load_drawing(path)
    message = str(info.value)
    assert "\n" not in message and message.startswith(str(path) + ": ")
    if match:
        assert match in message
    return message


def test_bad_paths(tmp_path):
    refused(tmp_path / "missing.svg", "no such file")
    (tmp_path / "folder.dxf").mkdir()
    refused(tmp_path / "folder.dxf", "a folder")
    (tmp_path / "empty.svg").write_bytes(b"")
    refused(tmp_path / "empty.svg", "empty file")
    (tmp_path / "blank.dxf").write_bytes(b"  \n\n ")
    refused(tmp_path / "blank.dxf", "empty file")
    (tmp_path / "x.png").write_bytes(b"\x89PNG\r\n")
    assert refused(tmp_path / "x.png") == \
        f"{tmp_path / 'x.png'}: not a drawing galvoscan reads (.svg, .dxf, .job)"
    (tmp_path / "garbage.svg").write_bytes(b"garbage\x00\xff")
    refused(tmp_path / "garbage.svg", "not a readable SVG file")
    (tmp_path / "garbage.dxf").write_bytes(b"garbage\x00\xff\n1\n2\n")
    refused(tmp_path / "garbage.dxf", "not a readable DXF file")


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() == 0,
                    reason="root reads files whatever their permissions")
def test_unreadable_file(tmp_path):
    path = tmp_path / "locked.svg"
    path.write_text(svg('<line x1="0" y1="0" x2="5" y2="5"/>'))
    path.chmod(0)
    refused(path, "cannot read")


def test_nothing_to_mark(tmp_path):
    (tmp_path / "blank.svg").write_text(svg('<text x="0" y="0">only text</text>'))
    refused(tmp_path / "blank.svg", "no lines or curves to mark")
    doc, msp = new_dxf()
    msp.add_text("only text")
    doc.saveas(tmp_path / "blank.dxf")
    refused(tmp_path / "blank.dxf", "no lines or curves to mark")


def test_absurd_size_and_non_finite(tmp_path):
    doc, msp = new_dxf(units=6)                 # metres
    msp.add_line((0, 0), (11, 0))
    doc.saveas(tmp_path / "big.dxf")
    refused(tmp_path / "big.dxf", "check the drawing's units")
    (tmp_path / "inf.svg").write_text(svg('<line x1="0" y1="0" x2="1e400" y2="5"/>'))
    refused(tmp_path / "inf.svg", "not finite")


def test_damaged_dxf_value_is_refused_with_what_ezdxf_found(tmp_path):
    """ezdxf reads "1.5x" as 1.5 but counts it an error: a damaged file is not marked."""
    doc, msp = new_dxf()
    msp.add_line((1.5, 0), (3, 0))
    doc.saveas(tmp_path / "ok.dxf")
    text = (tmp_path / "ok.dxf").read_text()
    assert text.count("\n1.5\n") == 1
    (tmp_path / "damaged.dxf").write_text(text.replace("\n1.5\n", "\n1.5x\n"))
    refused(tmp_path / "damaged.dxf", 'damaged DXF (recovered invalid floating point value "1.5x"')


@pytest.fixture(scope="module")
def valid(tmp_path_factory):
    """A folder for the cases, and valid files of each kind to damage."""
    folder = tmp_path_factory.mktemp("drawings")
    doc, msp = new_dxf()
    msp.add_lwpolyline([(0, 0, 1), (10, 0, 0), (10, 10, 0)], format="xyb", close=True)
    msp.add_circle((5, 5), 2)
    msp.add_spline([(0, 0), (3, 4), (6, 0)])
    msp.add_text("skip me")
    doc.saveas(folder / "valid.dxf")
    return folder, {
        ".svg": svg('<g transform="rotate(10)"><path d="M0,0 H10 V10 H0 Z M3,3 H7 V7 H3 Z"/>'
                    '<circle cx="5" cy="5" r="2"/><text>t</text></g>').encode(),
        ".dxf": (folder / "valid.dxf").read_bytes(),
    }


def only_drawing_errors(folder, data, suffix):
    path = folder / f"case{suffix}"
    path.write_bytes(data)
    try:
        drawing = load_drawing(path)
    except DrawingError as error:
        assert "\n" not in str(error)
        return
    for p in drawing.paths:                 # what does load must be sane
        assert p.ndim == 2 and p.shape[1] == 2 and len(p) >= 2 and np.isfinite(p).all()


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(suffix=st.sampled_from([".svg", ".dxf"]), fraction=st.floats(0, 1))
def test_truncated_files_give_drawing_errors_only(valid, suffix, fraction):
    folder, files = valid
    data = files[suffix]
    only_drawing_errors(folder, data[:int(len(data) * fraction)], suffix)


@settings(max_examples=60, deadline=None)
@given(suffix=st.sampled_from([".svg", ".dxf"]), data=st.binary(max_size=400))
def test_garbage_gives_drawing_errors_only(valid, suffix, data):
    only_drawing_errors(valid[0], data, suffix)


@settings(max_examples=40, deadline=None)
@given(suffix=st.sampled_from([".svg", ".dxf"]), position=st.floats(0, 1),
       junk=st.binary(min_size=1, max_size=20))
def test_corrupted_files_give_drawing_errors_only(valid, suffix, position, junk):
    folder, files = valid
    data = files[suffix]
    at = int(len(data) * position)
    only_drawing_errors(folder, data[:at] + junk + data[at + len(junk):], suffix)
