"""What meerk40t makes besides rectangles and circles, marked through the galvoscan device on the
simulated board (headless and in-process: tests/support/meerk40t_session.py) and read off the
XY2-100 wires and the laser pins by the tests' own readers, against meerk40t's own geometry
read off its elements (not the device's): a line of its text (``linetext``), an image
(``imageop``: a RasterCut), two operations in one job (each its own layer, each one's speed,
PRR and pulses per point measured on the wires), a wait operation between two (the board held
for its time, measured on the wires), the driver's own ``wait`` and ``dwell``, and I/O
operations on a board without I/O in the queue refused in one line (tests/meerk40t/test_io.py
runs them on one with it)."""

import re
import shutil
import time
from pathlib import Path

import matplotlib
import numpy as np
import pytest
from PIL import Image
from hypothesis import given, settings, strategies as st

pytest.importorskip("meerk40t")

from meerk40t.core.cutcode.inputcut import InputCut     # noqa: E402
from meerk40t.core.cutcode.linecut import LineCut       # noqa: E402
from meerk40t.core.cutcode.outputcut import OutputCut   # noqa: E402
from meerk40t.core.cutcode.waitcut import WaitCut       # noqa: E402
from meerk40t.core.units import UNITS_PER_MM            # noqa: E402
from meerk40t.svgelements import Matrix                 # noqa: E402

from galvoscan.analysis.galvo import FRAME_PERIOD       # noqa: E402
from galvoscan.geometry.field import PlanError          # noqa: E402
from galvoscan.meerk40t.cutcode import job_from_cuts, job_parts  # noqa: E402

from meerk40t_session import (FIELD_MM, PROFILE, UNIT_MM, GrblSender,  # noqa: E402
                              distance_to_rect, marks_off_the_wires, median_pitch,
                              outline_gaps, plan_name)
from fly_marks import writes                            # noqa: E402
from vector_board import pulses_per_frame               # noqa: E402


def _scene_to_field(points):
    """meerk40t's scene units (Y down, the field's top left corner at 0,0) as field mm
    (centre 0,0, Y up): the scene's mm are ``UNITS_PER_MM`` of its units."""
    points = np.asarray(points, dtype=float).reshape(-1, 2) / UNITS_PER_MM
    return np.column_stack([points[:, 0] - FIELD_MM / 2, FIELD_MM / 2 - points[:, 1]])


def _spool(kernel, device, command, *, timeout_s=60):
    """Spool ``command`` (the elements made before it) planned as the other tests plan, and
    wait until the device has run (or refused) it."""
    device.driver.last_report = device.driver.last_error = None
    kernel.console(f"{command} {plan_name()} copy-selected preprocess validate blob preopt "
                   f"optimize spool\n")
    _ended(device, timeout_s)


def _ended(device, timeout_s=60):
    deadline = time.monotonic() + timeout_s
    while device.driver.last_report is None and device.driver.last_error is None:
        assert time.monotonic() < deadline, "the device did not finish the job"
        time.sleep(0.02)
    assert device.driver.last_error is None, device.driver.last_error


def _pulses(board, since):
    """Each laser pulse, frame ``since`` on: ``(clock, position)``, the position (field mm)
    the frame in force at it put the mirrors at, read off the pins and wires as
    :func:`vector_board.pulses_per_frame` reads them (a rising PRR edge while modulation is
    on, given to the frame in force before it)."""
    board.run_for(0)
    frames = np.array([xy for _, xy in board.xy2_frames()], dtype=float)
    sync = np.array(board.sync_pins, dtype=bool)
    starts = np.flatnonzero(sync[1:] & ~sync[:-1]) + 1
    first = max(1, int(starts[since])) if 0 < since < len(starts) else 1
    pins = np.array(board.laser_pins[first - 1:], dtype=np.int32)
    rising = np.flatnonzero((pins[1:, 2] == 1) & (pins[:-1, 2] == 0) & (pins[1:, 1] == 1))
    clocks = rising + first
    where = frames[np.searchsorted(starts, clocks) - 2]
    return clocks, (where.reshape(-1, 2) - 32768) * UNIT_MM


