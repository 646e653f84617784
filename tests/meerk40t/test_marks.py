"""What meerk40t makes besides rectangles and circles, marked through the galvoscan device on the
simulated board (headless and in-process: tests/support/meerk40t_session.py) and read off the
XY2-100 wires and the laser pins by the tests' own readers, against meerk40t's own geometry
read off its elements (not the device's): a line of its text (``linetext``), an image
(``imageop``: a RasterCut), two operations in one job (each its own layer, each one's speed,
PRR and pulses per point measured on the wires), a wait operation between two (the board held
for its time, measured on the wires), the driver's own ``wait`` and ``dwell``, and I/O
operations refused in one line naming galvoscan issue #38."""

import shutil
import time
from pathlib import Path

import matplotlib
import numpy as np
import pytest
from PIL import Image

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

from meerk40t_session import (FIELD_MM, PROFILE, UNIT_MM, distance_to_rect,  # noqa: E402
                              marks_off_the_wires, median_pitch, outline_gaps, plan_name)
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
    :func:`vector_board.pulses_per_frame` reads them (its frame for a pulse)."""
    board.run_for(0)
    frames = [xy for xy, _ in pulses_per_frame(board, 0)]
    sync, pins = board.sync_pins, board.laser_pins
    starts = [i for i in range(1, len(sync)) if sync[i] and not sync[i - 1]]
    first = starts[since] if 0 < since < len(starts) else 1
    clocks, where = [], []
    for clock in range(max(1, first), len(pins)):
        if pins[clock][2] and not pins[clock - 1][2] and pins[clock][1]:
            clocks.append(clock)
            where.append(frames[np.searchsorted(starts, clock) - 2])
    return np.array(clocks), (np.array(where, dtype=float).reshape(-1, 2) - 32768) * UNIT_MM


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
