"""The G-code reader (galvoscan/inputs/gcode.py, through load_drawing and the API): files in
the form other programs write them (tests/data/gcode/, see its README), arcs against the
true circle, inches against mm, relative moves against absolute ones, damaged lines refused
in one line naming them, and random bytes and words giving a Drawing or a DrawingError only.
Every expected point comes from the shape a file was made from, not from the reader."""

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from galvoscan import api
from galvoscan.geometry.drawing import Drawing, DrawingError
from galvoscan.inputs.drawings import load_drawing

from drawings import chord_midpoints


DATA = Path(__file__).resolve().parents[1] / "data" / "gcode"
#: Float noise of the reader's own arithmetic (the files' numbers are exact to 1e-8 mm).
ATOL = 1e-7


def write(tmp_path, text, name="t.gcode"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def vertices(path):
    return {tuple(np.round(p, 6)) for p in path}


# --- files other programs wrote -------------------------------------------------------------

def test_jtech_square_and_triangle():
    """Inkscape's J Tech extension: M3 S255 and F750.0 are one layer; the laser-off G1 moves
    at the travel speed are jumps, not marks."""
    d = load_drawing(DATA / "jtech_square_triangle.gcode", s_max=255)
    assert isinstance(d, Drawing) and d.closed == (True, True)
    square, triangle = d.paths
    assert vertices(square) == {(10, 10), (30, 10), (30, 30), (10, 30)}
    apex = 10 + 10 * math.sqrt(3)
    np.testing.assert_allclose(triangle, [(40, 10), (60, 10), (50, apex), (40, 10)], atol=1e-8)
    (layer,) = d.layers
    assert layer.speed_mm_s == pytest.approx(750 / 60)
    assert layer.power_percent == pytest.approx(100)
    assert {style.layer for style in d.styles} == {layer.name}
    assert d.skipped == ()
    # At GRBL's default S maximum, S255 is a quarter of full power.
    (layer,) = load_drawing(DATA / "jtech_square_triangle.gcode").layers
    assert layer.power_percent == pytest.approx(25.5)


def test_lasergrbl_raster_rows_by_pixel():
    """LaserGRBL's line-to-line raster: relative moves, power changing within a line, each
    power a layer; the white run and the step to the next row one G0 jump. The expected runs
    are the image's pixels, 0.1 mm each from 10, 10."""
    d = load_drawing(DATA / "lasergrbl_raster.nc")
    assert [layer.name for layer in d.layers] == ["S300 F1000", "S600 F1000"]
    assert [layer.power_percent for layer in d.layers] == pytest.approx([30, 60])
    assert [layer.speed_mm_s for layer in d.layers] == pytest.approx([1000 / 60] * 2)
    expected = [("S300 F1000", [(10.0, 10.0), (10.5, 10.0)]),
                ("S600 F1000", [(10.5, 10.0), (10.9, 10.0)]),
                ("S600 F1000", [(11.0, 10.1), (10.6, 10.1)]),
                ("S300 F1000", [(10.6, 10.1), (10.0, 10.1)])]
    assert [style.layer for style in d.styles] == [name for name, _ in expected]
    for path, (_, points) in zip(d.paths, expected):
        np.testing.assert_allclose(path, points, atol=ATOL)


# --- arcs -------------------------------------------------------------------------------------

R = 8.0
CX, CY = 3.0, -2.0


def arc_file(tmp_path, start_deg, end_deg, word, form):
    """An arc about (CX, CY) of radius R, by its centre (I J from the start) or R."""
    a0, a1 = math.radians(start_deg), math.radians(end_deg)
    x0, y0 = CX + R * math.cos(a0), CY + R * math.sin(a0)
    x1, y1 = CX + R * math.cos(a1), CY + R * math.sin(a1)
    move = f"{word} X{x1:.9f} Y{y1:.9f} " + \
        (f"I{CX - x0:.9f} J{CY - y0:.9f}" if form == "ij" else form)
    return write(tmp_path, f"G21 G90\nG0 X{x0:.9f} Y{y0:.9f}\nM3 S1000\nG1 F600\n{move}\nM5\n")


@pytest.mark.parametrize("tolerance_mm", [0.1, 0.01, 0.001])
@pytest.mark.parametrize("word, start_deg, end_deg, sweep_deg", [
    ("G3", 0, 90, 90), ("G2", 0, 90, -270), ("G3", 30, 30, 360), ("G2", 200, 200, -360),
    ("G3", 170, -100, 90), ("G2", -45, 135, -180)])
def test_arc_by_centre_lies_on_the_circle(tmp_path, word, start_deg, end_deg, sweep_deg,
                                          tolerance_mm):
    d = load_drawing(arc_file(tmp_path, start_deg, end_deg, word, "ij"),
                     tolerance_mm=tolerance_mm)
    (p,) = d.paths
    check_arc(p, start_deg, sweep_deg, tolerance_mm)


@pytest.mark.parametrize("word, radius, start_deg, end_deg, sweep_deg", [
    # The same two points, (R, 0) and (0, R) from the centre: R > 0 the short way round,
    # R < 0 the long way, G2 clockwise, G3 counter-clockwise.
    ("G3", R, 0, 90, 90), ("G3", -R, 0, 90, 90), ("G2", R, 0, 90, -270),
    ("G2", -R, 0, 90, -270)])
def test_arc_by_radius_takes_the_right_side(tmp_path, word, radius, start_deg, end_deg,
                                            sweep_deg):
    """``R``: of the two circles through both ends, the one whose arc that way round is
    shorter than half a turn (R > 0) or longer (R < 0). Here the file's circle is the one
    about (CX, CY) only where that arc is the one asked; else it is the mirror circle, and
    the expected centre is that one's."""
    tol = 0.01
    d = load_drawing(arc_file(tmp_path, start_deg, end_deg, word, f"R{radius:g}"),
                     tolerance_mm=tol)
    (p,) = d.paths
    short = abs(sweep_deg) < 180
    if short == (radius > 0):
        check_arc(p, start_deg, sweep_deg, tol)
    else:
        # The mirror circle through both ends: its centre is the first's reflected across the
        # chord; from it the arc turns the other way's complement.
        start = np.array([CX + R, CY])
        end = np.array([CX, CY + R])
        mirror = start + end - np.array([CX, CY])
        r = np.hypot(*(p - mirror).T)
        np.testing.assert_allclose(r, R, atol=ATOL)
        turned = np.unwrap(np.arctan2(p[:, 1] - mirror[1], p[:, 0] - mirror[0]))
        expected = math.copysign(360 - abs(sweep_deg), sweep_deg)
        assert math.degrees(turned[-1] - turned[0]) == pytest.approx(expected, abs=1e-6)


def check_arc(p, start_deg, sweep_deg, tol):
    """Every point on the circle, every chord within ``tol`` of it, the arc from its start
    turning ``sweep_deg`` one way, in about as few chords as the tolerance allows."""
    r = np.hypot(p[:, 0] - CX, p[:, 1] - CY)
    np.testing.assert_allclose(r, R, atol=ATOL)
    mid = np.hypot(*(chord_midpoints(p) - (CX, CY)).T)
    assert np.all(mid >= R - tol - ATOL)
    turned = np.unwrap(np.arctan2(p[:, 1] - CY, p[:, 0] - CX))
    steps = np.diff(turned)
    assert np.all(steps * sweep_deg > 0)                          # one way round
    assert math.degrees(turned[-1] - turned[0]) == pytest.approx(sweep_deg, abs=1e-6)
    assert math.degrees(turned[0]) % 360 == pytest.approx(start_deg % 360, abs=1e-6)
    fewest = math.radians(abs(sweep_deg)) / (2 * math.acos(1 - tol / R))
    assert fewest <= len(p) - 1 <= 2 * fewest + 2


def test_arc_whose_end_is_off_its_circle_is_refused(tmp_path):
    """GRBL's own check: an end 0.05 mm off the circle of the centre given (more than
    0.005 mm and 0.1 % of R, 0.01 mm) is an error, on its line; 0.005 mm off is not."""
    path = write(tmp_path, "G0 X10 Y0\nM3 S500 F600\nG3 X0 Y10.005 I-10 J0\n")
    load_drawing(path)
    path = write(tmp_path, "G0 X10 Y0\nM3 S500 F600\nG3 X0 Y10.05 I-10 J0\n")
    with pytest.raises(DrawingError, match=r"line 3 .*off its circle"):
        load_drawing(path)


def test_radius_shorter_than_half_the_chord_is_refused(tmp_path):
    path = write(tmp_path, "M3 S500 F600\nG2 X10 Y0 R4.9\n")
    with pytest.raises(DrawingError, match="line 2 .*shorter than half"):
        load_drawing(path)


# --- units and relative moves -----------------------------------------------------------------

#: A shape in mm: a line, an arc by centre, a line, an arc by radius, back (F in mm/min).
SHAPE_MM = [("G1", 20.0, 0.0, ""), ("G3", 30.0, 10.0, "I0 J10"), ("G1", 30.0, 25.4, ""),
            ("G2", 20.0, 35.4, "R10"), ("G1", 0.0, 0.0, "")]


def shape_file(tmp_path, name, per_mm, header, relative=False):
    """SHAPE_MM with every length (X, Y, I, J, R, F) in a unit ``per_mm`` of a mm."""
    lines = [header, "M4 S400", f"F{1500 * per_mm:.12g}"]
    at = (0.0, 0.0)
    for word, x, y, rest in SHAPE_MM:
        arc = " ".join(f"{w[0]}{float(w[1:]) * per_mm:.12g}" for w in rest.split())
        tx, ty = (x - at[0], y - at[1]) if relative else (x, y)
        lines.append(f"{word} X{tx * per_mm:.12g} Y{ty * per_mm:.12g} {arc}".strip())
        at = (x, y)
    return write(tmp_path, "\n".join(lines) + "\nM5\n", name)


def test_inches_read_as_the_same_shape_in_mm(tmp_path):
    mm = load_drawing(shape_file(tmp_path, "mm.gcode", 1.0, "G21 G90"))
    inches = load_drawing(shape_file(tmp_path, "in.gcode", 1 / 25.4, "G20 G90"))
    (a,), (b,) = mm.paths, inches.paths
    assert len(a) == len(b) and mm.closed == inches.closed == (True,)
    np.testing.assert_allclose(b, a, atol=ATOL)
    assert inches.layers[0].speed_mm_s == pytest.approx(mm.layers[0].speed_mm_s) == 25
    # The corners the shape was written with, in mm.
    assert {(20, 0), (30, 10), (30, 25.4), (20, 35.4), (0, 0)} <= vertices(a)


def test_relative_moves_read_as_the_absolute_shape(tmp_path):
    absolute = load_drawing(shape_file(tmp_path, "abs.gcode", 1.0, "G90"))
    relative = load_drawing(shape_file(tmp_path, "rel.gcode", 1.0, "G91", relative=True))
    np.testing.assert_allclose(relative.paths[0], absolute.paths[0], atol=ATOL)
    inches = load_drawing(shape_file(tmp_path, "rel-in.gcode", 1 / 25.4, "G20 G91",
                                     relative=True))
    np.testing.assert_allclose(inches.paths[0], absolute.paths[0], atol=ATOL)


def test_units_given_replace_g20_and_g21(tmp_path):
    path = write(tmp_path, "G21\nM3 S100 F600\nG1 X1 Y0\n")
    (p,) = load_drawing(path, units="in").paths
    np.testing.assert_allclose(p, [(0, 0), (25.4, 0)])


# --- the laser: marks, jumps and layers ------------------------------------------------------

def test_marks_only_with_the_laser_on_and_s_above_0(tmp_path):
    path = write(tmp_path, "\n".join([
        "G1 F600 X1",               # laser off (M5 at power-up): a jump
        "M3 S0", "G1 X2",           # on, S0: a jump
        "S200 G1 X3",               # marks 2 → 3
        "G0 X4",                    # G0: a jump, laser on or not
        "G1 X5",                    # marks 4 → 5
        "M5", "G1 X6",              # off: a jump
        "M4 G1 X7 S300",            # on again at S300: 6 → 7, a layer of its own
        "F1200 X8",                 # the feed changes: 7 → 8 another
    ]) + "\n")
    d = load_drawing(path)
    segments = [tuple(p[:, 0]) for p in d.paths]
    assert segments == [(2, 3), (4, 5), (6, 7), (7, 8)]
    assert [s.layer for s in d.styles] == ["S200 F600", "S200 F600", "S300 F600",
                                           "S300 F1200"]
    assert [(l.speed_mm_s, l.power_percent) for l in d.layers] == \
        pytest.approx([(10, 20), (10, 30), (20, 30)])


def test_harmless_words_are_read_and_what_is_left_out_is_counted(tmp_path):
    body = "N3 G1 X10 Y0 "
    checksum = 0
    for char in body.encode():
        checksum ^= char
    path = write(tmp_path, "\n".join([
        "%", "; a comment", "(another) G17 G40 G54 G94 G21 G90 (and one more)",
        "N1 M3 S500 F600 ; laser on", "N2 G4 P0.5", "M8", body + f"*{checksum}",
        "G1 Z-1 X20", "M9", "G4 P1", "G28 X0 Y0", "M2", "%"]) + "\n")
    d = load_drawing(path)
    (p,) = d.paths
    np.testing.assert_allclose(p, [(0, 0), (10, 0), (20, 0)])
    assert d.skipped == ("1 G28/G30 homing move left out (not a move on a galvo)",
                         "2 G4 dwells left out (a galvo marks no dwell from G-code)",
                         "2 M7/M8/M9 air assist commands left out",
                         "1 Z word left out (a galvo has no Z)")
    assert any("S1000" in note for note in d.notes)


@pytest.mark.parametrize("lines, number, words", [
    (["M3 S100 F600", "G1 X1O"], 2, "'O' is not a G-code word"),
    (["G1 X"], 1, "not a G-code word"),
    (["M3 S100 F600", "G1 X1 X2"], 2, "X given twice"),
    (["G21", "", "G5 X1"], 3, "G5: not a G code"),
    (["N10 G1 X5*99"], 1, "checksum"),
    (["G1 X1 (unclosed"], 1, "not closed"),
    (["G1 E5"], 1, "E5: not a word"),
    (["M3 S100", "G1 X10"], 2, "no feed rate"),
    (["M3 S1200 F600", "G1 X10"], 2, "more than the S maximum 1000"),
    (["G18"], 1, "G18"),
    (["M3 S10 F600", "G2 X10 Y0 R5 I1"], 2, "both R and I/J"),
    (["G1 F0.5 X1 M3 S1"], 1, "mm/s: galvoscan marks at 0.1"),
    (["G1 X1e3"], 1, "E3: not a word"),
    (["M3 S10 F600", "G4 P1 X5"], 2, "a dwell (G4) and a move"),
    (["M3 S10 F600", "G1 X1 \u017f500"], 2, "'\u017f' is not a character"),   # a long s
    (["G28 G1 X5"], 1, "a homing move (G28, G30) and another"),           # (GRBL reads no exponent)
    (["M3 S10 F600", "G1 X" + "9" * 12], 2, "beyond any machine"),
])
def test_a_damaged_line_is_one_line_naming_it(tmp_path, lines, number, words):
    path = write(tmp_path, "\n".join(lines) + "\n")
    with pytest.raises(DrawingError) as error:
        load_drawing(path)
    message = str(error.value)
    assert "\n" not in message and message.startswith(f"{path}: line {number} (")
    assert words in message


def test_nothing_marked_says_so(tmp_path):
    path = write(tmp_path, "G0 X10\nG1 F600 X20\nG4 P1\n")
    with pytest.raises(DrawingError, match="no lines or curves to mark .*G4 dwell"):
        load_drawing(path)


def test_s_max_is_for_gcode_only_and_in_range(tmp_path):
    svg = write(tmp_path, "<svg xmlns='http://www.w3.org/2000/svg'/>", "t.svg")
    with pytest.raises(DrawingError, match="an S maximum is for G-code"):
        load_drawing(svg, s_max=255)
    with pytest.raises(DrawingError, match="S maximum must be from"):
        load_drawing(write(tmp_path, "G1 X1\n"), s_max=0)


# --- through the API: the file's layers in the plan ------------------------------------------

def test_the_plan_has_a_layer_for_each_s_and_f(tmp_path):
    """Each distinct S and F a job of its own at that speed and power; a given layer of the
    same name changes what it gives and keeps the file's speed and power."""
    job = api.Job(drawings=[api.Drawing(str(DATA / "lasergrbl_raster.nc"))])
    plan = api.plan(job)
    layers = plan.vector_job.layers
    assert [lj.label for lj in layers] == ["S300 F1000", "S600 F1000"]
    assert [lj.settings.power_percent for lj in layers] == pytest.approx([30, 60])
    assert [lj.settings.speed_mm_s for lj in layers] == pytest.approx([1000 / 60] * 2)
    # (Each run's ends rounded to whole galvo units: 110 mm across 65536 of them.)
    assert plan.mark_mm == pytest.approx(0.5 + 0.4 + 0.4 + 0.6, abs=8 * 110 / 65536)
    given = api.Layer("s600 f1000", passes=3, power_percent=45)
    layers = api.plan(api.Job(drawings=job.drawings, layers=[given])).vector_job.layers
    assert [lj.label for lj in layers] == ["s600 f1000", "S300 F1000"]
    assert (layers[0].settings.passes, layers[0].settings.power_percent,
            layers[0].settings.speed_mm_s) == pytest.approx((3, 45, 1000 / 60))


def test_two_files_with_one_layer_name_at_two_powers_are_refused(tmp_path):
    """Two G-code drawings whose S500 F600 are different powers (their S maxima differ):
    one layer cannot be both."""
    path = write(tmp_path, "M3 S500 F600\nG1 X1\n")
    same = api.Job(drawings=[api.Drawing(str(path)), api.Drawing(str(path), offset_mm=(5, 0))])
    assert [lj.label for lj in api.plan(same).vector_job.layers] == ["S500 F600"]
    mixed = api.Job(drawings=[api.Drawing(str(path)),
                              api.Drawing(str(path), offset_mm=(5, 0), s_max=500)])
    with pytest.raises(ValueError, match="'S500 F600' is at 100 %, another drawing's at 50 %"):
        api.plan(mixed)


# --- anything at all: a Drawing or a DrawingError ---------------------------------------------

def only_drawing_errors(tmp_path, data):
    path = tmp_path / "case.gcode"
    path.write_bytes(data)
    try:
        drawing = load_drawing(path)
    except DrawingError as error:
        assert "\n" not in str(error)
        return
    for p in drawing.paths:
        assert p.ndim == 2 and p.shape[1] == 2 and len(p) >= 2 and np.isfinite(p).all()
    held = {style.layer for style in drawing.styles}
    assert held == {layer.name for layer in drawing.layers}


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.binary(max_size=400))
def test_random_bytes_give_a_drawing_or_a_drawing_error(tmp_path, data):
    only_drawing_errors(tmp_path, data)


