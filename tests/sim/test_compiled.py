"""The compiled backend of the simulated board (galvoscan.sim.compiled) against the reference,
Amaranth's simulator: the same stimulus through both gives the same records to the clock
(frames off the XY2-100 wires, SYNC rises, laser pulses and pin changes, UART bytes both
ways, framing errors). The full spiral, too long for the reference, is checked on the
compiled board against the tests' own model of the pattern. And the ways a compile can fail.
"""

import contextlib
import io
import json
import math

import pytest
from hypothesis import HealthCheck, example, given, settings, strategies as st

from galvoscan.cli import main
from galvoscan.link.client import HostClient, encode_read, encode_write
from galvoscan.sim.compiled import CompileError, Compiler, compiled_model, find_compiler
from galvoscan.sim.compiled import model as model_module
from galvoscan.gateware.host.regmap import Mode
from galvoscan.gateware.top import GalvoScanTop, ScanSettings
from galvoscan.sim.board import SimSPITransport, SimTransport, SimulatedBoard
from galvoscan.sim.spiral import replay_spiral
from galvoscan.gateware.sources.spiral_table import SpiralTable

from link_codec import cobs_encode
from player_board import JOB as PLAYER_JOB, PLAYER_BOARD, REGISTERS
from sim_board import QUICK_SIM_BOARD, VECTOR_BOARD, quick_sim_board
from ulx3s_board import ulx3s_board
from galvoscan.gateware.sources.spiral import PARK_FRAMES
from spiral_model import spiral_frames


RECORDS = ("frames", "sync_rises", "pulses", "laser_changes", "bytes_in", "framing_errors")


def records(board):
    return {name: getattr(board, name) for name in RECORDS} | {
        "from_board": list(board.from_board), "now": board.now}


def assert_same_records(compiled, python):
    a, b = records(compiled), records(python)
    for name in a:
        assert a[name] == b[name], f"{name} differ"


def both(**kwargs):
    return (SimulatedBoard(backend="compiled", **kwargs),
            SimulatedBoard(backend="python", **kwargs))


def session(board):
    """A host's session over the UART: registers written and read back, the interlock opened
    and closed while armed, the alarms raised, the faults cleared, a few vector segments."""
    client = HostClient(SimTransport(board))
    for name, value in (("laser_prr", 500), ("pulses_per_point", 2), ("laser_power", 77),
                        ("watchdog", 2000), ("mode", Mode.VECTOR.value)):
        client.write(name, value)
    readings = [client.read(name) for name in ("laser_prr", "laser_power", "status", "errors")]
    client.write("arm", 1)
    board.run_for(0.6e-3)                   # past the MO lead
    board.interlock_closed = False
    board.run_for(30e-6)
    board.interlock_closed = True
    readings.append(client.read("status"))
    client.write("fault_clear", 1)
    board.alarms_clear = False
    board.run_for(30e-6)
    board.alarms_clear = True
    readings.append(client.read("status"))
    board.to_board.extend(b"\x00\xff\x13")  # bytes that are no frame
    board.run_for(200e-6)
    readings.append(client.read("errors"))
    return readings


@pytest.mark.slow
def test_a_uart_session_gives_the_same_records():
    compiled, python = both(**QUICK_SIM_BOARD)
    assert compiled.backend == "compiled" and python.backend == "python"
    assert session(compiled) == session(python)
    assert_same_records(compiled, python)
    assert compiled.laser_changes[1:], "the session moved no laser pin"
    assert compiled.bytes_in and compiled.from_board == python.from_board


@st.composite
def writes(draw):
    from galvoscan.gateware.host.regmap import BY_NAME
    name = draw(st.sampled_from(["laser_prr", "dwell", "arm", "mode", "laser_power", "guide"]))
    register = BY_NAME[name]
    # (Sequence numbers near the board's first: some are taken, some refused out of step.)
    return encode_write(name, draw(st.integers(register.low, register.high)),
                        seq=draw(st.integers(0, 3)))


FRAMES = st.lists(st.one_of(
    writes(),
    st.builds(encode_read, st.sampled_from(["status", "errors", "laser_prr"])),
    st.binary(min_size=1, max_size=12)), min_size=1, max_size=6)


@pytest.mark.slow
@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(FRAMES, st.lists(st.tuples(st.booleans(), st.booleans()), min_size=1, max_size=3),
       st.integers(0, 50))