def _nearest(points, others, within):
    """Each point's distance (mm) to the nearest of ``others``, where one is within
    ``within`` of it in x (else infinity): ``others`` sorted by x, each point looking only at
    those in its x window."""
    others = others[np.argsort(others[:, 0])]
    low = np.searchsorted(others[:, 0], points[:, 0] - within)
    high = np.searchsorted(others[:, 0], points[:, 0] + within)
    return np.array([np.hypot(*(others[a:b] - p).T).min() if b > a else np.inf
                     for p, a, b in zip(points, low, high)])


# --- a line of meerk40t's text ---------------------------------------------------------------

#: The text, where its baseline starts (scene mm) and its size (meerk40t's font size, mm).
TEXT, TEXT_AT, TEXT_SIZE_MM = "Gk", (50.0, 56.0), 4.0
TEXT_SPEED_MM_S, TEXT_PRR_KHZ = 500.0, 50.0
#: meerk40t's text path is read off as points this far apart (mm) along it.
SAMPLE_MM = 0.005


@pytest.fixture
def fonts(meerk40t, tmp_path):
    """meerk40t's font directory: one of the test's own, with matplotlib's DejaVu Sans (a TTF
    that is there wherever galvoscan is installed)."""
    kernel, device, board, lines = meerk40t
    ttf = Path(matplotlib.get_data_path()) / "fonts" / "ttf" / "DejaVuSans.ttf"
    shutil.copy(ttf, tmp_path / ttf.name)
    fonts = kernel.root.fonts
    before = fonts.font_directory
    fonts.font_directory = str(tmp_path)
    yield ttf.name
    fonts.font_directory = before


def test_a_line_of_meerk40ts_text_is_marked_on_its_outlines(meerk40t, fonts):
    """meerk40t's ``linetext`` (its own font renderer: the glyphs' outlines as a path),
    engraved: every mark off the wires lies on the path meerk40t made (read off its element,
    in its scene's units) within the chord tolerance and half a pitch, and the marks go all
    along it."""
    kernel, device, board, lines = meerk40t
    kernel.elements.clear_all()
    kernel.console(f"linetext {TEXT_AT[0]:g}mm {TEXT_AT[1]:g}mm {TEXT} -f {fonts} "
                   f"-s {TEXT_SIZE_MM:g}mm\n")
    (text,) = list(kernel.elements.elems())
    # meerk40t's own geometry of it: its subpaths sampled every SAMPLE_MM.
    polylines, current = [], []
    for point in text.as_geometry().as_equal_interpolated_points(
            distance=SAMPLE_MM * UNITS_PER_MM, expand_lines=True):
        if point is None:
            if len(current) > 1:
                polylines.append(_scene_to_field([(p.real, p.imag) for p in current]))
            current = []
        else:
            current.append(point)
    if len(current) > 1:
        polylines.append(_scene_to_field([(p.real, p.imag) for p in current]))
    assert len(polylines) >= 2                  # the outlines of G and of k
    board.run_for(0)
    before = len(board.xy2_frames())
    _spool(kernel, device, f"element* engrave -s {TEXT_SPEED_MM_S:g} -p 500 frequency "
                           f"{TEXT_PRR_KHZ:g}")
    assert device.driver.last_report.clean
    marks, _ = marks_off_the_wires(board, before)
    assert len(marks) > 200
    pitch = median_pitch(marks)
    # (The samples are SAMPLE_MM apart: a point of the path is within half that of one.)
    reach = device.tolerance_mm + pitch / 2 + UNIT_MM + SAMPLE_MM / 2
    samples = np.concatenate(polylines)
    assert _nearest(marks, samples, reach).max() <= reach
    # All along it: every sampled point of the outlines within reach of a mark.
    assert _nearest(samples, marks, reach).max() <= reach


# --- an image ---------------------------------------------------------------------------------

#: The image: '#' dark, '.' light; a pixel PIXEL_MM square, its top left corner at CORNER
#: (scene mm).
IMAGE = [".##.#...##",
         "...#......",
         "##########",
         "#.......##"]
PIXEL_MM, CORNER = 0.2, (50.0, 52.0)
IMAGE_SPEED_MM_S, IMAGE_PRR_KHZ = 100.0, 50.0


