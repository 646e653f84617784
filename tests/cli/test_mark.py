"""`galvoscan mark` end to end: drawings read, planned and streamed over the serial link into
the simulated board (``--sim``: the system top served on a pseudo-terminal, the same link code
a real board gets), and what the XY2-100 wires and the DB25 pins did checked against the
drawing's own geometry, written out here independently of the planner."""

import json
import math
import os
import re
import subprocess
import sys

import numpy as np
import pytest

from galvoscan.bench_sim import PHOTO_GALVO, shaded_picture
from galvoscan.cli import main

from sim_board import VECTOR_BOARD, quick_sim_board


SPEED_MM_S = 2000.0
PRR_KHZ = 50.0
# A machine with a 0.1 mm spot and quick mirrors: fewer points and shorter waits to simulate.
PROFILE = """
[laser]
spot_mm = 0.1
[galvo]
jump_delay_us = 100
"""
# Pitch the planner may choose at most (half the 0.1 mm spot), one galvo unit of rounding on a
# 110 mm field, and the chord tolerance of curves.
HALF_PITCH_MM = 0.025
UNIT_MM = 110 / 65536
CHORD_MM = 0.01

# A 1 mm square with a 0.3 mm square hole (one path, even-odd) and a circle, SVG units = mm:
# small, so that the simulated board marks it in a few milliseconds of its time (the hatch
# lines are still a dozen, the circle still dozens of chords).
SVG = """<svg xmlns="http://www.w3.org/2000/svg" width="2mm" height="2mm" viewBox="0 0 2 2">
  <path d="M 0.25 0.25 H 1.25 V 1.25 H 0.25 Z M 0.6 0.6 H 0.9 V 0.9 H 0.6 Z"
        fill-rule="evenodd" fill="none" stroke="black"/>
  <circle cx="1.6" cy="1.6" r="0.3" fill="none" stroke="black"/>
</svg>
"""
HATCH_MM = 0.125
# The SVG, DXF and Ctrl-C jobs run on VECTOR_BOARD: vector mode alone, without the correction
# stage (which passes points through unchanged in vector mode with its identity table): the
# job's CPU 15-20 % less than on the default build, whose vector path the wobble mark, clean,
# job and link tests run.
# The simulated board's answers, in host seconds: a batch of 128 segments is 15 ms of the
# board's time, a minute of a busy machine's (the command line's 60 s is for a machine to
# itself).
SIM_TIMEOUT = ["--timeout", "600"]
#: The tests' shared helpers (sim_board), for a child process's sys.path.
SUPPORT = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "support")
# A port that cannot be opened: an error about the drawing or the profile, not about the port,
# shows the job was refused before the link was touched.
NOPORT = ["--port", "/nonexistent/ttyUSB9"]


def run_json(args, capsys):
    assert main(args) == 0
    out = capsys.readouterr().out
    return json.loads(out.strip().splitlines()[-1])


def distance_to_segment(p, a, b):
    p, a, b = (np.asarray(v, dtype=float) for v in (p, a, b))
    ab = b - a
    t = np.clip(np.dot(p - a, ab) / np.dot(ab, ab), 0, 1)
    return float(np.hypot(*(p - (a + t * ab))))


def distance_to_polygon(p, corners):
    return min(distance_to_segment(p, corners[i], corners[(i + 1) % len(corners)])
               for i in range(len(corners)))


# The SVG's shapes in its own coordinates (mm, Y down), as the JSON's drawing_marks are.
OUTER = [(0.25, 0.25), (1.25, 0.25), (1.25, 1.25), (0.25, 1.25)]
HOLE = [(0.6, 0.6), (0.9, 0.6), (0.9, 0.9), (0.6, 0.9)]
CIRCLE = ((1.6, 1.6), 0.3)


def inside_region(p):
    """Even-odd: in the outer square and not in the hole, or in the circle."""
    x, y = p
    in_outer = 0.25 <= x <= 1.25 and 0.25 <= y <= 1.25
    in_hole = 0.6 < x < 0.9 and 0.6 < y < 0.9
    (cx, cy), r = CIRCLE
    return (in_outer and not in_hole) or math.hypot(x - cx, y - cy) <= r


def outline_distance(p):
    (cx, cy), r = CIRCLE
    return min(distance_to_polygon(p, OUTER), distance_to_polygon(p, HOLE),
               abs(math.hypot(p[0] - cx, p[1] - cy) - r))