_NUMBER = st.one_of(st.integers(-200, 200).map(str),
                    st.floats(-1e3, 1e3, allow_nan=False).map(lambda v: f"{v:.4f}"),
                    st.sampled_from(["", ".", "-", "1e5", "9" * 20, "-.5", "+3."]))
_WORD = st.builds(lambda letter, number: letter + number,
                  st.sampled_from(list("GGGMMXYXYIJRSFNPZTKE")), _NUMBER)
_CODE = st.sampled_from(["G0", "G1", "G2", "G3", "G4", "G20", "G21", "G90", "G91", "G90.1",
                         "M3", "M4", "M5", "M2", "M8", "S0", "S500", "S1000", "F600", "F3000",
                         "(c)", ";c", "%", "*12"])
_LINE = st.lists(st.one_of(_WORD, _CODE), max_size=6).map(" ".join)
_LENGTH = st.floats(-50, 50, allow_nan=False).map(lambda v: f"{v:.3f}")
_OPTIONAL = {"X": _LENGTH, "Y": _LENGTH, "S": st.sampled_from(["0", "300", "1000"]),
             "F": st.sampled_from(["600", "6000"])}


def _words_of(first, needed=(), **parts):
    """A line as a program writes one: ``first``, the ``needed`` words (letter, value), then
    each of ``parts`` or not, each word once."""
    return st.builds(lambda head, *words: " ".join(w for w in (head, *words) if w), first,
                     *(value.map(f"{letter}{{}}".format) for letter, value in needed),
                     *(st.one_of(st.just(""), value.map(f"{letter}{{}}".format))
                       for letter, value in parts.items()))


