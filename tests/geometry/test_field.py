"""Planning (galvoscan/geometry/field.py, hatch.py, order.py): placement, hatching, path order, galvo units and the field
check, each checked against geometry worked out here (own ray casting, analytic shapes). The
pitch choice and the estimates are in test_speed.py."""

from collections import Counter
import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from galvoscan.geometry.drawing import Drawing
from galvoscan.inputs.drawings import load_drawing
from galvoscan.geometry.field import Placement, PlanError, field_check, from_galvo, place, to_galvo
from galvoscan.geometry.hatch import hatch
from galvoscan.geometry.order import order_paths


def ring(points):
    points = np.asarray(points, dtype=float)
    return np.vstack([points, points[:1]])


def square(x0, y0, size):
    return ring([(x0, y0), (x0 + size, y0), (x0 + size, y0 + size), (x0, y0 + size)])


def even_odd_inside(points, rings):
    """Ray casting to +X, counting crossings of every ring edge: the even-odd rule. Takes one
    point or an (n, 2) array."""
    points = np.asarray(points, dtype=float)
    x, y = np.atleast_2d(points).T[:, :, None]
    crossings = 0
    for r in rings:
        (x1, y1), (x2, y2) = r[:-1].T, r[1:].T
        straddle = (y1 > y) != (y2 > y)
        with np.errstate(divide="ignore", invalid="ignore"):
            crossing_x = x1 + (y - y1) * (x2 - x1) / (y2 - y1)
        crossings = crossings + np.sum(straddle & (x < crossing_x), axis=1)
    inside = crossings % 2 == 1
    return bool(inside[0]) if points.ndim == 1 else inside


def distance_to_rings(points, rings):
    """Distance to the nearest ring edge, for one point or an (n, 2) array."""
    points = np.asarray(points, dtype=float)
    p = np.atleast_2d(points)[:, None, :]
    best = np.full(len(p), np.inf)
    for r in rings:
        a, ab = r[:-1], np.diff(r, axis=0)
        a, ab = a[np.any(ab != 0, axis=1)], ab[np.any(ab != 0, axis=1)]
        if not len(a):
            continue
        t = np.clip(np.sum((p - a) * ab, axis=2) / np.sum(ab * ab, axis=1), 0, 1)
        best = np.minimum(best, np.min(np.hypot(*np.moveaxis(a + t[..., None] * ab - p, 2, 0)),
                                       axis=1))
    return float(best[0]) if points.ndim == 1 else best


def samples(line, count=9):
    a, b = line
    return [a + (b - a) * s for s in np.linspace(0.05, 0.95, count)]


# --- placement --------------------------------------------------------------------------------

def test_placement_centre_lower_left_and_turn():
    bounds = (10, 20, 30, 60)                   # 20 × 40 mm, centre (20, 40)
    corners = np.array([[10, 20], [30, 60], [20, 40]], dtype=float)
    centred = Placement(offset_mm=(1, 2)).forward(corners, bounds)
    np.testing.assert_allclose(centred, [[-9, -18], [11, 22], [1, 2]])
    lower_left = Placement("lower-left", (5, 5), scale=2).forward(corners, bounds)
    np.testing.assert_allclose(lower_left, [[5, 5], [45, 85], [25, 45]])
    # A quarter turn: the 40 mm tall box lies down, 80 × 40 at scale 2, lower-left at (5, 5).
    turned = Placement("lower-left", (5, 5), scale=2, rotate_deg=90).forward(corners, bounds)
    np.testing.assert_allclose(turned, [[85, 5], [5, 45], [45, 25]], atol=1e-12)
    assert Placement("center").origin == "centre"
    # page: the drawing's own coordinates, its origin on the offset, turned about it.
    page = Placement("page", (1, 2)).forward(corners, bounds)
    np.testing.assert_allclose(page, corners + (1, 2))
    turned_page = Placement("page", (0, 0), scale=2, rotate_deg=90).forward(corners, bounds)
    np.testing.assert_allclose(turned_page, [[-40, 20], [-120, 60], [-80, 40]], atol=1e-12)