# Session-wide, so that the drawing is marked once however the worker interleaves the two
# tests with other modules' (a module's fixture is torn down whenever another module's test
# comes between); the tests share one worker by their xdist_group.
@pytest.fixture(scope="session")
def svg_result(tmp_path_factory):
    folder = tmp_path_factory.mktemp("svg")
    path = folder / "shape.svg"
    path.write_text(SVG)
    machine = folder / "machine.toml"
    machine.write_text(PROFILE)
    import contextlib
    import io
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()), \
            quick_sim_board(**VECTOR_BOARD):
        assert main(["mark", str(path), "--speed", str(SPEED_MM_S), "--prr", str(PRR_KHZ),
                     "--hatch", str(HATCH_MM), "--machine", str(machine), "--sim", *SIM_TIMEOUT,
                     "--json"]) == 0
    return json.loads(out.getvalue().strip().splitlines()[-1])


@pytest.mark.xdist_group("svg_job")
def test_the_svg_tests_share_a_worker(request):
    """Under ``--dist loadgroup`` the group is in the test's id, which is what sends the group
    to one worker (and the marking above is done once): a pytest that drops it (9.2 with
    pytest-xdist 3.8) would split them silently."""
    if getattr(request.config.option, "loadgroup", False):
        assert request.node.nodeid.endswith("@svg_job")


@pytest.mark.slow
@pytest.mark.xdist_group("svg_job")
def test_svg_marks_lie_on_the_drawing(svg_result):
    assert svg_result["drawing_frame"].startswith("the SVG's own")
    marks = svg_result["drawing_marks"]
    assert len(marks) > 100
    tolerance = HALF_PITCH_MM + CHORD_MM + UNIT_MM
    hatch_ys = []
    for p in marks:
        if outline_distance(p) <= tolerance:
            continue
        # Not on an outline: a hatch point, inside the even-odd region, on a hatch line.
        assert inside_region(p), p
        hatch_ys.append(p[1])
    # Hatch lines every HATCH_MM (one galvo unit of rounding).
    levels = sorted({round(y / UNIT_MM) for y in hatch_ys})
    lines = [levels[0]]
    for level in levels[1:]:
        if level - lines[-1] > 2:
            lines.append(level)
    gaps = np.diff(np.array(lines) * UNIT_MM) / HATCH_MM
    assert len(lines) >= 6
    # One grid of lines HATCH_MM apart: between the square and the circle some are empty.
    assert np.all(np.abs(gaps - np.round(gaps)) <= 2 * UNIT_MM / HATCH_MM), gaps
    assert np.sum(np.round(gaps) == 1) >= len(gaps) - 2


@pytest.mark.slow
@pytest.mark.xdist_group("svg_job")
def test_svg_corners_hit_speed_and_counters(svg_result):
    marks = np.array(svg_result["drawing_marks"])
    for corner in OUTER + HOLE:
        assert np.min(np.hypot(*(marks - corner).T)) <= 1.5 * UNIT_MM, corner
    # The circle is marked all round (every chord's end lies on it, within the tolerance).
    (cx, cy), r = CIRCLE
    on_circle = marks[np.abs(np.hypot(marks[:, 0] - cx, marks[:, 1] - cy) - r) <= 0.02]
    angles = np.sort(np.arctan2(on_circle[:, 1] - cy, on_circle[:, 0] - cx))
    assert np.max(np.diff(angles)) < 2 * HALF_PITCH_MM * 2 / r
    assert abs(svg_result["speed_mm_s"] - SPEED_MM_S) / SPEED_MM_S <= 0.02
    assert svg_result["underruns"] == svg_result["errors"] == svg_result["rejected"] == 0
    assert svg_result["pulses_per_point"] == 1
    # Along the whole path (the short last step of every segment included) a little slower.
    assert 0.9 * SPEED_MM_S <= svg_result["path_speed_mm_s"] <= svg_result["speed_mm_s"]


