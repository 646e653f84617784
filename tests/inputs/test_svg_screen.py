"""SVG elements that are errors by the specification (galvoscan/inputs/svg_screen.py): left out,
each named in a note, the rest of the drawing read as a browser draws it."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from galvoscan.geometry.drawing import DrawingError

from drawings import load_svg


SQUARE = '<path id="square" d="M10,10 H20 V20 H10 Z"/>'


def _square_only(drawing):
    (points,) = drawing.paths
    assert np.ptp(points[:, 0]) == pytest.approx(10) and np.ptp(points[:, 1]) == pytest.approx(10)


@pytest.mark.parametrize("data", ["L 5 5 L 10 10", "l 5 5", "H 5 V 5", "A 5 5 0 0 1 10 10",
                                  "C 1 1 2 2 3 3", "Z", "5 5 L 3 3", ",M 1 1 L 5 5",
                                  "\n  Q 1 1 4 4"])
def test_a_path_without_a_moveto_is_left_out_by_name(tmp_path, data):
    drawing = load_svg(tmp_path, SQUARE + f'<path id="stray" d="{data}"/>')
    _square_only(drawing)
    assert any("'stray' starts without a moveto" in note for note in drawing.notes), \
        drawing.notes


def test_a_path_with_no_id_is_named_by_its_place(tmp_path):
    drawing = load_svg(tmp_path, SQUARE + '<path d="H 5"/>')
    assert any("<path> number 2 starts without a moveto" in note for note in drawing.notes)


def test_a_path_that_starts_with_spaces_then_a_moveto_is_drawn(tmp_path):
    drawing = load_svg(tmp_path, '<path d="  \n m10,10 h10 v10 h-10 z"/>')
    _square_only(drawing)
    assert not drawing.notes


@pytest.mark.parametrize("body, names", [
    ('<use id="self" href="#self"/>', ["self"]),
    ('<use id="old" xlink:href="#old"/>', ["old"]),
    ('<g id="a"><use id="b" href="#c"/></g><g id="c"><use id="d" href="#a"/></g>', ["b", "d"]),
    ('<g id="g"><use id="inside" href="#g"/></g>', ["inside"]),
])
def test_a_use_that_refers_to_itself_is_left_out_by_name(tmp_path, body, names):
    drawing = load_svg(tmp_path, SQUARE + body)
    _square_only(drawing)
    for name in names:
        assert any(f"<use> '{name}' refers to itself" in note for note in drawing.notes), \
            drawing.notes


def test_a_use_that_refers_to_a_circle_keeps_what_is_not_on_it(tmp_path):
    """A <use> of a group that holds a circular <use> draws the group's other shapes: only
    the circular one is left out."""
    body = ('<defs><g id="part"><path d="M10,10 H20 V20 H10 Z"/>'
            '<use id="back" href="#part"/></g></defs><use id="copy" href="#part" x="50"/>')
    drawing = load_svg(tmp_path, body)
    (points,) = drawing.paths
    assert np.min(points[:, 0]) == pytest.approx(60)
    assert [n for n in drawing.notes if "refers to itself" in n] == [
        "<use> 'back' refers to itself (directly or through other <use> elements): left out, "
        "as a browser draws none of it"]


@settings(max_examples=40, deadline=None)
@given(refs=st.lists(st.tuples(st.integers(0, 5), st.integers(0, 5)), max_size=8))
def test_any_web_of_uses_loads_or_is_one_line(tmp_path_factory, refs):
    """Groups g0…g5, each holding uses of others (any, circles included): the drawing loads,
    or is refused in one line, never a Python error."""
    groups = {k: [] for k in range(6)}
    for number, (owner, target) in enumerate(refs):
        groups[owner].append(f'<use id="u{number}" href="#g{target}"/>')
    body = "".join(f'<g id="g{k}">{"".join(uses)}<path d="M{k},{k} h1"/></g>'
                   for k, uses in groups.items())
    try:
        drawing = load_svg(tmp_path_factory.mktemp("web"), body)
    except DrawingError as error:
        assert "\n" not in str(error)
        return
    assert len(drawing.paths) >= 6             # the groups' own lines, at least