def test_random_byte_streams_with_the_machine_toggling(frames, machine, gap_us):
    compiled, python = both(**QUICK_SIM_BOARD, **VECTOR_BOARD)
    for board in (compiled, python):
        for k, frame in enumerate(frames):
            # A frame as the serial line carries it (random bytes as they are).
            if len(frame) == 10:
                frame = cobs_encode(frame) + b"\0"
            board.to_board.extend(frame)
            interlock, alarms = machine[k % len(machine)]
            board.interlock_closed, board.alarms_clear = interlock, alarms
            board.run_for(len(frame) * 10e-6 + gap_us * 1e-6 + 7e-6)
        board.run_for(100e-6)
    assert_same_records(compiled, python)


JOB = [("jump", 32000, 32000), ("mark", 32400, 32000), ("mark", 32400, 32250),
       ("mark", 32000, 32000), ("jump", 33000, 31000), ("mark", 32800, 31300)]
JOB_REGISTERS = {"pitch": 40, "pulses_per_point": 2, "laser_prr": 500, "jump_delay": 30,
                 "laser_power": 90, "laser_on_delay": 20, "laser_off_delay": 30,
                 "mark_delay": 40, "polygon_delay": 25, "polygon_scaled": 1,
                 "wob_shape": 1, "wob_along": 12, "wob_across": 20, "wob_freq": 3000}


#: The boards of the job tests: the vector build with the delays and wobble, and the ULX3S
#: bitstream (every feature).
JOB_BOARDS = {"vector": lambda: dict(**QUICK_SIM_BOARD, **VECTOR_BOARD, vector_delays=True,
                                     wobble=True),
              "ulx3s": lambda: ulx3s_board(mo_lead=QUICK_SIM_BOARD["mo_lead"])}


@pytest.mark.slow
@pytest.mark.parametrize("build", JOB_BOARDS)
def test_a_vector_job_with_delays_and_wobble_is_the_same_on_both_backends(build):
    """The job streamer (the host client's, as ``mark`` runs it) with a host that answers in
    the board's own time: the same frames, pulses and pins to the clock."""
    from galvoscan.outputs.stream import JobStreamer
    compiled, python = both(**JOB_BOARDS[build]())
    reports = []
    for board in (compiled, python):
        client = HostClient(SimTransport(board))
        report = JobStreamer(client, poll_s=0).run_vector(JOB, JOB_REGISTERS, timeout_s=1e9)
        reports.append((report.segments, report.pulses, report.counters))
        board.run_for(100e-6)
    assert reports[0] == reports[1]
    assert compiled.pulses and len({(x, y) for _, x, y in compiled.frames}) > 20
    assert_same_records(compiled, python)


@pytest.mark.slow
@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(FRAMES, st.lists(st.tuples(st.booleans(), st.booleans()), min_size=1, max_size=3))
# Found by hypothesis: an alarm disarms the laser, and on Amaranth's simulator laser_prr fell
# one delta before laser_enable and laser_mo at that clock (a state the settled pins never
# have), which the reference once recorded as a change of its own.
@example(frames=[encode_read("status"), encode_write("arm", 1, seq=0),
                 encode_write("mode", 1, seq=1), encode_read("status"), b"\x8a\rA\xe0",
                 encode_write("mode", 0, seq=2)],
         machine=[(True, False), (True, True)])
def test_random_spi_frames_with_the_machine_toggling(frames, machine):
    """Frames of any kind, cut or not, clocked into the SPI target, the answers clocked out."""
    compiled, python = both(**QUICK_SIM_BOARD, **VECTOR_BOARD)
    answers = []
    for board in (compiled, python):
        link = SimSPITransport(board)
        got = []
        for k, frame in enumerate(frames):
            interlock, alarms = machine[k % len(machine)]
            board.interlock_closed, board.alarms_clear = interlock, alarms
            got.append(link.transfer(frame))
        board.run_for(50e-6)
        answers.append(got)
    assert answers[0] == answers[1]
    assert_same_records(compiled, python)