_ARC = st.sampled_from(["G2", "G3"])
#: Lines as programs write them: most are read, and many mark.
_PLAUSIBLE = st.one_of(
    _words_of(st.sampled_from(["", "G0", "G1", "G91", "G90", "G20", "G21", "M5", "M3", "M4"]),
              **_OPTIONAL),
    _words_of(_ARC, (("X", _LENGTH), ("Y", _LENGTH), ("I", _LENGTH), ("J", _LENGTH)),
              S=_OPTIONAL["S"]),
    _words_of(_ARC, (("X", _LENGTH), ("Y", _LENGTH), ("R", _LENGTH)), F=_OPTIONAL["F"]))


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(lines=st.lists(st.one_of(_LINE, _PLAUSIBLE, _PLAUSIBLE), max_size=30))
def test_random_word_sequences_give_a_drawing_or_a_drawing_error(tmp_path, lines):
    only_drawing_errors(tmp_path, ("M3 S500 F600\n" + "\n".join(lines)).encode())


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(lines=st.lists(_PLAUSIBLE, max_size=30))
def test_programs_of_plausible_lines_give_a_drawing_or_a_drawing_error(tmp_path, lines):
    """Lines as programs write them, most of which mark: the arcs' and units' paths too."""
    only_drawing_errors(tmp_path, ("G1 M3 S500 F600\n" + "\n".join(lines)).encode())