def test_an_image_is_marked_on_its_dark_pixels(meerk40t):
    """An image element at 0.2 mm a pixel (its dpi), engraved by meerk40t's image operation
    (a RasterCut, walked as meerk40t's galvo driver walks it): every mark off the wires lies on
    a dark pixel of the image as meerk40t places it (its ``as_image`` bounds: the pixel squares
    in the scene), and every dark pixel's centre has a mark within half a pitch."""
    kernel, device, board, lines = meerk40t
    kernel.elements.clear_all()
    image = Image.new("L", (len(IMAGE[0]), len(IMAGE)), 255)
    for y, row in enumerate(IMAGE):
        for x, pixel in enumerate(row):
            if pixel == "#":
                image.putpixel((x, y), 0)
    matrix = Matrix()
    matrix.post_scale(PIXEL_MM * UNITS_PER_MM)
    matrix.post_translate(CORNER[0] * UNITS_PER_MM, CORNER[1] * UNITS_PER_MM)
    node = kernel.elements.elem_branch.add(type="elem image", image=image, matrix=matrix,
                                           dpi=25.4 / PIXEL_MM, dither=False)
    # meerk40t's geometry of the image: the image its operation rasters, and its bounds.
    shown, (x0, y0, x1, y1) = node.as_image()
    shown = np.array(shown.convert("L"))
    assert shown.shape == (len(IMAGE), len(IMAGE[0]))
    step = np.array([(x1 - x0) / shown.shape[1], (y1 - y0) / shown.shape[0]])
    dark = np.argwhere(shown < 128)[:, ::-1]                  # (column, row) of each
    board.run_for(0)
    before = len(board.xy2_frames())
    _spool(kernel, device, f"element* imageop -s {IMAGE_SPEED_MM_S:g} -p 500 frequency "
                           f"{IMAGE_PRR_KHZ:g}")
    assert device.driver.last_report.clean
    marks, _ = marks_off_the_wires(board, before)
    pitch = median_pitch(marks)
    # Each mark in the scene's units: on a dark pixel's square (a galvo unit's rounding).
    slack = UNIT_MM * UNITS_PER_MM
    in_scene = np.column_stack([(marks[:, 0] + FIELD_MM / 2), (FIELD_MM / 2 - marks[:, 1])]) \
        * UNITS_PER_MM
    cells = (in_scene - (x0, y0)) / step
    for (column, row), point in zip(cells, in_scene):
        near = [(c, r) for c, r in dark
                if x0 + c * step[0] - slack <= point[0] <= x0 + (c + 1) * step[0] + slack and
                y0 + r * step[1] - slack <= point[1] <= y0 + (r + 1) * step[1] + slack]
        assert near, f"a mark on no dark pixel: pixel ({column:.2f}, {row:.2f})"
    centres = _scene_to_field((x0, y0) + (dark + 0.5) * step)
    nearest = np.min(np.hypot(*(centres[:, None, :] - marks[None, :, :]).transpose(2, 0, 1)),
                     axis=1)
    assert nearest.max() <= pitch / 2 + UNIT_MM


# --- two operations in one job; a wait between two --------------------------------------------

#: The engrave: a rectangle (scene mm: x, y, width, height) at its speed (mm/s), power (‰) and
#: PRR (kHz); the cut: a circle (scene mm: centre, radius) at its own.
ENGRAVE_RECT, ENGRAVE = (48.0, 50.0, 5.0, 3.0), (400.0, 600.0, 50.0)
CUT_CIRCLE, CUT = (60.0, 57.0, 2.0), (150.0, 300.0, 25.0)


@pytest.fixture
def unclassified(meerk40t):
    """meerk40t not classifying new elements into operations (its default adds each to every
    operation of its colour, and makes one where none is): each element in the one operation
    its command gives it."""
    kernel, device, board, lines = meerk40t
    elements = kernel.elements
    before = elements.classify_new
    elements.classify_new = False
    yield
    elements.classify_new = before


def _rect_field(x, y, width, height):
    """A scene rectangle's (left, top, right, bottom), field mm."""
    left, top = x - FIELD_MM / 2, FIELD_MM / 2 - y
    return left, top, left + width, top - height