@pytest.mark.parametrize("kwargs", [dict(origin="top"), dict(scale=0), dict(scale=-1),
                                    dict(offset_mm=(math.nan, 0)), dict(rotate_deg=math.inf)])
def test_placement_refuses(kwargs):
    with pytest.raises(PlanError):
        Placement(**kwargs)


finite = st.floats(-500, 500, allow_nan=False)


@settings(max_examples=200, deadline=None)
@given(origin=st.sampled_from(["centre", "lower-left", "page"]), offset=st.tuples(finite, finite),
       scale=st.floats(0.01, 100), turn=st.floats(-720, 720),
       box=st.tuples(finite, finite, st.floats(0.001, 500), st.floats(0.001, 500)),
       points=st.lists(st.tuples(finite, finite), min_size=1, max_size=8))
def test_placement_inverse_undoes_forward(origin, offset, scale, turn, box, points):
    x, y, w, h = box
    bounds = (x, y, x + w, y + h)
    placement = Placement(origin, offset, scale, turn)
    points = np.array(points)
    back = placement.inverse(placement.forward(points, bounds), bounds)
    np.testing.assert_allclose(back, points, atol=1e-9 * (1 + scale + 1 / scale) * 1000)
    # It is a similarity: distances scale by `scale`.
    moved = placement.forward(points, bounds)
    if len(points) > 1:
        np.testing.assert_allclose(np.hypot(*(moved[1] - moved[0])),
                                   scale * np.hypot(*(points[1] - points[0])), atol=1e-6)


def test_place_keeps_the_drawing_and_moves_its_paths():
    drawing = Drawing("d.svg", (square(10, 10, 10), np.array([[0.0, 0], [4, 0]])),
                      (True, False), ("1 text element",), ("note",))
    placed = place(drawing, Placement())
    assert placed.closed == drawing.closed and placed.skipped == drawing.skipped
    assert placed.name == "d.svg" and placed.notes == ("note",)
    np.testing.assert_allclose(placed.bounds(), (-10, -10, 10, 10))
    assert not placed.paths[0].flags.writeable


# --- hatching ---------------------------------------------------------------------------------

def test_hatch_square_is_the_expected_lines():
    lines = hatch([square(0, 0, 10)], [True], 1.0)
    ys = sorted(line[0, 1] for line in lines)
    np.testing.assert_allclose(ys, np.arange(10) + 0.5)
    for line in lines:
        np.testing.assert_allclose(sorted(line[:, 0]), [0, 10], atol=1e-12)


def test_hatch_leaves_holes_and_matches_the_area():
    outer, hole = square(0, 0, 10), square(3, 3, 4)
    lines = hatch([outer, hole], [True, True], 1.0)
    for line in lines:
        for p in samples(line):
            assert 0 < p[0] < 10 and 0 < p[1] < 10
            assert not (3 < p[0] < 7 and 3 < p[1] < 7)
    # Lines 1 mm apart through the middle of each 1 mm band: total length = area / spacing.
    total = sum(np.hypot(*(b - a)) for a, b in lines)
    assert total == pytest.approx(100 - 16, abs=1e-9)


def test_open_paths_are_not_hatched():
    assert hatch([np.array([[0.0, 0], [10, 0], [10, 10]])], [False], 1.0) == []


@pytest.mark.parametrize("angle", [0, 30, 45, 90, 137.5, -60])
def test_hatch_circle_at_angles_spacing_and_inside(angle):
    t = np.linspace(0, 2 * np.pi, 400)[:-1]
    circle = ring(np.column_stack([5 * np.cos(t) + 2, 5 * np.sin(t) - 1]))
    spacing = 0.37
    lines = hatch([circle], [True], spacing, angle)
    direction = np.array([math.cos(math.radians(angle)), math.sin(math.radians(angle))])
    normal = np.array([-direction[1], direction[0]])
    offsets = []
    for a, b in lines:
        along = (b - a) / np.hypot(*(b - a))
        assert abs(abs(along @ direction) - 1) < 1e-9
        for p in samples((a, b)):
            assert np.hypot(p[0] - 2, p[1] + 1) < 5
        # The ends are on the circle (the 399-gon, within its sagitta).
        for end in (a, b):
            assert distance_to_rings(end, [circle]) < 1e-9
        offsets.append(a @ normal)
    steps = np.diff(np.unique(np.round(offsets, 9)))
    np.testing.assert_allclose(steps, spacing, atol=1e-6)
    assert abs(len(steps) + 1 - 10 / spacing) <= 1           # the 10 mm across, filled