def dxf_drawing(path, zigzag_points):
    import ezdxf
    doc = ezdxf.new(units=4)            # mm
    msp = doc.modelspace()
    msp.add_line((0, 0), (4, 0))
    msp.add_arc((2, 2), 1.5, 0, 180)
    # A polyline with a bulge of 1: a half circle from (5, 0) to (7, 0), centre (6, 0).
    msp.add_lwpolyline([(5, 0, 0, 0, 1), (7, 0)], format="xyseb")
    # Many short segments: with the rest, more than the board's queue holds.
    msp.add_lwpolyline([(0.05 * i, -1 - 0.03 * (i % 2)) for i in range(zigzag_points)])
    doc.saveas(path)


# The vector queue of the board the DXF job runs on: a real board's holds 512 segments; this
# one is built to hold 48, so that a job longer than the queue (the host refilling it as it
# empties) is a few dozen segments to send, not several hundred.
SHORT_QUEUE = 48


@pytest.mark.slow
def test_dxf_longer_than_the_queue_never_underruns(tmp_path, capsys):
    path = tmp_path / "parts.dxf"
    # With the line, the arc and the bulge (30 segments) the job is 55 segments, longer than
    # the queue by a seventh, as 540 zigzag points (570 segments) were for the real board's
    # 512: the part past the queue must reach the board while the queue's is marked.
    zigzag = SHORT_QUEUE // 2
    dxf_drawing(path, zigzag)
    machine = tmp_path / "machine.toml"
    machine.write_text(PROFILE)
    with quick_sim_board(vector_queue_depth=SHORT_QUEUE, **VECTOR_BOARD) as board_class:
        result = run_json(["mark", str(path), "--speed", str(SPEED_MM_S), "--prr",
                           str(PRR_KHZ), "--machine", str(machine), "--sim", *SIM_TIMEOUT,
                           "--json"], capsys)
    [board] = board_class.built
    assert board.top.config.vector_queue_depth == SHORT_QUEUE
    assert result["segments"] > SHORT_QUEUE
    assert result["underruns"] == result["errors"] == result["rejected"] == 0
    assert abs(result["speed_mm_s"] - SPEED_MM_S) / SPEED_MM_S <= 0.02
    tolerance = HALF_PITCH_MM + CHORD_MM + UNIT_MM
    zig = [(0.05 * i, -1 - 0.03 * (i % 2)) for i in range(zigzag)]

    def distance(p):
        return min(distance_to_segment(p, (0, 0), (4, 0)),
                   abs(math.hypot(p[0] - 2, p[1] - 2) - 1.5) if p[1] >= 2 - 1e-3 else 9,
                   abs(math.hypot(p[0] - 6, p[1]) - 1) if p[1] <= 1e-3 else 9,
                   # (the zigzag's segments near p's x: none past its end)
                   min((distance_to_segment(p, zig[i], zig[i + 1]) for i in
                        range(max(0, int(p[0] / 0.05) - 2), min(zigzag - 1,
                                                                 int(p[0] / 0.05) + 2))),
                       default=9))

    assert result["drawing_frame"].startswith("the drawing's own")
    marks = np.array(result["drawing_marks"])
    for p in marks[::7]:                        # every 7th point keeps the test quick
        assert distance(p) <= tolerance, p
    # Every end of every entity and every zigzag vertex is hit.
    for end in [(0, 0), (4, 0), (3.5, 2), (0.5, 2), (5, 0), (7, 0), *zig]:
        assert np.min(np.hypot(*(marks - end).T)) <= 1.5 * UNIT_MM, end


def test_out_of_field_drawing_is_refused_before_anything(tmp_path, capsys):
    path = tmp_path / "big.svg"
    big = SVG.replace('width="2mm" height="2mm"', 'width="200mm" height="200mm"')
    assert big != SVG
    path.write_text(big)
    with pytest.raises(SystemExit) as stop:
        main(["mark", str(path), *NOPORT])
    message = str(stop.value)
    assert "the field is −55.0…55.0 mm" in message and "\n" not in message


@pytest.mark.parametrize("content, expected", [
    (b"", "empty"),
    (b"<svg xmlns='http://www.w3.org/2000/svg'><path d='M 0 0 L", "svg"),
    (b"\x89PNG\r\n\x1a\n", "svg"),
])
def test_unreadable_drawings_are_one_line(tmp_path, content, expected):
    path = tmp_path / "bad.svg"
    path.write_bytes(content)
    with pytest.raises(SystemExit) as stop:
        main(["mark", str(path), *NOPORT])
    message = str(stop.value)
    assert message.startswith("galvoscan mark: error:") and "\n" not in message
    assert "bad.svg" in message