def _measured(board, wires, on):
    """Of ``wires`` (:func:`marks_off_the_wires`' marks and pulses, :func:`_pulses`' clocks
    and positions), the marks (field mm) that ``on`` (a function of the points) picks, their
    pitch (mm, median), pulses per point (median) and PRR (kHz: the laser's pulses' median
    spacing on the pins, at the board's clock)."""
    marks, pulses, clocks, where = wires
    picked = on(marks)
    spacing = np.diff(clocks[on(where)])
    return (marks[picked], median_pitch(marks[picked]), int(np.median(pulses[picked])),
            board.clk_freq / float(np.median(spacing)) / 1e3)


def test_two_operations_are_two_layers_each_at_its_own_speed(meerk40t, unclassified):
    """An engrave and a cut in one job: each its own layer (the console says both, each at
    its speed, power and PRR), and on the wires each marked at its own speed: its pitch × its
    PRR (measured on the laser's pins) / its pulses per point."""
    kernel, device, board, lines = meerk40t
    kernel.elements.clear_all()
    kernel.console(f"rect {' '.join(f'{v:g}mm' for v in ENGRAVE_RECT)} engrave "
                   f"-s {ENGRAVE[0]:g} -p {ENGRAVE[1]:g} frequency {ENGRAVE[2]:g}\n")
    kernel.console(f"circle {' '.join(f'{v:g}mm' for v in CUT_CIRCLE)} cut "
                   f"-s {CUT[0]:g} -p {CUT[1]:g} frequency {CUT[2]:g}\n")
    board.run_for(0)
    before = len(board.xy2_frames())
    said = len(lines)
    device.driver.last_report = device.driver.last_error = None
    kernel.console(f"{plan_name()} copy preprocess validate blob preopt optimize spool\n")
    _ended(device)
    console = " ".join(" ".join(lines[said:]).split())
    for speed, power, prr in (ENGRAVE, CUT):
        assert f"speed {speed:g} mm/s, power {power / 10:g} %, PRR {prr:g} kHz" in console
    left, top, right, bottom = _rect_field(*ENGRAVE_RECT)
    cx, cy = CUT_CIRCLE[0] - FIELD_MM / 2, FIELD_MM / 2 - CUT_CIRCLE[1]

    def on_rect(points):
        return distance_to_rect(points, left, top, right, bottom) <= 0.05

    def on_circle(points):
        return abs(np.hypot(points[:, 0] - cx, points[:, 1] - cy) - CUT_CIRCLE[2]) <= 0.05
    wires = (*marks_off_the_wires(board, before), *_pulses(board, before))
    for on, (speed, _, prr) in ((on_rect, ENGRAVE), (on_circle, CUT)):
        marks, pitch, per_point, prr_khz = _measured(board, wires, on)
        assert len(marks) > 100
        assert prr_khz == pytest.approx(prr, rel=0.01)
        assert pitch * prr_khz * 1e3 / per_point == pytest.approx(speed, rel=0.03)
    # Nothing marked off the two.
    marks = wires[0]
    assert (on_rect(marks) | on_circle(marks)).all()
    rect_marks = marks[on_rect(marks)]
    assert outline_gaps(rect_marks, left, top, right, bottom) <= median_pitch(rect_marks) / 2 \
        + UNIT_MM


#: The wait between the two rectangles (s: meerk40t's wait operation's unit).
WAIT_S = 0.01
#: How far (s) the time a wait adds on the wires may be from the wait: the link's exchanges
#: around the hold (a few frames).
WAIT_SLACK_S = 0.5e-3


def _gap_between_two_rects(kernel, device, board, wait_s):
    """Two rectangles engraved in one job as two operations, meerk40t's wait operation
    (``waitop``: a WaitCut in the job) between them if ``wait_s``: the time (s) on the pins
    from the first's last pulse to the second's first, each marked whole."""
    kernel.elements.clear_all()
    first, second = (48.0, 50.0, 3.0, 2.0), (56.0, 50.0, 3.0, 2.0)
    kernel.console(f"rect {' '.join(f'{v:g}mm' for v in first)} engrave -s 400 -p 500 "
                   f"frequency 50\n")
    if wait_s:
        kernel.console(f"waitop {wait_s:g}\n")
    kernel.console(f"rect {' '.join(f'{v:g}mm' for v in second)} engrave -s 400 -p 500 "
                   f"frequency 50\n")
    board.run_for(0)
    before = len(board.xy2_frames())
    device.driver.last_report = device.driver.last_error = None
    kernel.console(f"{plan_name()} copy preprocess validate blob preopt optimize spool\n")
    _ended(device)
    assert device.driver.last_report.clean
    clocks, where = _pulses(board, before)
    on_first = distance_to_rect(where, *_rect_field(*first)) <= 0.05
    on_second = distance_to_rect(where, *_rect_field(*second)) <= 0.05
    assert (on_first | on_second).all() and on_first.sum() > 100 and on_second.sum() > 100
    # The first marked whole before the second began.
    assert clocks[on_first].max() < clocks[on_second].min()
    return (clocks[on_second].min() - clocks[on_first].max()) / board.clk_freq