def test_hatch_pentagram_leaves_its_centre_even_odd():
    turns = np.arange(5) * 4 * np.pi / 5 + np.pi / 2
    star = ring(10 * np.column_stack([np.cos(turns), np.sin(turns)]))
    lines = hatch([star], [True], 0.5)
    assert lines
    for line in lines:
        for p in samples(line):
            assert even_odd_inside(p, [star])
    # The centre pentagon (even-odd: crossed twice) gets no line through the middle.
    for a, b in lines:
        if abs(a[1]) < 0.5:
            xs = sorted([a[0], b[0]])
            assert not xs[0] < 0 < xs[1]


@st.composite
def polygons(draw):
    count = draw(st.integers(1, 3))
    rings = []
    for _ in range(count):
        points = draw(st.lists(st.tuples(st.integers(-20, 20), st.integers(-20, 20)),
                               min_size=3, max_size=7))
        rings.append(ring(np.array(points, dtype=float) + 0.125))     # off the scan lines
    return rings


@settings(max_examples=80, deadline=None)
@given(rings=polygons(), spacing=st.sampled_from([0.7, 1.3, 2.9]))
def test_hatch_is_the_even_odd_region_on_every_line(rings, spacing):
    """On each hatch line's level, a point is covered by a line if and only if it is inside by
    the even-odd rule (own ray casting), away from the edges."""
    lines = hatch(rings, [True] * len(rings), spacing)
    if lines:
        inner = np.concatenate([samples(line, 5) for line in lines])
        clear = distance_to_rings(inner, rings) > 1e-6
        assert even_odd_inside(inner[clear], rings).all()
    levels = sorted({round(float(line[0, 1]), 9) for line in lines})
    if len(levels) > 1:
        np.testing.assert_allclose(np.diff(levels) / spacing,
                                   np.round(np.diff(levels) / spacing), atol=1e-6)
    xs = np.linspace(-21, 21, 85) + 0.0123
    for y in levels:
        on_level = [np.sort(line[:, 0]) for line in lines if abs(line[0, 1] - y) < 1e-9]
        points = np.column_stack([xs, np.full(len(xs), y)])
        clear = distance_to_rings(points, rings) > 1e-6
        covered = np.array([any(a < x < b for a, b in on_level) for x in xs])
        assert np.array_equal(covered[clear], even_odd_inside(points, rings)[clear])


def test_svg_with_a_hole_hatched_end_to_end(tmp_path):
    path = tmp_path / "hole.svg"
    path.write_text('<svg xmlns="http://www.w3.org/2000/svg" width="20mm" height="20mm" '
                    'viewBox="0 0 20 20"><path d="M0,0 H20 V20 H0 Z M5,5 H15 V15 H5 Z"/></svg>')
    placed = place(load_drawing(path), Placement())
    lines = hatch(placed.paths, placed.closed, 0.5, 45)
    assert lines
    for line in lines:
        for p in samples(line):
            assert max(abs(p)) < 10 + 1e-6 and max(abs(p)) > 5 - 1e-6


@pytest.mark.parametrize("spacing", [0, -1, math.nan])
def test_hatch_refuses_bad_spacing(spacing):
    with pytest.raises(PlanError):
        hatch([square(0, 0, 1)], [True], spacing)
    with pytest.raises(PlanError, match="not finite"):
        hatch([ring([(0, 0), (1, math.nan), (1, 1)])], [True], 0.1)


# --- path order -------------------------------------------------------------------------------

def jumps(paths, start=(0.0, 0.0)):
    here, total = np.array(start, dtype=float), 0.0
    for p in paths:
        total += math.hypot(*(p[0] - here))
        here = p[-1]
    return total