def test_unknown_suffix_missing_file_and_bad_profile(tmp_path):
    for args, words in ((["mark", str(tmp_path / "x.png"), *NOPORT], "not a drawing"),
                        (["mark", str(tmp_path / "none.svg"), *NOPORT], "none.svg")):
        (tmp_path / "x.png").write_bytes(b"\x89PNG")
        with pytest.raises(SystemExit) as stop:
            main(args)
        assert words in str(stop.value) and "\n" not in str(stop.value)
    drawing = tmp_path / "ok.svg"
    drawing.write_text(SVG)
    profile = tmp_path / "m.toml"
    profile.write_text("[laser]\nmax_power_w = 'fifty'\n")
    with pytest.raises(SystemExit) as stop:
        main(["mark", str(drawing), *NOPORT, "--machine", str(profile)])
    assert "max_power_w" in str(stop.value)


def test_units_and_placement_in_the_plan(tmp_path, capsys):
    """Without a board: the plan, in mm, for an inch DXF placed lower-left at an offset."""
    import ezdxf
    doc = ezdxf.new(units=1)            # inches
    doc.modelspace().add_line((0, 0), (1, 0))
    path = tmp_path / "inch.dxf"
    doc.saveas(path)
    assert main(["mark", str(path), "--origin", "lower-left", "--offset", "10,5",
                 "--estimate"]) == 0
    out = capsys.readouterr().out
    assert "25.4 mm marked" in out
    assert "X 10.00 … 35.40 mm, Y 5.00 … 5.00 mm" in out


def test_estimate_json_is_one_object_on_stdout(tmp_path, capsys):
    """``--estimate --json`` (and ``--json`` with no board) print the plan as one JSON object
    on stdout, the text going to stderr: a 1 inch line, 25.4 mm, three times, at the asked
    speed and PRR."""
    import ezdxf
    doc = ezdxf.new(units=1)            # inches
    doc.modelspace().add_line((0, 0), (1, 0))
    path = tmp_path / "inch.dxf"
    doc.saveas(path)
    for extra in (["--estimate"], []):
        assert main(["mark", str(path), "--origin", "lower-left", "--speed", "400", "--prr",
                     "40", "--passes", "3", "--json", *extra]) == 0
        out, err = capsys.readouterr()
        record = json.loads(out)
        assert "76.2 mm marked" in err                  # three passes
        assert record["mark_mm"] == pytest.approx(3 * 25.4, abs=0.01)
        assert record["bounds_mm"] == pytest.approx([0, 0, 25.4, 0])
        assert record["prr_khz"] == 40 and record["passes"] == 3
        assert record["speed_mm_s"] == pytest.approx(400, rel=0.02)
        # The speed is the pitch's: pitch × PRR / pulses per point.
        assert record["speed_mm_s"] == pytest.approx(
            record["pitch_um"] / 1000 * 40e3 / record["pulses_per_point"], rel=1e-3)
        assert record["estimate_s"] > 3 * 25.4 / 400


# `python -m galvoscan.cli` with the tests' quick simulated board (8 MHz, 0.5 ms MO lead,
# VECTOR_BOARD, a 16-segment queue, so the job starts after 16 segments, not 512), and a line
# on stdout at the first laser pulse: the sign that the job is mid-way with the laser on.
CTRL_C_CHILD = """
import runpy, signal, sys, threading, time
# Ctrl-C as from a terminal (a shell that starts the tests in the background has them, and so
# this process, ignore SIGINT; Python then leaves it ignored).
signal.signal(signal.SIGINT, signal.default_int_handler)
sys.path.insert(0, sys.argv.pop(1))
from sim_board import VECTOR_BOARD, quick_sim_board

def watch(built):
    while not (built and built[0].pulses):
        time.sleep(0.02)
    print("galvoscan-test: emitting", flush=True)

# (A queue of four: the link fault tests' build, whose compiled model they share.)
with quick_sim_board(vector_queue_depth=4, **VECTOR_BOARD) as board_class:
    threading.Thread(target=watch, args=(board_class.built,), daemon=True).start()
    sys.argv[0] = "galvoscan"
    runpy.run_module("galvoscan.cli", run_name="__main__", alter_sys=True)
"""


