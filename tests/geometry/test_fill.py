"""Fills (galvoscan/geometry/fill.py): hatch sets in their line orders, cross-hatch and the angle
step a pass, contour rings; checked against the shapes' own geometry, worked out here."""

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from galvoscan.geometry.fill import Contour, HatchSet, LineOrder, contour_rings, hatch_strokes
from galvoscan.geometry.field import PlanError


def square(half, centre=(0.0, 0.0)):
    cx, cy = centre
    return np.array([(cx - half, cy - half), (cx + half, cy - half), (cx + half, cy + half),
                     (cx - half, cy + half), (cx - half, cy - half)])


SQUARE = [square(5)]
ANNULUS = [square(5), square(2)]          # even-odd: the inner square is a hole


def directions(strokes):
    return [math.copysign(1, s[-1][0] - s[0][0]) for s in strokes]


def test_serpentine_and_oneway_lines_of_a_square():
    """A 10 mm square at 1 mm: ten lines 1 mm apart, centred across it (0.5 mm in from its
    edges), each the width of the square; serpentine turns every line, oneway none."""
    for order, want in [(LineOrder.SERPENTINE, [1, -1] * 5), (LineOrder.ONEWAY, [1] * 10)]:
        strokes = hatch_strokes(SQUARE, [True], HatchSet(1.0), order=order)
        assert len(strokes) == 10
        ys = [s[0][1] for s in strokes]
        assert ys == pytest.approx(np.arange(-4.5, 5, 1.0))
        assert all(s[0][1] == s[1][1] for s in strokes)
        assert all(abs(s[0][0]) == pytest.approx(5) and abs(s[1][0]) == pytest.approx(5)
                   for s in strokes)
        assert directions(strokes) == want


def test_angle_and_offset_move_the_lines():
    """At 90° the lines are vertical; an offset of 0.25 mm moves them across by that much."""
    vertical = hatch_strokes(SQUARE, [True], HatchSet(1.0, 90))
    assert all(s[0][0] == pytest.approx(s[1][0]) for s in vertical)
    xs = sorted(s[0][0] for s in vertical)
    moved = sorted(s[0][1] for s in hatch_strokes(SQUARE, [True], HatchSet(1.0, 0, 0, 0.25)))
    # At 0° "across" is +Y: every line 0.25 mm up, and the square still covered.
    assert moved == pytest.approx(np.arange(-4.25, 5, 1.0))
    assert xs == pytest.approx(np.arange(-4.5, 5, 1.0))


def test_the_angle_step_turns_each_pass():
    hatch_set = HatchSet(1.0, 30, 90)
    assert [hatch_set.angle_on_pass(k) for k in range(5)] == [30, 120, 210, 300, 30]
    first = hatch_strokes(SQUARE, [True], hatch_set, pass_index=0)
    second = hatch_strokes(SQUARE, [True], hatch_set, pass_index=1)
    for strokes, angle in [(first, 30), (second, 120)]:
        d = strokes[0][-1] - strokes[0][0]
        assert abs(math.sin(math.atan2(d[1], d[0]) - math.radians(angle))) < 1e-9


def test_joined_lines_step_along_the_edge_never_across_a_hole():
    """Joined, a square's lines are one stroke, each step from one line to the next along
    the square's edge; an annulus's steps never cross the hole."""
    (stroke,) = hatch_strokes(SQUARE, [True], HatchSet(1.0), order=LineOrder.JOINED)
    assert len(stroke) == 20
    steps = [(a, b) for a, b in zip(stroke, stroke[1:]) if a[1] != b[1]]
    assert len(steps) == 9
    assert all(abs(a[0]) == pytest.approx(5) and a[0] == b[0] for a, b in steps)
    strokes = hatch_strokes(ANNULUS, [True, True], HatchSet(1.0), order=LineOrder.JOINED)
    for s in strokes:
        for a, b in zip(s, s[1:]):
            mid = (a + b) / 2
            assert not (abs(mid[0]) < 2 and abs(mid[1]) < 2), (a, b)     # not in the hole
    assert 1 < len(strokes) < 12


def test_contour_rings_of_a_square_and_an_annulus():
    """Rings 1 mm inward: a 10 mm square gives squares of half-width 4, 3, 2, 1; the annulus
    gives them outside the hole and rings around it, 1 mm out, while they fit."""
    rings = contour_rings(SQUARE, [True], Contour(1.0))
    halves = sorted(np.max(np.abs(r)) for r in rings)
    assert halves == pytest.approx([1, 2, 3, 4])
    assert all(np.array_equal(r[0], r[-1]) for r in rings)
    two = contour_rings(SQUARE, [True], Contour(1.0, 2))
    assert sorted(np.max(np.abs(r)) for r in two) == pytest.approx([3, 4])
    around = contour_rings(ANNULUS, [True, True], Contour(1.0))
    # 1 mm in: the outer square at half 4 and the hole's ring at half 3; 2 mm in they would
    # cross (3 inside 4): nothing more.
    extents = sorted(round(float(np.max(np.abs(r))), 6) for r in around)
    assert extents == [3, 4]