def test_a_wait_operation_holds_the_board_for_its_time(meerk40t, unclassified):
    """An engrave, meerk40t's wait operation and another engrave: both marked, and on the pins
    the laser fires nothing between them for the wait, and the wait adds its time to the gap
    the same two operations have without it (the host ends one part and starts the next as it
    always does: its status polls and the laser's MO lead)."""
    kernel, device, board, lines = meerk40t
    without = _gap_between_two_rects(kernel, device, board, 0)
    said = len(lines)
    gap = _gap_between_two_rects(kernel, device, board, WAIT_S)
    assert gap >= WAIT_S
    assert gap - without == pytest.approx(WAIT_S, abs=WAIT_SLACK_S), (gap, without)
    assert any(f"waited {WAIT_S * 1e3:g} ms" in line for line in lines[said:])


def test_the_drivers_wait_and_dwell_on_the_board(meerk40t):
    """meerk40t's driver calls ``wait`` (a hold: the board's frames go on for its time, no
    pulse, the laser disarmed) and ``dwell`` (the laser on where the head is: its time ×
    the PRR in pulses, at that point), spooled as meerk40t's own commands are."""
    kernel, device, board, lines = meerk40t
    spool_and_wait_items(kernel, device, [("wait", 10)])    # (the board made, idle)
    board.run_for(0)
    frames, pulses = len(board.xy2_frames()), len(board.board.pulses)
    clocks = len(board.laser_pins)
    spool_and_wait_items(kernel, device, [("wait", 10)])
    board.run_for(0)
    held_s = (len(board.xy2_frames()) - frames) * FRAME_PERIOD
    assert 10e-3 <= held_s <= 10e-3 + WAIT_SLACK_S, held_s
    assert len(board.board.pulses) == pulses
    enable = board.LASER_PIN_NAMES.index("laser_enable")
    assert not any(pins[enable] for pins in board.laser_pins[clocks:])
    # A dwell of 4 ms at 50 kHz where the head was moved: 200 pulses at one point.
    board.run_for(0)
    before = len(board.xy2_frames())
    spool_and_wait_items(kernel, device, [("move_abs", "52mm", "53mm"),
                                          ("dwell", 4, {"power": 500.0, "frequency": 50.0})])
    assert device.driver.last_report.clean
    marks, counts = marks_off_the_wires(board, before)
    assert len(marks) == 1 and counts.tolist() == [200]
    assert marks[0] == pytest.approx([52 - FIELD_MM / 2, FIELD_MM / 2 - 53], abs=UNIT_MM)


def spool_and_wait_items(kernel, device, items, timeout_s=60):
    """``items`` (what meerk40t's spooler calls the driver with) as a job of meerk40t's
    spooler, and wait until the device has done it."""
    device.driver.last_report = device.driver.last_error = None
    device.spooler.laserjob(list(items), label="test items", helper=True)
    _ended(device, timeout_s)


# --- input and output operations --------------------------------------------------------------

def test_io_cuts_on_a_board_without_io_are_one_line_and_nothing_marked(meerk40t):
    """A job with meerk40t's output cut in it, spooled to the device on a board whose
    bitstream has no I/O in the queue (the iCEBreaker's default): one line on the console, and
    not a write to the board (its caps read alone), not even of the lines before it."""
    kernel, device, board, lines = meerk40t
    sent, pulses = len(board.board.bytes_in), len(board.board.pulses)
    said = len(lines)
    device.driver.last_report = device.driver.last_error = None
    settings = {"speed": 400.0, "power": 500.0, "frequency": 50.0}
    line = LineCut((30000, 30000), (31000, 30000), settings=settings)
    device.spooler.laserjob([("plot", line), ("plot", OutputCut(1, 1)), "plot_start"],
                            label="test io", helper=True)
    deadline = time.monotonic() + 30
    while device.driver.last_error is None:
        assert time.monotonic() < deadline
        time.sleep(0.02)
    errors = [said_line for said_line in lines[said:] if "galvoscan: error:" in said_line]
    assert len(errors) == 1 and "no I/O in the queue" in errors[0] and \
        "nothing was sent" in errors[0]
    assert writes(board.board.bytes_in[sent:]) == [] and len(board.board.pulses) == pulses


