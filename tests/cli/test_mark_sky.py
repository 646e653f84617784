"""`galvoscan mark --sky`: SkyWriting from the command line, on the simulated board's pins.

An L and a square (SVGs written here) are marked by `mark --sim` (the engraver's bitstream,
which has pixel lines) with SkyWriting. The frames are read off the XY2-100 wires and the
laser's modulation (DB25 pin 19, ``laser_am``) off the DB25 pins. Where the drawing's corners
are comes from the SVG and the field (not from the plan); when the laser must switch comes from
RTC's definition, as the register map words it: on Timelag + LaserOnShift after the set point
reaches a mark's first point, off Timelag after it leaves its last, to the clock (the
modulation follows a frame coming in force a clock later, as tests/support/
vector_delay_model.py has it). The run-in before each mark and the run-out after it are on the
wires, laser off while the set point is in the run-in. Bad SkyWriting values are one line,
before anything is sent; a bitstream without pixel lines refuses the job, nothing sent."""

import json

from hypothesis import HealthCheck, given, settings as hypothesis_settings, strategies as st
import pytest

from galvoscan.cli import main
from galvoscan.sim.contract import LASER_PINS


FIELD_MM = 110.0
UNITS_PER_MM = 65536 / FIELD_MM
AM = LASER_PINS.index("laser_am")
PROFILE = "[galvo]\njump_delay_us = 100\n"
# An L, 2 mm each way: its set points in the SVG (y down), placed with its bounding box's
# centre at the field's centre.
L_SVG = ('<svg xmlns="http://www.w3.org/2000/svg" width="4mm" height="4mm" viewBox="0 0 4 4">'
         '<polyline points="1,1 3,1 3,3" fill="none" stroke="black"/></svg>')
SQUARE_SVG = ('<svg xmlns="http://www.w3.org/2000/svg" width="4mm" height="4mm" '
              'viewBox="0 0 4 4"><rect x="1" y="1" width="2" height="2" fill="none" '
              'stroke="black"/></svg>')
NOPORT = ["--port", "/nonexistent/ttyUSB9"]


def galvo(x_mm, y_mm):
    """A field point (mm, y up) in galvo units."""
    return (x_mm * UNITS_PER_MM + 32768, y_mm * UNITS_PER_MM + 32768)


# The L's points, field mm: SVG (1,1) → (-1, +1), (3,1) → (+1, +1), (3,3) → (+1, -1).
L_POINTS = [galvo(-1, 1), galvo(1, 1), galvo(1, -1)]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("sky")
    (folder / "l.svg").write_text(L_SVG)
    (folder / "square.svg").write_text(SQUARE_SVG)
    (folder / "machine.toml").write_text(PROFILE)
    return folder


@pytest.fixture
def boards(monkeypatch):
    """Every simulated board `mark --sim` builds, as it is built."""
    import galvoscan.sim.board as module
    built = []

    class Recorded(module.SimulatedBoard):
        def __init__(self, **kwargs):
            super().__init__(**kwargs)
            built.append(self)

    monkeypatch.setattr(module, "SimulatedBoard", Recorded)
    return built


def mark(files, drawing, *more):
    return ["mark", str(files / drawing), "--machine", str(files / "machine.toml"), *more]


def near(frame_xy, point, units=1.0):
    return abs(frame_xy[0] - point[0]) <= units and abs(frame_xy[1] - point[1]) <= units


def wires(board):
    """``(positions, in_force, edges)``: each frame's (x, y), the clock it comes in force on
    (the SYNC rise that starts the next frame), and the modulation's edges ``(clock,
    level)``."""
    positions = [(x, y) for _, x, y in board.frames]
    in_force = board.sync_rises[1:len(positions) + 1]
    edges, level = [], 0
    for clock, pins in board.laser_changes:
        if pins[AM] != level:
            level = pins[AM]
            edges.append((clock, level))
    return positions[:len(in_force)], in_force, edges


def run(files, capsys, drawing, *options):
    assert main(mark(files, drawing, "--sim", "--json", *options)) == 0
    return json.loads(capsys.readouterr().out.strip().splitlines()[-1])


