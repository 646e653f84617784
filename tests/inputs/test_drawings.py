"""Loading drawings (galvoscan/inputs/drawings.py, svg.py): SVG files with known geometry, checked against
the analytic shapes (not against the libraries), and bad SVG and DXF files, which must give a
DrawingError and nothing else. The DXF reader's geometry is in test_dxf.py."""

import math
import os
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from galvoscan.geometry.drawing import Drawing, DrawingError
from galvoscan.inputs.drawings import load_drawing

from drawings import (SVG_ATOL, SVG_MM, bezier, chord_midpoints, distance_to_curve, load_svg,
                      new_dxf, svg)




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
    d = load_svg(tmp_path, '<text x="1" y="1" font-family="No Such Font">a</text>'
                           '<text x="1" y="5" font-family="No Such Font">b</text>'
                           '<image href="x.png" width="5" height="5"/>'
                           '<line x1="0" y1="0" x2="5" y2="5"/>'
                           '<line x1="1" y1="1" x2="1" y2="1"/>'
                           '<g style="display:none"><rect width="50" height="50"/></g>'
                           '<rect width="60" height="60" visibility="hidden"/>'
                           '<defs><rect id="r" width="70" height="70"/></defs>')
    # The texts in the generic family, said (never left out for their font).
    assert sum(1 for p in d.paths if p[:, 0].min() >= 0.5) >= 2
    assert "font 'No Such Font' is not installed: set in DejaVu Sans (sans-serif) in its place " \
        "(2 elements)" in d.notes
    assert set(d.skipped) == {"1 image element", "1 hidden element", "1 zero-length path"}


def test_svg_use_of_a_def_is_marked(tmp_path):
    d = load_svg(tmp_path, '<defs><rect id="r" width="10" height="10"/></defs>'
                           '<use xlink:href="#r" x="20" y="0"/>')
    (p,) = d.paths
    np.testing.assert_allclose(d.bounds(), (20, -10, 30, 0), atol=SVG_ATOL)


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
        f"{tmp_path / 'x.png'}: not a drawing galvoscan reads (.svg, .dxf, .gcode, .gco, " \
        f".gc, .nc, .ngc, .job)"
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
    (tmp_path / "blank.svg").write_text(svg('<text x="0" y="5" visibility="hidden">only '
                                            'text</text>'))
    # What was left out is said: it may be why nothing is left.
    refused(tmp_path / "blank.svg", "no lines or curves to mark (left out: 1 hidden element)")
    doc, msp = new_dxf()
    msp.add_point((1, 1))
    doc.saveas(tmp_path / "blank.dxf")
    refused(tmp_path / "blank.dxf", "no lines or curves to mark (left out: 1 POINT entity")
    (tmp_path / "nothing.svg").write_text(svg(""))
    assert refused(tmp_path / "nothing.svg").endswith("no lines or curves to mark")


def test_absurd_size_and_non_finite(tmp_path):
    doc, msp = new_dxf(units=6)                 # metres
    msp.add_line((0, 0), (11, 0))
    doc.saveas(tmp_path / "big.dxf")
    refused(tmp_path / "big.dxf", "11 × 0 m (its $INSUNITS 6, metres), more than 10 m: give "
            "--units mm if its numbers are millimetres, or --scale 0.9 or less")
    (tmp_path / "inf.svg").write_text(svg('<line x1="0" y1="0" x2="1e400" y2="5"/>'))
    refused(tmp_path / "inf.svg", "not finite")


def _huge_curves(folder):
    """Curves far beyond any field, each alone in a drawing: without a count of their chords
    before they are made, each of these took gigabytes (a pytest worker grew to 24 GB)."""
    cases = {
        "cubic.svg": svg('<path d="M0 0 C 9e14 9e14 -9e14 9e14 1 0"/>'),
        "quadratic.svg": svg('<path d="M0 0 Q 9e14 9e14 1 0"/>'),
        "arc.svg": svg('<path d="M0 0 A 9e14 9e14 0 1 1 1e14 0"/>'),
    }
    for name, text in cases.items():
        (folder / name).write_text(text)
    huge = 9e14
    for name, add in {
        "circle.dxf": lambda msp: msp.add_circle((0, 0), huge),
        "arc.dxf": lambda msp: msp.add_arc((0, 0), huge, 0, 270),
        "ellipse.dxf": lambda msp: msp.add_ellipse((0, 0), major_axis=(huge, 0), ratio=0.5),
        "spline.dxf": lambda msp: msp.add_spline([(0, 0), (huge, huge), (-huge, huge), (1, 0)]),
        "bulge.dxf": lambda msp: msp.add_lwpolyline([(0, 0, 0, 0, 1e6), (1, 0)],
                                                    format="xyseb"),
    }.items():
        doc, msp = new_dxf()
        add(msp)
        doc.saveas(folder / name)
    return [folder / name for name in [*cases, "circle.dxf", "arc.dxf", "ellipse.dxf",
                                       "spline.dxf", "bulge.dxf"]]