def test_waits_split_a_job_and_a_bad_wait_is_one_line():
    """WaitCuts split the cuts into parts and holds (ms as seconds; a wait of 0 none); a wait
    below 0, not a number or over an hour is one line."""
    a = LineCut((30000, 30000), (31000, 30000), settings={})
    b = LineCut((31000, 30000), (31000, 31000), settings={})
    assert job_parts([a, WaitCut(250.0), WaitCut(0), b]) == \
        [("cuts", [a]), ("hold", 0.25), ("cuts", [b])]
    assert job_parts([WaitCut(5.0)]) == [("hold", 0.005)]
    for bad in (-1.0, float("nan"), float("inf"), 4e6, "soon"):
        with pytest.raises(PlanError) as refused:
            job_parts([a, WaitCut(bad)])
        assert "a wait" in str(refused.value) and "\n" not in str(refused.value)
    with pytest.raises(PlanError, match="job_parts takes it out"):
        job_from_cuts([InputCut(1, 1)], PROFILE, tolerance_mm=0.01)


# --- G-code opened in meerk40t ----------------------------------------------------------------

#: An L in G-code (mm, Y up as G-code's is): its corner, a stem STEM mm up and a foot FOOT mm
#: to the right: it is not its mirror image either way, so a flip in X or Y shows.
L_CORNER, STEM, FOOT = (50.0, 52.0), 4.0, 2.0
L_GCODE = (f"G21 G90\nG0 X{L_CORNER[0]:g} Y{L_CORNER[1] + STEM:g}\nM4 S500 F24000\n"
           f"G1 X{L_CORNER[0]:g} Y{L_CORNER[1]:g}\nG1 X{L_CORNER[0] + FOOT:g} "
           f"Y{L_CORNER[1]:g}\nM5\n")


def test_gcode_opened_in_meerk40t_is_marked_the_right_way_up(meerk40t, tmp_path):
    """A G-code file opened in meerk40t (its G-code loader: a blob of the file for the device)
    is marked as meerk40t places G-code on its GRBL device: the file's 0,0 at the lens field's
    lower left corner, its Y up. The L off the wires: its stem above its corner, its foot to
    the right, at the file's coordinates from that corner, at F24000's 400 mm/s."""
    kernel, device, board, lines = meerk40t
    kernel.elements.clear_all()
    path = tmp_path / "l.gcode"
    path.write_text(L_GCODE)
    kernel.console(f"load {path}\n")
    assert [op.type for op in kernel.elements.ops()] == ["blob"]
    board.run_for(0)
    before = len(board.xy2_frames())
    device.driver.last_report = device.driver.last_error = None
    kernel.console(f"{plan_name()} copy preprocess validate blob preopt optimize spool\n")
    _ended(device)
    assert device.driver.last_report.clean
    marks, pulses = marks_off_the_wires(board, before)
    # The file's mm from the field's lower left corner (field mm: centre 0,0, Y up).
    x, y = marks[:, 0] + FIELD_MM / 2, marks[:, 1] + FIELD_MM / 2
    x0, y0 = L_CORNER
    pitch = median_pitch(marks)
    reach = pitch / 2 + UNIT_MM
    on_stem = (abs(x - x0) <= reach) & (y0 - reach <= y) & (y <= y0 + STEM + reach)
    on_foot = (abs(y - y0) <= reach) & (x0 - reach <= x) & (x <= x0 + FOOT + reach)
    assert (on_stem | on_foot).all()
    # All along both: the stem's top and the foot's end marked.
    assert np.hypot(x - x0, y - (y0 + STEM)).min() <= reach
    assert np.hypot(x - (x0 + FOOT), y - y0).min() <= reach
    speed = pitch * PROFILE.defaults.prr_khz * 1e3 / int(np.median(pulses))
    assert speed == pytest.approx(24000 / 60, rel=0.03)