def test_mode_1_switches_the_laser_timelag_after_the_set_point_crosses_the_ends(
        files, capsys, boards):
    timelag, shift = 200, 30
    result = run(files, capsys, "l.svg", "--sky", "1", "--timelag", str(timelag),
                 "--laser-on-shift", str(shift))
    board, = boards
    clocks_per_us = board.clk_freq / 1e6
    positions, in_force, edges = wires(board)
    # The planner may take the L from either end: the one the set point reaches first.
    first = next(k for k, p in enumerate(positions)
                 if near(p, L_POINTS[0]) or near(p, L_POINTS[2]))
    start, corner, end = L_POINTS if near(positions[first], L_POINTS[0]) else L_POINTS[::-1]
    # The set point reaches the L's start (its first frame there) and leaves its end (the
    # first frame after its last one there).
    last = max(k for k, p in enumerate(positions) if near(p, end))
    assert any(near(p, corner) for p in positions[first:last])
    rise = in_force[first] + 1 + (timelag + shift) * clocks_per_us
    fall = in_force[last + 1] + 1 + timelag * clocks_per_us
    assert edges == [(rise, 1), (fall, 0)]
    # The run-in: the set point comes along the L's first line from behind its start (Nprev,
    # 0.15 × Timelag: 30 µs, whole points at the mark's speed), laser off all the while.
    dwell_us = result["pulses_per_point"] / 50e3 * 1e6
    jump_end = 1 + max(k for k in range(first) if not behind(positions[k], start, corner))
    run_in = list(dict.fromkeys(positions[jump_end:first]))
    assert len(run_in) == 1 + -(-30 // dwell_us)         # the jump's end, then Nprev's points
    assert all(behind(p, start, corner) for p in run_in), run_in
    # The run-out: on along the L's last line, past its end (Npost: 20 µs).
    after = list(dict.fromkeys(positions[last + 1:]))
    run_out = [p for p in after if behind(p, end, corner)]
    assert len(run_out) == -(-20 // dwell_us)
    assert not any(in_force[jump_end] < clock < rise for clock in board.pulses)


def behind(p, at, towards):
    """Whether ``p`` lies on the line through ``at`` and ``towards`` (within a unit and a
    half), beyond ``at`` seen from ``towards``."""
    d = (towards[0] - at[0], towards[1] - at[1])
    length = (d[0] ** 2 + d[1] ** 2) ** 0.5
    v = (p[0] - at[0], p[1] - at[1])
    across = abs(v[0] * d[1] - v[1] * d[0]) / length
    along = (v[0] * d[0] + v[1] * d[1]) / length
    return across <= 1.5 and along < -0.5


def test_mode_2_marks_each_side_of_a_square_up_to_its_corners(files, capsys, boards):
    timelag = 120
    run(files, capsys, "square.svg", "--sky", "2", "--timelag", str(timelag))
    board, = boards
    clocks_per_us = board.clk_freq / 1e6
    positions, in_force, edges = wires(board)
    # Four marks, each lit from the set point at one corner to the set point at the next,
    # each edge Timelag after the set point's, to the clock.
    assert [level for _, level in edges] == [1, 0] * 4
    corners = [galvo(-1, 1), galvo(-1, -1), galvo(1, -1), galvo(1, 1)]
    lit = []
    for (rise, _), (fall, _) in zip(edges[::2], edges[1::2]):
        k0 = next(k for k, clock in enumerate(in_force)
                  if clock + 1 + timelag * clocks_per_us == rise)
        k1 = next(k for k, clock in enumerate(in_force)
                  if clock + 1 + timelag * clocks_per_us == fall) - 1
        lit.append((positions[k0], positions[k1]))
    def corner_of(point, units=1.0):
        found = [k for k, c in enumerate(corners) if near(point, c, units)]
        assert len(found) == 1, point
        return found[0]
    # A side ends on its corner; the next starts a pitch (at most 30 µm) past it, the corner
    # lit once, by the side that ends there (the first side, after a jump, on its corner).
    pitch_units = 0.03 * UNITS_PER_MM
    sides = [(corner_of(first, pitch_units), corner_of(last)) for first, last in lit]
    assert near(lit[0][0], corners[sides[0][0]])
    # Each side from a corner to the one next to it, every corner a side's start once.
    assert sorted(a for a, _ in sides) == [0, 1, 2, 3]
    assert all((b - a) % 4 in (1, 3) for a, b in sides), sides
    # Between two sides the set point runs out, jumps and runs in, dark: every pulse falls
    # while the mirror (Timelag behind the set point) and the set point are on one side's line,
    # never while the mirror jumps to the next.
    import bisect
    lines = [(0, corners[0][0]), (0, corners[2][0]), (1, corners[1][1]), (1, corners[0][1])]

    def set_point(clock):
        return positions[bisect.bisect_right(in_force, clock) - 1]
    for clock in board.pulses:
        now, then = set_point(clock), set_point(clock - timelag * clocks_per_us)
        assert any(abs(now[axis] - at) <= 1 and abs(then[axis] - at) <= 1
                   for axis, at in lines), (clock, now, then)


def test_estimate_says_the_time_skywriting_adds(files, capsys):
    assert main(mark(files, "square.svg", "--estimate", "--json")) == 0
    plain = json.loads(capsys.readouterr().out)
    assert main(mark(files, "square.svg", "--sky", "2", "--timelag", "100", "--estimate",
                     "--json")) == 0
    sky = json.loads(capsys.readouterr().out)
    assert plain["sky_s"] == 0 and sky["sky_s"] > 0
    assert sky["estimate_s"] == pytest.approx(plain["estimate_s"] + sky["sky_s"], abs=2e-6)
    assert any(note.startswith("SkyWriting mode 2") and "3 corners taken apart" in note
               for note in sky["notes"])
    assert (sky["laser_on_delay_us"], sky["laser_off_delay_us"], sky["polygon_delay_us"]) == \
        (100, 100, 0)


def test_a_layer_and_a_job_file_carry_skywriting(files, capsys, tmp_path):
    saved = tmp_path / "job.toml"
    assert main(mark(files, "square.svg", "--sky", "1", "--timelag", "150", "--save",
                     str(saved), "--estimate")) == 0
    capsys.readouterr()
    text = saved.read_text()
    assert "sky = 1" in text and "timelag = 150" in text
    assert main(["mark", str(saved), "--machine", str(files / "machine.toml"), "--estimate",
                 "--json"]) == 0
    again = json.loads(capsys.readouterr().out)
    assert again["laser_off_delay_us"] == 150 and again["sky_s"] > 0
    # A layer's own: SkyWriting on for the black paths only, at its own Timelag.
    assert main(mark(files, "square.svg", "--layer", "#000000", "sky=2", "timelag=90",
                     "--estimate", "--json")) == 0
    layered = json.loads(capsys.readouterr().out)
    layer, = layered["layers"]
    assert layer["laser_on_delay_us"] == 90 and layer["sky_s"] > 0
    assert "sky 2, timelag 90 µs" in layer["sets"]


@pytest.mark.parametrize("options, said", [
    (["--sky", "4"], "--sky must be from 0 to 3, not 4"),
    (["--sky", "one"], "--sky must be an integer, not 'one'"),
    (["--sky", "1", "--timelag", "-1"], "timelag must be from 0 to 1023"),
    (["--sky", "1", "--timelag", "20", "--laser-on-shift", "-50"],
     "Timelag 20 µs + laser-on shift -50 µs is -30 µs"),
    (["--sky", "1", "--nprev", "nan"], "nprev must be from 0 to 10000, not nan"),
    (["--sky", "3", "--sky-limit", "2"], "sky limit must be from -1 to 1"),
])
def test_bad_sky_options_are_one_line_before_anything(files, capsys, boards, options, said):
    with pytest.raises(SystemExit) as stop:
        main(mark(files, "square.svg", *options, *NOPORT))
    assert stop.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert said in err[-1] and "ttyUSB9" not in err[-1], err
    assert not boards


@hypothesis_settings(max_examples=25, deadline=None,
                     suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(option=st.sampled_from(["--sky", "--timelag", "--laser-on-shift", "--nprev", "--npost",
                               "--sky-limit"]),
       value=st.one_of(st.text(min_size=1, max_size=6).filter(lambda t: not t.startswith("-")),
                       st.floats(-1e5, 1e5).map(repr), st.integers(-5000, 5000).map(str)))
def test_any_sky_value_is_planned_or_refused_in_one_line(files, capsys, option, value):
    """Random values: a plan (with --estimate) or one line with exit status 2, never a
    traceback and never the link."""
    try:
        code = main(mark(files, "square.svg", "--sky", "1", f"{option}={value}", "--estimate",
                         *NOPORT))
    except SystemExit as stop:
        code = stop.code
        err = capsys.readouterr().err.strip().splitlines()
        assert code == 2 and err and "Traceback" not in "\n".join(err), err
        assert "ttyUSB9" not in err[-1]
        return
    capsys.readouterr()
    assert code == 0


def test_a_bitstream_without_pixel_lines_refuses_skywriting_before_any_write(tmp_path):
    from galvoscan.api import Drawing, Job, plan
    from galvoscan.gateware.top import ScanSettings
    from galvoscan.link.client import HostClient
    from galvoscan.outputs.stream import JobAborted, JobStreamer
    from sim_board import SimBoard, SimSPITransport
    (tmp_path / "square.svg").write_text(SQUARE_SVG)
    planned = plan(Job(drawings=(Drawing(str(tmp_path / "square.svg")),), sky_mode=1))
    board = SimBoard(settings=ScanSettings(mode="vector", run=False))
    client = HostClient(SimSPITransport(board, clocks_per_sck=12))
    with pytest.raises(JobAborted, match="no pixel lines, which SkyWriting's run-ins and "
                                         r"run-outs are .* \(--sky 0\); nothing was sent"):
        JobStreamer(client).run_vector(planned.segments, planned.vector_job.registers)
    assert client.read("link_seq") == 0


def test_store_refuses_skywriting_in_one_line(files, capsys, tmp_path):
    """The stand-alone player takes no pixel lines: one line, no image written."""
    image = tmp_path / "job.img"
    with pytest.raises(SystemExit) as stop:
        main(["store", str(files / "square.svg"), "--machine", str(files / "machine.toml"),
              "--sky", "1", "-o", str(image)])
    assert stop.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert "does not take SkyWriting's run-ins and run-outs" in err[-1], err
    assert not image.exists()


@pytest.mark.parametrize("table, said", [
    ("[job]\nsky = 9\n", "sky"),
    ("[job]\nsky = 1\ntimelag = \"long\"\n", "timelag"),
    ("[job]\nsky = 1\nnpost = -3\n", "npost"),
    ("[[layer]]\nmatch = \"#000000\"\nsky_limit = 4\n", "sky_limit"),
])
def test_a_job_files_bad_sky_key_is_one_line(files, capsys, boards, tmp_path, table, said):
    job = tmp_path / "job.toml"
    job.write_text(table + f"[[drawing]]\nfile = \"{files / 'square.svg'}\"\n")
    with pytest.raises(SystemExit) as stop:
        main(["mark", str(job), "--machine", str(files / "machine.toml"), *NOPORT])
    assert stop.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert said in err[-1] and "ttyUSB9" not in err[-1], err
    assert not boards


@hypothesis_settings(max_examples=30, deadline=None,
                     suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(key=st.sampled_from(["mode", "timelag_us", "laser_on_shift_us", "nprev_us", "npost_us",
                            "limit"]),
       value=st.one_of(st.integers(-3000, 3000), st.floats(-1e4, 1e4, allow_nan=False),
                       st.booleans(), st.text(alphabet="ab0.-e ", max_size=4)))
def test_any_profile_sky_value_is_taken_or_refused_in_one_line(tmp_path_factory, key, value):
    from galvoscan.profile.machine import ProfileError, parse_profile
    text = f"[sky]\nmode = 1\n{key} = {json.dumps(value)}\n" if key != "mode" else \
        f"[sky]\nmode = {json.dumps(value)}\n"
    try:
        profile = parse_profile(text)
    except ProfileError as error:
        assert "\n" not in str(error) and "[sky]" in str(error)
        return
    # Taken: a job plans with it (or says in one line why its Timelag cannot be).
    from galvoscan.plan.sky import job_sky
    sky = job_sky(profile)
    assert sky.mode in (0, 1, 2, 3)
    if sky.mode:
        assert 0 <= sky.laser_on_delay <= 1023


@pytest.mark.parametrize("limit, pieces", [(0.5, 2), (-0.9, 1), (0.9, 3)])
def test_mode_3_takes_apart_only_the_corners_sharper_than_its_limit(files, capsys, boards,
                                                                      tmp_path, limit, pieces):
    """A polyline turning 30° and then 120° (cos 0.87 and -0.5): at limit 0.5 the laser
    switches off and on again at the 120° corner only, on the wires; at -0.9 at neither, at
    0.9 at both."""
    import math
    points = [(0.0, 0.0), (2.0, 0.0)]
    heading = 0.0
    for turn in (30, 120):
        heading += math.radians(turn)
        x, y = points[-1]
        points.append((x + 2 * math.cos(heading), y + 2 * math.sin(heading)))
    svg = tmp_path / "turns.svg"
    svg.write_text('<svg xmlns="http://www.w3.org/2000/svg" width="10mm" height="10mm" '
                   'viewBox="-5 -5 10 10"><polyline points="' +
                   " ".join(f"{x:.4f},{y:.4f}" for x, y in points) +
                   '" fill="none" stroke="black"/></svg>')
    assert main(["mark", str(svg), "--machine", str(files / "machine.toml"), "--sky", "3",
                 "--sky-limit", str(limit), "--timelag", "100", "--sim", "--json"]) == 0
    capsys.readouterr()
    board, = boards
    _, _, edges = wires(board)
    assert [level for _, level in edges] == [1, 0] * pieces