@pytest.mark.slow
def test_a_job_stopped_by_ctrl_c_is_the_same_on_both_backends():
    """Ctrl-C while the streamer feeds the queue: it disarms, and both boards stop alike."""
    from galvoscan.outputs.stream import JobStreamer
    from galvoscan.sim.board import LASER_PINS
    job = [("jump", 30000, 30000)] + [("mark", 30000 + 300 * (k % 2), 30000 + 40 * k)
                                      for k in range(40)]
    # (A queue of four, the link fault tests' build: the streamer waits on it, so the laser
    # is marking by the twentieth segment, when Ctrl-C comes.)
    compiled, python = both(**QUICK_SIM_BOARD, **VECTOR_BOARD, vector_queue_depth=4)
    for board in (compiled, python):
        sent = [0]

        def interrupt(count):
            sent[0] += count
            if sent[0] >= 20:
                raise KeyboardInterrupt
        streamer = JobStreamer(HostClient(SimTransport(board)), poll_s=0, progress=interrupt)
        with pytest.raises(KeyboardInterrupt):
            streamer.run_vector(job, {"pitch": 60, "laser_prr": 500, "laser_power": 50,
                                      "jump_delay": 10}, timeout_s=1e9)
        board.run_for(200e-6)
    assert_same_records(compiled, python)
    assert compiled.pulses, "the job had started marking"
    last = compiled.laser_changes[-1][1]
    assert not last[LASER_PINS.index("laser_enable")] and not last[LASER_PINS.index("laser_mo")]


SQUARE = """<svg xmlns="http://www.w3.org/2000/svg" width="10mm" height="10mm" viewBox="0 0 10 10">
<rect x="4" y="4" width="0.6" height="0.4" fill="none" stroke="black"/></svg>"""


def mark_json(folder, backend):
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()), \
            quick_sim_board(**VECTOR_BOARD) as board_class:
        assert main(["mark", str(folder / "square.svg"), "--sim", "--backend", backend,
                     "--json", "--speed", "500"]) == 0
    [board] = board_class.built
    assert board.backend == backend
    return json.loads(out.getvalue().strip().splitlines()[-1])


@pytest.mark.slow
def test_mark_on_the_simulated_board_marks_the_same_on_both_backends(tmp_path):
    """``mark --sim --json`` through the pseudo-terminal: the host's timing is its own clock's
    here, so the backends may differ in when things happen, never in what is marked."""
    (tmp_path / "square.svg").write_text(SQUARE)
    compiled, python = mark_json(tmp_path, "compiled"), mark_json(tmp_path, "python")
    assert compiled["pulses"] > 0
    for name in ("marks", "pulses", "segments", "errors", "rejected", "underruns"):
        assert compiled[name] == python[name], name
    assert compiled["speed_mm_s"] == pytest.approx(python["speed_mm_s"], rel=1e-3)


def expected_spiral(settings, points):
    table = SpiralTable()
    return spiral_frames(table.x, table.y, points, dwell=settings.dwell,
                         interp=settings.spiral_interp, x_range=settings.x_range,
                         y_range=settings.y_range, gain=(settings.amp_x, settings.amp_y),
                         centre=(settings.center_x, settings.center_y))


@pytest.mark.parametrize("interp", [0, 1])
def test_the_whole_spiral_off_the_default_builds_wires(interp):
    """All lcm(128, 126) = 8064 points of the precessing spiral, held and interpolated, off
    the XY2-100 wires of the default build (every mode, the correction stage) on the
    compiled board, equal the tests' model frame for frame."""
    settings = ScanSettings(spiral_interp=interp)
    points = math.lcm(128, 126)
    total = PARK_FRAMES + points * settings.dwell
    frames = replay_spiral(frames=total, settings=settings, backend="compiled")
    got = [(f.x, f.y) for f in frames]
    assert got == expected_spiral(settings, points)


@pytest.mark.slow
@pytest.mark.parametrize("interp", [0, 1])
def test_the_spiral_is_the_same_on_both_backends(interp):
    settings = ScanSettings(spiral_interp=interp)
    total = PARK_FRAMES + 60 * settings.dwell
    assert (replay_spiral(frames=total, settings=settings, backend="compiled") ==
            replay_spiral(frames=total, settings=settings, backend="python"))


@pytest.mark.slow
def test_raster_is_the_same_on_both_backends():
    """The default build (the link tests' quick model), switched to raster over SPI."""
    compiled, python = both(**QUICK_SIM_BOARD)
    for board in (compiled, python):
        client = HostClient(SimSPITransport(board))
        for name, value in (("run", 0), ("mode", Mode.RASTER.value), ("ras_w", 40),
                            ("ras_h", 30), ("ras_spacing", 10), ("ras_step", 10), ("run", 1)):
            client.write(name, value)
        board.run_for(1.5e-3)
    assert len({(x, y) for _, x, y in compiled.frames}) > 3
    assert_same_records(compiled, python)


@pytest.mark.slow
def test_correction_table_writes_are_the_same_on_both_backends():
    compiled, python = both(**QUICK_SIM_BOARD)
    for board in (compiled, python):
        client = HostClient(SimTransport(board))
        for node in (0, 5, 12):
            for name, value in (("cor_node", node), ("cor_dx", (40 * node - 200) & 0xFFFF),
                                ("cor_dy", (7 - node) & 0xFFFF), ("cor_write", 1)):
                client.write(name, value)
        client.write("cor_enable", 1)
        client.write("mode", 0)
        board.run_for(0.5e-3)
    assert_same_records(compiled, python)