@settings(max_examples=80, deadline=None)
@given(wait=st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10**9, 10**9),
                      st.text(max_size=5), st.none(), st.just(3.6e6)))
def test_any_wait_is_a_hold_or_one_line(wait):
    """A WaitCut's time comes from outside (a wait operation's setting, G-code's G4): any
    value is a hold of 0 s to an hour, or refused in one line naming the wait."""
    line = LineCut((30000, 30000), (31000, 30000), settings={})
    try:
        parts = job_parts([line, WaitCut(wait), line])
    except PlanError as error:
        assert str(error).startswith("a wait of") and "\n" not in str(error)
        return
    holds = [seconds for kind, seconds in parts if kind == "hold"]
    assert all(0 < seconds <= 3600 for seconds in holds)
    assert [kind for kind, _ in parts] in (["cuts", "hold", "cuts"], ["cuts", "cuts"])


def test_a_senders_gcode_is_marked_the_right_way_up(meerk40t, grbl_port):
    """The same L from a G-code sender on the device's ``grblcontrol``: marked as the file
    opened in meerk40t is, its stem above its corner and its foot to the right, the file's mm
    from the field's lower left corner; ``?`` at the end says where the head is in the same
    G-code coordinates (the foot's end)."""
    kernel, device, board, lines = meerk40t
    device.driver.last_report = device.driver.last_error = None
    kernel.console(f"grblcontrol -p {grbl_port}\n")
    board.run_for(0)
    before = len(board.xy2_frames())
    sender = GrblSender(grbl_port)
    try:
        answers = [sender.send(line) for line in L_GCODE.splitlines()]
        _ended(device)
        sender.socket.sendall(b"?")
        status = sender.line()
    finally:
        sender.close()
        kernel.console("grblcontrol quit\n")
    assert answers == ["ok"] * len(answers)
    assert device.driver.last_report.clean
    marks, _ = marks_off_the_wires(board, before)
    x, y = marks[:, 0] + FIELD_MM / 2, marks[:, 1] + FIELD_MM / 2
    x0, y0 = L_CORNER
    reach = median_pitch(marks) / 2 + UNIT_MM
    on_stem = (abs(x - x0) <= reach) & (y0 - reach <= y) & (y <= y0 + STEM + reach)
    on_foot = (abs(y - y0) <= reach) & (x0 - reach <= x) & (x <= x0 + FOOT + reach)
    assert (on_stem | on_foot).all()
    assert np.hypot(x - x0, y - (y0 + STEM)).min() <= reach
    assert np.hypot(x - (x0 + FOOT), y - y0).min() <= reach
    reported = re.search(r"MPos:([-\d.]+),([-\d.]+),", status)
    assert reported, status
    assert (float(reported[1]), float(reported[2])) == pytest.approx((x0 + FOOT, y0), abs=0.01)


def test_damaged_gcode_or_another_blob_is_one_line_and_nothing_sent(meerk40t):
    """A G-code blob with a damaged line (the line named, as ``galvoscan mark`` names it), or a
    blob of another kind (a Lihuiyu device's EGV): one line on the console, not a byte to the
    board."""
    kernel, device, board, lines = meerk40t
    sent = len(board.board.bytes_in)
    for data_type, data, words in (("grbl", b"G21 G90\nM3 S500 F600\nG1 X10 Y1O\n",
                                    "line 3 ('G1 X10 Y1O')"),
                                   ("egv", b"IPPzzzzFNSE-\n", "'egv' data")):
        said = len(lines)
        spool_and_wait_items_refused(kernel, device, [("blob", data_type, data)])
        errors = [line for line in lines[said:] if "galvoscan: error:" in line]
        assert len(errors) == 1 and words in errors[0] and "nothing sent" in errors[0], \
            lines[said:]
        assert "/tmp" not in errors[0]
    assert len(board.board.bytes_in) == sent


def spool_and_wait_items_refused(kernel, device, items, timeout_s=30):
    device.driver.last_report = device.driver.last_error = None
    device.spooler.laserjob(list(items), label="test refused", helper=True)
    deadline = time.monotonic() + timeout_s
    while device.driver.last_error is None:
        assert time.monotonic() < deadline and device.driver.last_report is None
        time.sleep(0.02)