@pytest.mark.parametrize("make", [lambda: HatchSet(0), lambda: HatchSet(1, math.nan),
                                  lambda: HatchSet(1e3), lambda: Contour(1, 0),
                                  lambda: Contour(-1)])
def test_impossible_fills_are_refused(make):
    with pytest.raises(PlanError):
        make()


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(text=st.text(alphabet="0123456789.,-e ", max_size=20))
def test_any_hatch_or_contour_argument_is_a_fill_or_one_line(text, capsys):
    from galvoscan.cli import main
    for option in ("--hatch", "--contour"):
        try:
            main(["mark", "nonexistent.svg", f"{option}={text}", "--estimate"])
        except SystemExit as stop:
            err = capsys.readouterr().err
            assert stop.code != 0
            assert len(err.strip().splitlines()) <= 2 and "Traceback" not in err


def test_a_job_turns_its_hatch_each_pass(tmp_path):
    """plan_vector_job with a set turned 90° a pass: pass 1 horizontal lines, pass 2 vertical,
    pass 3 horizontal again, each after the outline; without a step every pass is the same."""
    from galvoscan.geometry.field import Placement
    from galvoscan.profile.machine import default_profile
    from galvoscan.plan.objects import JobSettings
    from galvoscan.plan.vector_job import plan_vector_job
    from drawings import load_svg
    drawing = load_svg(tmp_path, '<rect x="10" y="10" width="10" height="10"/>')

    def plan(hatch_set, passes):
        settings = JobSettings(speed_mm_s=500, power_percent=10, prr_khz=50, passes=passes,
                               hatch=(hatch_set,))
        return plan_vector_job(drawing, Placement(), settings, default_profile())
    job = plan(HatchSet(2.0, 0, 90), 3)
    kinds = []
    for path in job.paths_mm:
        d = path[-1] - path[0]
        kinds.append("outline" if len(path) > 2 else "row" if abs(d[1]) < 1e-9 else "column")
    assert kinds == ["outline"] + ["row"] * 5 + ["outline"] + ["column"] * 5 + \
        ["outline"] + ["row"] * 5
    same = plan(HatchSet(2.0, 0), 3)
    third = len(same.segments) // 3
    assert same.segments[:third] * 3 == same.segments


@pytest.mark.parametrize("order", [LineOrder.SERPENTINE, LineOrder.ONEWAY])
def test_a_hole_is_hatched_around_a_side_at_a_time(order):
    """The lines split by the annulus's hole are marked a side at a time (a strip above, one
    each side, one below), not across the hole on every line: a few jumps cross it, not one
    a line, and every line's runs are still marked once."""
    strokes = hatch_strokes(ANNULUS, [True, True], HatchSet(0.1), order=order)
    crossing = [(a[-1], b[0]) for a, b in zip(strokes, strokes[1:])
                if abs((a[-1] + b[0])[0] / 2) < 2 and abs((a[-1] + b[0])[1] / 2) < 2]
    assert len(crossing) <= 3
    lines_through_hole = round(4 / 0.1)
    assert len(strokes) == round(10 / 0.1) + lines_through_hole
    if order is LineOrder.SERPENTINE:   # (one way, each line starts back at its side)
        steps = [np.hypot(*(b[0] - a[-1])) for a, b in zip(strokes, strokes[1:])]
        assert sum(steps) < 60      # (across the hole on each of 40 lines: over 160 mm)


def test_a_hatch_finer_than_a_galvo_unit_is_refused(tmp_path):
    """Lines closer than a galvo unit fall on one another: refused, saying the unit."""
    from galvoscan.cli import main
    svg = tmp_path / "sq.svg"
    svg.write_text('<svg xmlns="http://www.w3.org/2000/svg" width="5mm" height="5mm" '
                   'viewBox="0 0 5 5"><rect width="5" height="5" fill="none" stroke="red"/>'
                   '</svg>')
    with pytest.raises(SystemExit, match=r"hatch spacing 0.001 mm is finer than a galvo unit "
                                         r"\(1.68 µm on this field\)"):
        main(["mark", str(svg), "--hatch", "0.001", "--estimate"])