# --- when it cannot be had ---------------------------------------------------------------------

def test_a_failing_compile_falls_back_to_python_with_one_line(monkeypatch, tmp_path):
    monkeypatch.setenv("GALVOSCAN_CACHE_DIR", str(tmp_path))
    broken = Compiler(("false",), "a compiler that fails")
    monkeypatch.setattr("galvoscan.sim.compiled.model.find_compiler", lambda: broken)
    said = []
    board = SimulatedBoard(backend="auto", say=said.append, **QUICK_SIM_BOARD,
                           **VECTOR_BOARD)
    assert board.backend == "python"
    assert len(said) >= 1 and "not available" in said[-1] and "false" in said[-1]
    with pytest.raises(CompileError, match="the C\\+\\+ compiler .*failed"):
        SimulatedBoard(backend="compiled", **QUICK_SIM_BOARD, **VECTOR_BOARD)
    # A compiler killed (out of memory, say) is named by its signal, not an exit status.
    killed = Compiler(("sh", "-c", "kill -9 $$", "sh"), "a compiler that is killed")
    monkeypatch.setattr("galvoscan.sim.compiled.model.find_compiler", lambda: killed)
    with pytest.raises(CompileError, match=r"failed: stopped by signal 9 \(SIGKILL\)$"):
        SimulatedBoard(backend="compiled", **QUICK_SIM_BOARD, **VECTOR_BOARD)


def test_no_compiler_at_all_is_one_line(monkeypatch):
    from galvoscan.sim.compiled import CompilerError

    def none():
        raise CompilerError("no C++ compiler: none on PATH")
    monkeypatch.setattr("galvoscan.sim.compiled.model.find_compiler", none)
    with pytest.raises(CompileError, match="no C\\+\\+ compiler"):
        compiled_model(GalvoScanTop(clk_freq=8e6, **VECTOR_BOARD))


def test_a_foreign_or_damaged_cached_model_is_never_used(monkeypatch, tmp_path):
    """A file where the cache keeps this design's model that is not it (garbage, or the
    model of another design) is built again, never loaded as this one."""
    monkeypatch.setenv("GALVOSCAN_CACHE_DIR", str(tmp_path))
    small = {"modes": ("spiral",), "correction": None, "laser": False}     # quick to compile
    other_top = GalvoScanTop(clk_freq=4e6, **small)
    other = compiled_model(other_top)
    top = GalvoScanTop(clk_freq=4e6, baud=250_000, **small)
    key = model_module._key(model_module.top_design(top), model_module._board_source(),
                            model_module._yosys_version(), model_module.find_compiler())
    assert key != other.key
    (tmp_path / key).mkdir()
    (tmp_path / key / "model.so").write_bytes(other.path.read_bytes())
    model_module._loaded.pop(key, None)         # (loaded from the user's cache before)
    said = []
    model = compiled_model(top, say=said.append)
    assert model.key == key and any("not usable" in line for line in said)
    assert model.lib.gs_model_key().decode() == key
    (tmp_path / key / "model.so").write_bytes(b"not a library")
    model_module._loaded.pop(key)
    assert compiled_model(top).key == key