def test_ctrl_c_through_the_command_line_exits_130(tmp_path):
    """A real SIGINT to `galvoscan mark --sim` while the laser emits: exit 130, one line, no
    traceback."""
    import select
    import signal
    import time
    path = tmp_path / "shape.svg"
    path.write_text(SVG)
    process = subprocess.Popen([sys.executable, "-c", CTRL_C_CHILD, SUPPORT,
                                "mark", str(path), "--sim", *SIM_TIMEOUT, "--speed", "1000",
                                "--prr", "50",
                                "--passes", "20"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               env=dict(os.environ, PYTHONUNBUFFERED="1"))
    try:
        # Stopped the moment it is seen mid-job, however long the machine takes to get there.
        deadline = time.monotonic() + 600
        out = b""
        while b"galvoscan-test: emitting" not in out:
            assert process.poll() is None, (out, process.stderr.read())
            assert time.monotonic() < deadline, "the job never got under way"
            if select.select([process.stdout], [], [], 1)[0]:
                out += os.read(process.stdout.fileno(), 4096)
        process.send_signal(signal.SIGINT)
        # (The board finishes the step it is in, which a busy machine may take minutes over.)
        rest, err = (text.decode() for text in process.communicate(timeout=600))
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate()
    assert process.returncode == 130, (out, rest, err)
    assert "Traceback" not in err
    # How far the job got, said in the line.
    last = err.strip().splitlines()[-1]
    assert last.startswith("galvoscan: stopped (Ctrl-C): the laser is disarmed; stopped at "
                           "segment "), last
    assert last.endswith("the part is not done"), last


def test_unknown_units_are_refused_before_anything(tmp_path):
    import ezdxf
    svg = tmp_path / "furlongs.svg"
    svg.write_text(SVG.replace('width="2mm"', 'width="2furlong"'))
    doc = ezdxf.new()
    doc.header["$INSUNITS"] = 99
    doc.modelspace().add_line((0, 0), (1, 0))
    dxf = tmp_path / "odd.dxf"
    doc.saveas(dxf)
    for path, words in ((svg, "unit galvoscan does not know"), (dxf, "cannot be converted")):
        with pytest.raises(SystemExit) as stop:
            main(["mark", str(path), *NOPORT])
        message = str(stop.value)
        assert words in message and "\n" not in message and "cannot open" not in message


def test_the_profiles_lens_table_is_loaded_at_the_boards_size(tmp_path):
    """A profile's correction table goes into the board before the job, resampled to the
    board's node count, node by node (cor_node, cor_dx, cor_dy, cor_write)."""
    from galvoscan.cli.jobargs import load_lens_table
    from galvoscan.correction.files import save_table
    from galvoscan.gateware.field.correction_table import CorrectionTable
    from galvoscan.profile.machine import load_profile
    table = CorrectionTable.identity(5).with_node(2, 2, 40, -7)
    save_table(tmp_path / "lens.json", table)
    (tmp_path / "m.toml").write_text('[field]\ncorrection = "lens.json"\n')
    profile = load_profile(tmp_path / "m.toml")

    class Board:
        writes = []

        def read(self, name):
            assert name == "cor_nodes"
            return 9

        def write(self, name, value):
            self.writes.append((name, value))
    board = Board()
    said = []
    load_lens_table(board, profile, said.append)
    assert len(board.writes) == 4 * 81 and "9 x 9" in said[0]
    # Node (4, 4) of 9 sits where node (2, 2) of 5 does: the centre, with its offsets.
    centre = board.writes.index(("cor_node", 4 * 9 + 4))
    assert board.writes[centre + 1:centre + 4] == [("cor_dx", 40), ("cor_dy", 0xFFFF - 6),
                                                   ("cor_write", 1)]


@pytest.mark.parametrize("command", [
    ["mark", "DRAWING"], ["clean", "--area", "5x5"],
    ["test-grid", "--speeds", "500:1000:2", "--powers", "10:20:2"]])
@pytest.mark.parametrize("option, said", [
    (["--backend", "python"], "--backend python chooses the simulated board's simulator: it "
                              "needs --sim"),
    (["--board", "ulx3s"], "--board ulx3s chooses the simulated board's bitstream: it needs "
                           "--sim (a real board's is read off it)")])
def test_a_backend_or_board_without_sim_is_refused_before_anything(tmp_path, command, option,
                                                                    said):
    """--backend and --board pick the simulated board's simulator and bitstream: on a real
    board's job they would choose nothing, so each is one line, before any planning or
    link."""
    drawing = tmp_path / "square.svg"
    drawing.write_text(SVG)
    argv = [str(drawing) if word == "DRAWING" else word for word in command]
    with pytest.raises(SystemExit) as stop:
        main([*argv, *option, "--port", str(tmp_path / "no-such-port")])
    message = str(stop.value)
    assert message == f"galvoscan {command[0]}: error: {said}"
    assert stop.value.code == 2


def test_origin_page_keeps_the_drawings_own_coordinates(tmp_path, capsys):
    """--origin page: a DXF's 0,0 and an SVG's top-left corner land on the offset; the DXF's
    Y up, the SVG's Y down from its top edge (so its shapes lie below the offset)."""
    import ezdxf
    doc = ezdxf.new(units=4)
    doc.modelspace().add_line((10, 5), (20, 8))
    dxf = tmp_path / "part.dxf"
    doc.saveas(dxf)
    svg = tmp_path / "part.svg"
    svg.write_text('<svg xmlns="http://www.w3.org/2000/svg" width="10mm" height="10mm" '
                   'viewBox="0 0 10 10"><rect x="1" y="2" width="6" height="3" fill="none" '
                   'stroke="black"/></svg>')
    for path, offset, bounds in [(dxf, "0,0", [10, 5, 20, 8]), (dxf, "-5,1", [5, 6, 15, 9]),
                                 (svg, "0,0", [1, -5, 7, -2])]:
        assert main(["mark", str(path), "--origin", "page", f"--offset={offset}", "--estimate",
                     "--json"]) == 0
        assert json.loads(capsys.readouterr().out)["bounds_mm"] == pytest.approx(bounds)


@pytest.mark.slow
def test_cross_hatch_and_contour_marked_off_the_wires(tmp_path, capsys):
    """A 1 mm square with two hatch sets (0° and 90°, 0.25 mm) and a contour ring 0.2 mm in,
    marked on the simulated board: every mark off the wires lies on the outline, the ring, a
    horizontal or a vertical hatch line, and the lines of both sets are there."""
    path = tmp_path / "square.svg"
    path.write_text('<svg xmlns="http://www.w3.org/2000/svg" width="2mm" height="2mm" '
                    'viewBox="0 0 2 2"><rect x="0.5" y="0.5" width="1" height="1" '
                    'fill="none" stroke="black"/></svg>')
    machine = tmp_path / "machine.toml"
    machine.write_text(PROFILE)
    with quick_sim_board(**VECTOR_BOARD):
        result = run_json(["mark", str(path), "--speed", str(SPEED_MM_S), "--prr",
                           str(PRR_KHZ), "--hatch", "0.25", "--hatch", "0.25,90", "--contour",
                           "0.2,1", "--machine", str(machine), "--sim", *SIM_TIMEOUT, "--json"],
                          capsys)
    assert result["underruns"] == result["errors"] == result["rejected"] == 0
    marks = np.array(result["drawing_marks"])
    lines = 0.5 + np.array([0.125, 0.375, 0.625, 0.875])       # each set's four lines
    slack = HALF_PITCH_MM + UNIT_MM
    on_outline = np.array([distance_to_polygon(p, [(0.5, 0.5), (1.5, 0.5), (1.5, 1.5),
                                                   (0.5, 1.5)]) <= slack for p in marks])
    on_ring = np.array([distance_to_polygon(p, [(0.7, 0.7), (1.3, 0.7), (1.3, 1.3),
                                                (0.7, 1.3)]) <= slack for p in marks])
    on_row = np.min(np.abs(marks[:, 1:2] - lines), axis=1) <= 1.5 * UNIT_MM
    on_column = np.min(np.abs(marks[:, 0:1] - lines), axis=1) <= 1.5 * UNIT_MM
    assert np.all(on_outline | on_ring | on_row | on_column)
    inside = (np.abs(marks - 1.0) < 0.45).all(axis=1) & ~on_ring
    for only, axis in ((on_row & ~on_column, 1), (on_column & ~on_row, 0)):
        hit = {int(np.argmin(np.abs(v - lines))) for v in marks[inside & only, axis]}
        assert hit == {0, 1, 2, 3}, (axis, hit)         # every line of both sets
    assert np.sum(inside & on_row) > 10 and np.sum(inside & on_column) > 10
    assert np.sum(on_ring & ~on_outline) > 10


@pytest.mark.slow
def test_each_jump_is_held_as_long_as_its_length_needs_on_the_wires(tmp_path, capsys):
    """With RTC's variable jump delay, each jump is held (on the XY2-100 wires, before its
    first pulse on the DB25 pins) at least what its length needs: 50 µs and 20 µs a mm up to
    100 mm (``min_jump_delay_us`` 50, ``jump_delay_us`` 2050 at ``jump_length_limit_mm``
    100): the long jump across the field its long hold, the many short ones between dashes
    short ones, not each the longest's."""
    import json
    import numpy as np
    from sim_board import VECTOR_BOARD, quick_sim_board
    machine = tmp_path / "machine.toml"
    machine.write_text("[laser]\nspot_mm = 0.1\n[galvo]\nmin_jump_delay_us = 50\n"
                       "jump_delay_us = 2050\njump_length_limit_mm = 100\n")
    dashes = "".join(f'<path d="M {x0 + 0.6 * k:.1f} 50 h 0.3" stroke="black"/>'
                     for x0 in (5, 85) for k in range(12))
    svg = tmp_path / "dashes.svg"
    svg.write_text('<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm" '
                   f'viewBox="0 0 100 100">{dashes}</svg>')
    with quick_sim_board(**VECTOR_BOARD) as boards:
        assert main(["mark", str(svg), "--speed", "503.5", "--prr", "50", "--machine",
                     str(machine), "--sim", "--timeout", "600", "--json"]) == 0
        board = boards.built[-1]
        points = board.points()
    out = capsys.readouterr()
    assert "each jump held as long as its length needs" in out.err
    units_per_mm = 65536 / 110
    held, last = [], None
    for x, y, pulses, frames, cycle, first_pulse in points:
        # A marked point 0.1 mm or more from the last marked one: a jump ended there.
        if pulses and last is not None and \
                np.hypot(x - last[0], y - last[1]) / units_per_mm >= 0.1:
            length = np.hypot(x - last[0], y - last[1]) / units_per_mm
            held.append((length, (first_pulse - cycle) / board.clk_freq * 1e6))
        if pulses:
            last = (x, y)
    assert len(held) >= 20
    for length, hold_us in held:
        assert hold_us >= 50 + 20 * length - 10, (length, hold_us)
    long_ones = [h for length, h in held if length > 50]
    short_ones = [h for length, h in held if length < 1]
    assert long_ones and short_ones and max(short_ones) < 200 < min(long_ones)
    assert json.loads(out.out.strip().splitlines()[-1])["errors"] == 0


# --- a photo through the link ----------------------------------------------------------------

# A machine with quick mirrors (the bench's: 100 µs after a jump, 50 µs after a mark): a
# photo's thousands of short marks and gaps then ask more segments a second of the link than
# 1 Mbaud carries.
QUICK_MIRRORS = "[galvo]\n" + "".join(f"{key} = {value}\n"
                                      for key, value in PHOTO_GALVO.items())


@pytest.mark.slow
@pytest.mark.parametrize("board", ["icebreaker", "ulx3s"])
def test_a_photo_streams_with_no_underrun_where_the_link_keeps_up(tmp_path, capsys, board):
    """A strip of that photo (4,680 segments, nine times the queue) marked through the link,
    on quick mirrors: the iCEBreaker's 1 Mbaud falls behind, as mark warns before any byte
    (its count an upper bound: it leaves the mark delays out); the ULX3S's 3 Mbaud keeps the
    queue from running dry, every mark to its end."""
    machine = tmp_path / "machine.toml"
    machine.write_text(QUICK_MIRRORS)
    strip = shaded_picture(tmp_path / "strip.png", 16)
    argv = ["mark", "--image", str(strip), "--width", "24", "--speed", "1000", "--machine",
            str(machine), "--image-lines", "runs", "--sim", "--board", board, *SIM_TIMEOUT,
            "--json"]
    if board == "ulx3s":
        result = run_json(argv, capsys)
        assert "underruns" not in capsys.readouterr().err
        assert result["segments"] == 4681
        assert result["underruns"] == result["errors"] == result["rejected"] == 0
        return
    with pytest.raises(SystemExit) as stop:
        main(argv)
    assert "the job was not marked as planned" in str(stop.value) and stop.value.code == 1
    err = capsys.readouterr().err
    foretold = int(re.search(r"expect about ([\d,]+) underruns", err)[1].replace(",", ""))
    happened = int(re.search(r"underruns (\d+),", err)[1])
    assert 0 < happened <= foretold <= 1.2 * happened, err


# --- a photo as pixel lines ---------------------------------------------------------------------

def test_a_photos_pixel_lines_light_its_dithered_cells_on_the_wires(tmp_path, capsys):
    """A photo marked as pixel lines (the default) on the simulated board (the engraver's
    bitstream, which has them): the points lit on the wires are exactly the dithered grid's
    dark cells, each row shifted as one by the scan offset, the other way on the next row;
    every dark cell gets the same pulses; far fewer link words than runs. (Amaranth's
    simulator steps the same pixel words point by point in
    tests/gateware/sources/test_pixel_lines.py: a photo takes it minutes.)"""
    from galvoscan.inputs.photo import PhotoSpec, photo_bitmap
    width = 3.0
    picture = shaded_picture(tmp_path / "photo.png", 60, 80)
    argv = ["mark", "--image", str(picture), "--width", str(width), "--speed", "800", "--sim",
            *SIM_TIMEOUT, "--json"]
    result = run_json(argv, capsys)
    units_per_mm = 65536 / 110
    cell = round(0.05 * units_per_mm) / units_per_mm
    dark = photo_bitmap(PhotoSpec(str(picture), width, cell))
    assert dark.sum() > 5
    rows, columns = dark.shape
    lit = [(round(x * units_per_mm + 32768), round(y * units_per_mm + 32768))
           for x, y in result["marks"]]
    assert len(lit) == len(set(lit)) == dark.sum()
    assert result["pulses"] == dark.sum() * result["pulses_per_point"]
    assert result["underruns"] == result["errors"] == result["rejected"] == 0
    shifts = []
    for r in range(rows):
        y = round((rows * cell / 2 - (r + 0.5) * cell) * units_per_mm + 32768)
        xs = sorted(x for x, yy in lit if yy == y)
        centres = [round((-columns * cell / 2 + (c + 0.5) * cell) * units_per_mm + 32768)
                   for c in np.flatnonzero(dark[r])]
        assert len(xs) == len(centres), r
        if centres:
            row_shift = {x - c for x, c in zip(xs, centres)}
            assert len(row_shift) == 1, (r, row_shift)
            shifts.append(row_shift.pop())
    # The mirrors' 80 µs lag at the line's speed (a cell a PRR period at 50 kHz, over the
    # pulses a cell), ahead in each row's own direction.
    speed = cell * 50e3 / result["pulses_per_point"]
    assert result["speed_mm_s"] == pytest.approx(speed, rel=0.01)
    offset = round(speed * 80e-6 * units_per_mm)
    assert shifts == [offset * (-1) ** n for n in range(len(shifts))]
    runs = run_json(["mark", "--image", str(picture), "--width", str(width), "--speed", "800",
                     "--image-lines", "runs", "--estimate", "--json"], capsys)
    assert result["segments"] * 5 < runs["segments"]


def test_a_photos_pixel_lines_are_refused_by_a_bitstream_without_them(tmp_path, capsys):
    """The ULX3S's bitstream has them; a board without them (here the default iCEBreaker's,
    by its caps) refuses before anything is sent, in one line that says what to do."""
    from galvoscan.outputs.stream import JobAborted, JobStreamer
    from galvoscan.api import Job, Photo, plan
    from galvoscan.gateware.top import ScanSettings
    from galvoscan.link.client import HostClient
    from sim_board import SimBoard, SimSPITransport
    picture = shaded_picture(tmp_path / "photo.png", 20, 20)
    planned = plan(Job(photos=(Photo(str(picture), 1.0),)))
    board = SimBoard(settings=ScanSettings(mode="vector", run=False))
    client = HostClient(SimSPITransport(board, clocks_per_sck=12))
    streamer = JobStreamer(client)
    with pytest.raises(JobAborted, match="no pixel lines .* --image-lines runs; nothing was "
                                         "sent"):
        streamer.run_vector(planned.segments, planned.vector_job.registers)
    assert client.read("fifo_free") == client.read("vec_depth")
    assert client.read("link_seq") == 0