def canonical(path, closed):
    """The same path whatever its direction (open) or starting vertex (closed)."""
    points = [tuple(map(float, q)) for q in path]
    if closed:
        cycle = points[:-1]
        return min(tuple(cycle[k:] + cycle[:k]) for k in range(len(cycle)))
    return min(tuple(points), tuple(points[::-1]))


def test_order_paths_small_example():
    a = np.array([[10.0, 0], [20, 0]])
    b = np.array([[1.0, 0], [2, 0]])
    c = square(30, -1, 2)
    ordered, before, after = order_paths([a, c, b], [False, True, False])
    np.testing.assert_allclose(ordered[0], b)
    np.testing.assert_allclose(ordered[1], a)
    np.testing.assert_allclose(ordered[2][0], [30, -1])  # the nearest corner of the square
    assert before == pytest.approx(jumps([a, c, b]))
    assert after == pytest.approx(1 + 8 + math.hypot(10, 1))


def test_order_paths_reverses_open_paths_and_rotates_closed_ones():
    far = np.array([[50.0, 0], [1, 0]])
    box = square(-5, -5, 10)[::-1]
    ordered, _, after = order_paths([far], [False])
    np.testing.assert_allclose(ordered[0], far[::-1])
    assert after == pytest.approx(1)
    ordered, _, _ = order_paths([box], [True], start=(6, 6))
    assert tuple(ordered[0][0]) == (5, 5) and tuple(ordered[0][-1]) == (5, 5)
    assert order_paths([], []) == ([], 0.0, 0.0)


coordinate = st.floats(-50, 50, allow_nan=False).map(lambda v: round(v, 3))


@st.composite
def path_sets(draw):
    paths, closed = [], []
    for _ in range(draw(st.integers(0, 12))):
        points = draw(st.lists(st.tuples(coordinate, coordinate), min_size=2, max_size=6,
                               unique=True))
        is_closed = draw(st.booleans()) and len(points) >= 3
        paths.append(ring(points) if is_closed else np.array(points, dtype=float))
        closed.append(is_closed)
    start = draw(st.tuples(coordinate, coordinate))
    return paths, closed, start


@settings(max_examples=200, deadline=None)
@given(case=path_sets())
def test_order_paths_never_worse_and_keeps_every_path(case):
    paths, closed, start = case
    ordered, before, after = order_paths(paths, closed, start)
    assert before == pytest.approx(jumps(paths, start))
    assert after == pytest.approx(jumps(ordered, start))
    assert after <= before + 1e-9
    was = Counter(canonical(p, c) for p, c in zip(paths, closed))
    now = Counter()
    for p in ordered:
        as_closed = len(p) > 2 and np.array_equal(p[0], p[-1])
        key = canonical(p, as_closed)
        now[key if key in was else canonical(p, False)] += 1
    assert now == was


# --- galvo units, field, estimate -------------------------------------------------------------

def test_to_and_from_galvo():
    units = to_galvo([[0, 0], [27.5, -27.5], [-55, 54.99]], 110)
    assert units.dtype.kind == "i"
    assert units.tolist() == [[32768, 32768], [49152, 16384], [0, 65530]]
    np.testing.assert_allclose(from_galvo(units, 110)[:2], [[0, 0], [27.5, -27.5]])
    with pytest.raises(PlanError):
        to_galvo([[55, 0]], 110)


def test_field_check_at_the_edges():
    micron = 1e-3
    field_check([np.array([[-55.0, -55.0], [55 - micron, 55 - micron]])], 110)
    for bad in ([-55 - micron, 0], [55 + micron, 0], [0, -55 - micron], [0, 55 + micron]):
        with pytest.raises(PlanError):
            field_check([np.array([[0.0, 0.0], bad])], 110)
    with pytest.raises(PlanError) as info:
        field_check([np.array([[-60.0, -5.0], [60.0, 5.0]])], 110)
    assert str(info.value) == ("the drawing spans X \u221260.0…60.0 mm, Y \u22125.0…5.0 mm "
                               "after placement; the field is \u221255.0…55.0 mm (110 mm lens)")
    with pytest.raises(PlanError, match="55.001"):
        field_check([np.array([[55 + micron, 0.0]])], 110)