def test_an_unwritable_cache_is_one_line(monkeypatch, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    monkeypatch.setenv("GALVOSCAN_CACHE_DIR", str(blocker / "cache"))
    with pytest.raises(CompileError, match="cache .* cannot be used"):
        compiled_model(GalvoScanTop(clk_freq=8e6, laser_alarms=1, **VECTOR_BOARD))


def test_a_model_that_crashes_ends_the_command_with_one_line(tmp_path):
    """A compiled model that fails (a bad memory access) ends its process with one line on
    stderr and a non-zero exit: no core dump, no traceback, and so no pseudo-terminal left
    open behind it."""
    import signal
    import subprocess
    import sys
    child = tmp_path / "child.py"
    child.write_text(
        "import sys\n"
        "sys.path.insert(0, 'tests/support')\n"
        "from sim_board import QUICK_SIM_BOARD, VECTOR_BOARD\n"
        "from galvoscan.sim.board import PTYServer, SimulatedBoard\n"
        "board = SimulatedBoard(backend='compiled', **QUICK_SIM_BOARD, **VECTOR_BOARD)\n"
        "server = PTYServer(board).start()\n"
        "print(server.port, flush=True)\n"
        "board.engine.crash()\n")
    run = subprocess.run([sys.executable, str(child)], capture_output=True, text=True,
                         timeout=300, cwd=str(__import__("pathlib").Path(__file__).parents[2]))
    assert run.returncode == 128 + signal.SIGSEGV
    assert run.stderr.strip().splitlines() == [
        "galvoscan: error: the compiled simulated board crashed (run it with --backend "
        "python, and report it)"]


def test_the_minutes_of_zigs_first_run_are_told_only_before_it(monkeypatch, tmp_path):
    """zig builds its C++ library on its first run alone (minutes, where a compile after it
    takes seconds): the compile's line says so only while zig's cache is empty."""
    from galvoscan.sim.compiled.model import _zig_cache_is_empty
    monkeypatch.setenv("ZIG_GLOBAL_CACHE_DIR", str(tmp_path / "zig"))
    assert _zig_cache_is_empty()                    # not there at all
    (tmp_path / "zig").mkdir()
    assert _zig_cache_is_empty()                    # there, empty
    (tmp_path / "zig" / "o").mkdir()
    assert not _zig_cache_is_empty()


def fake_compiler(folder, name, says):
    path = folder / name
    path.write_text(f"#!/bin/sh\necho '{says}'\n")
    path.chmod(0o755)


def test_the_compiler_is_cxx_then_the_newest_clang_then_gpp(monkeypatch, tmp_path):
    """Clang before g++ (it compiles CXXRTL's C++ in half the time, the models as fast), a
    versioned clang++-N where there is no plain clang++, and $CXX before them all; a
    netlist's light optimisation is -O1 for Clang (zig's included) and -Og for g++."""
    for name, says in [("g++", "g++ (Debian 12.2.0) 12.2.0"),
                       ("clang++-9", "clang version 9.0.1"),
                       ("clang++-14", "Debian clang version 14.0.6"),
                       ("clang++-14.bak", "not a compiler"),
                       ("my-cxx", "my compiler 1.0")]:
        fake_compiler(tmp_path, name, says)
    monkeypatch.setenv("PATH", str(tmp_path))
    monkeypatch.delenv("CXX", raising=False)
    clang = find_compiler("system")
    assert clang.identity == "Debian clang version 14.0.6"
    assert clang.light_optimisation == "-O1"
    (tmp_path / "clang++-14").unlink()
    (tmp_path / "clang++-9").unlink()
    gpp = find_compiler("system")
    assert gpp.identity == "g++ (Debian 12.2.0) 12.2.0" and gpp.light_optimisation == "-Og"
    fake_compiler(tmp_path, "clang++", "clang version 18.1.0")
    assert find_compiler("system").identity == "clang version 18.1.0"
    monkeypatch.setenv("CXX", "my-cxx")
    assert find_compiler("system").identity == "my compiler 1.0"
    assert Compiler(("zig",), "zig 0.13.0", zig=True).light_optimisation == "-O1"


@pytest.mark.parametrize("build", ["player", "ulx3s"])
def test_the_job_player_from_the_flash_is_the_same_on_both_backends(build):
    """The stand-alone board: the flash (the C++ model in board.cc, the Python one in
    galvoscan/sim/spi_flash.py, both from the datasheet), the foot switch, the player; a good
    image played twice and a damaged one refused, the same to the clock. On the small player
    build and on the ULX3S bitstream (every feature, its 33-node correction table; the good
    image alone: the refusal is the same player's, and the ULX3S's Python board is the
    slowest of the suite's)."""
    from galvoscan.outputs.image import job_image
    good = job_image(PLAYER_JOB, REGISTERS, repeats=2)
    damaged = bytearray(good)
    damaged[-1] ^= 0x40
    for image in (good, bytes(damaged)) if build == "player" else (good,):
        board = PLAYER_BOARD if build == "player" else dict(
            **ulx3s_board(mo_lead=PLAYER_BOARD["mo_lead"], start_debounce_ms=1),
            machine_period_s=PLAYER_BOARD["machine_period_s"])
        compiled, python = (SimulatedBoard(backend=backend, flash=image, record_pins=True,
                                           **board) for backend in ("compiled", "python"))
        for board in (compiled, python):
            board.press_start(1.5e-3)
            board.run_for(4e-3)
        assert_same_records(compiled, python)
        assert compiled.engine.flash_counts() == (len(python.flash.commands),
                                                  len(python.flash.ignored))
        assert bool(python.pulses) == (image == good) and python.flash.commands