# Loads each drawing named in argv with the memory capped at a gigabyte, and prints what it
# says: a regression fails in the cap, not by the OOM killer.
_CAPPED_LOADS = """
import resource, sys
resource.setrlimit(resource.RLIMIT_AS, (2 ** 30, 2 ** 30))
from galvoscan.geometry.drawing import DrawingError
from galvoscan.inputs.drawings import load_drawing
for path in sys.argv[1:]:
    try:
        load_drawing(path)
        print(path, "loaded")
    except DrawingError as error:
        print(error)
"""


@pytest.mark.skipif(sys.platform != "linux", reason="caps the loads' memory with setrlimit")
def test_huge_curves_are_refused_before_they_are_flattened(tmp_path):
    import subprocess
    paths = _huge_curves(tmp_path)
    run = subprocess.run([sys.executable, "-c", _CAPPED_LOADS, *map(str, paths)],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    lines = run.stdout.splitlines()
    assert len(lines) == len(paths)
    for path, line in zip(paths, lines):
        # (The bulge's arc is one a drawing 500 m wide can hold: refused for its size.)
        assert line.startswith(f"{path}: ") and ("more than 1,000,000 chords" in line or
                                                 "more than 10 m" in line), line


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
    hatch = msp.add_hatch()
    hatch.paths.add_polyline_path([(0, 0, 0.5), (8, 0, 0), (8, 8, 0)], is_closed=True)
    hatch.paths.add_edge_path().add_arc((4, 4), 2, 0, 360)
    msp.add_text("skip me")
    doc.saveas(folder / "valid.dxf")
    doc.saveas(folder / "valid-binary.dxf", fmt="bin")
    return folder, {
        # (A binary DXF: its case file is named case-binary.dxf.)
        "-binary.dxf": (folder / "valid-binary.dxf").read_bytes(),
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
@given(suffix=st.sampled_from([".svg", ".dxf", "-binary.dxf"]), fraction=st.floats(0, 1))
def test_truncated_files_give_drawing_errors_only(valid, suffix, fraction):
    folder, files = valid
    data = files[suffix]
    only_drawing_errors(folder, data[:int(len(data) * fraction)], suffix)


@settings(max_examples=60, deadline=None)
@given(suffix=st.sampled_from([".svg", ".dxf"]), data=st.binary(max_size=400))
def test_garbage_gives_drawing_errors_only(valid, suffix, data):
    only_drawing_errors(valid[0], data, suffix)


@settings(max_examples=40, deadline=None)
@given(suffix=st.sampled_from([".svg", ".dxf", "-binary.dxf"]), position=st.floats(0, 1),
       junk=st.binary(min_size=1, max_size=20))
def test_corrupted_files_give_drawing_errors_only(valid, suffix, position, junk):
    folder, files = valid
    data = files[suffix]
    at = int(len(data) * position)
    only_drawing_errors(folder, data[:at] + junk + data[at + len(junk):], suffix)


def test_binary_dxf_reads_as_its_text_twin(valid):
    """A binary DXF (AutoCAD's other DXF encoding, which ezdxf.readfile reads) gives the
    same paths as the same drawing saved as text; cut short, it is one line that says so."""
    folder, files = valid
    text, binary = load_drawing(folder / "valid.dxf"), load_drawing(folder / "valid-binary.dxf")
    assert len(binary.paths) == len(text.paths) > 0
    for a, b in zip(text.paths, binary.paths):
        assert np.allclose(a, b)
    assert binary.closed == text.closed and binary.skipped == text.skipped
    cut = folder / "cut-binary.dxf"
    cut.write_bytes(files["-binary.dxf"][:300])
    refused(cut, "damaged binary DXF: it ends early or a group is corrupt")
