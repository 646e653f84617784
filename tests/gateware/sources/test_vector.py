# amaranth: UnusedElaboratable=no
# (the parameter checks build tops that are never elaborated)

"""Vector mode (issue 6): the points decoded from the XY2-100 wires against plain Python models
written from Wan et al. 2018's DDA, and the laser pulses on every point counted on the DB25
pins. (Raster mode: tests/gateware/sources/test_raster.py.)"""

from hypothesis import HealthCheck, Phase, given, settings, strategies as st
import pytest

from galvoscan.link.client import ClientError, HostClient, WriteRefused
from galvoscan.gateware.host.regmap import STATUS_BITS, VectorOp
from galvoscan.gateware.fields import pack
from galvoscan.gateware.sources.vector import DelayedVectorCommand, VecOpWord
from galvoscan.gateware.top import VECTOR_QUEUE_DEPTH, ScanSettings

from player_board import PLAYER_BOARD
from sim_board import SimBoard, SimSPITransport, SimUARTTransport
from vector_board import NO_DELAYS, queue, runs_on_the_wires, set_up_job, start_board
from vector_model import PARK, dda, job_model, merge


def test_model_follows_001():
    """0.1 mm (60 units) pitch: a 600-unit line has points every 60; a 45° line steps both
    axes by 60/√2 ≈ 42.4."""
    assert dda((0, 0), (600, 0), 60) == [(60 * k, 0) for k in range(1, 11)]
    assert dda((0, 0), (100, 100), 60)[0] == (42, 42)
    assert dda((0, 0), (0, -130), 60) == [(0, -60), (0, -120), (0, -130)]
    assert dda((5, 5), (5, 5), 60) == []


# --- running a job on the simulated board -------------------------------------------------------

def run_job(job, *, prr_100hz=600, pulses=1, pitch=60, seconds=None, clk_freq=4e6):
    board, _ = start_board(clk_freq)
    client = set_up_job(board, job, [("laser_prr", prr_100hz), ("pulses_per_point", pulses),
                                     ("pitch", pitch), ("jump_delay", 50),
                                     *NO_DELAYS.items(), ("laser_power", 200)])
    expected = job_model(job, pitch, pulses)
    if seconds:
        board.run_for(seconds)
        return board, client, expected
    # Until the model's points and pulses are all on the wires (or the time the job needs,
    # with a fifth to spare, has passed), then half a millisecond (50 frames) more, in which
    # nothing else may happen: the test compares everything from power-up to the end.
    frames_needed = sum(max(1, n) for _, n in expected) * (100_000 / (prr_100hz * 100)) + 20
    want = merge([(PARK, 0)] + expected)
    deadline = board.now + frames_needed * 12e-6 + 1e-3
    while board.now < deadline and runs_on_the_wires(board) != want:
        board.run_for(0.1e-3)
    board.run_for(0.5e-3)
    return board, client, expected


LINES = [
    ("jump", 20000, 20000), ("mark", 20600, 20000),          # 0°
    ("mark", 21000, 20400),                                  # 45°, straight on from there
    ("mark", 21050, 21300),                                  # steep
    ("jump", 40000, 40000), ("mark", 39000, 39300),          # negative both ways
    ("jump", 10000, 50000), ("mark", 10000, 50000),          # a single point
    ("mark", 10000, 50000),                                  # zero length: nothing new
    ("mark", 10030, 49990),                                  # shorter than the pitch
    ("jump", 32768, 32768),                                  # park, laser off
]


@pytest.mark.parametrize("prr_100hz, pulses", [(600, 1), (300, 3)])
def test_job_matches_the_model_point_for_point_and_pulse_for_pulse(prr_100hz, pulses):
    board, client, expected = run_job(LINES, prr_100hz=prr_100hz, pulses=pulses)
    # Parked until run, laser off; then the model's points and pulses.
    assert runs_on_the_wires(board) == merge([(PARK, 0)] + expected)
    # The job ends with a jump, laser off: running out of segments then is no underrun.
    assert client.read("vec_underruns") == 0
    assert client.read("errors") == 0


def test_each_point_gets_exactly_n_pulses_at_the_board_clock():
    """At the iCEBreaker's 12 MHz the next segment is always ready in time: no stall."""
    job = [("jump", 30000, 30000), ("mark", 30100, 30000), ("mark", 30100, 30100),
           ("mark", 30000, 30100), ("mark", 30000, 30000)]
    board, client, expected = run_job(job, prr_100hz=1000, pulses=2, pitch=40, clk_freq=12e6)
    assert runs_on_the_wires(board) == merge([(PARK, 0)] + expected)
    assert client.read("vec_stalls") == 0


@pytest.mark.parametrize("prr_100hz, speed", [(600, 6.0), (300, 3.0)])
def test_line_speed_of_the_001_table(prr_100hz, speed):
    """Wan et al. 2018: 0.1 mm pitch (60 units on a 110 mm field), N = 1: 6 m/s at 60 kHz,
    3 m/s at 30."""
    job = [("jump", 20000, 30000), ("mark", 26000, 30000)]     # 100 points, 10 mm
    board, client, expected = run_job(job, prr_100hz=prr_100hz)
    frames = board.xy2_frames()
    sync = board.sync_pins
    starts = [i for i in range(1, len(sync)) if sync[i] and not sync[i - 1]]
    # When the head gets the line's first and last points (frame k in force from start k+1).
    index = [f for _, f in frames]
    first = index.index((20060, 30000))
    last = index.index((26000, 30000))
    seconds = (starts[last + 1] - starts[first + 1]) / 4e6
    mm = (26000 - 20060) * 110 / 65536
    assert mm / seconds / 1e3 == pytest.approx(speed * 1.0067, rel=0.01)   # 60 units = 0.1007 mm


def test_the_builds_queue_reads_512_free_when_empty():
    board = SimBoard(settings=ScanSettings(mode="vector", run=False))
    client = HostClient(SimSPITransport(board, clocks_per_sck=12))
    assert client.read("fifo_free") == VECTOR_QUEUE_DEPTH == 512
    assert client.read("status") & (1 << STATUS_BITS["vector_busy"]) == 0


# The queue filled here is built 16 deep, not the build's 512 (the same FIFO; fifo_free counts
# down from its depth): full after 17 writes, not 513.
SHORT_QUEUE = 8


def test_full_queue_refuses_and_counts():
    # The job player's small vector build, whose queue holds SHORT_QUEUE (its model is
    # compiled for the player's tests already), over its UART.
    assert PLAYER_BOARD["vector_queue_depth"] == SHORT_QUEUE
    board = SimBoard.powered_up(backend="compiled", record_laser=True, **{
        name: value for name, value in PLAYER_BOARD.items() if name != "machine_period_s"})
    client = HostClient(SimUARTTransport(board))
    assert client.read("fifo_free") == SHORT_QUEUE
    # The queue, and one in the sequencer's hand: the last answer says no room is left.
    assert client.queue_segments([(0, 32768, 32768)] * (SHORT_QUEUE + 1)) == 0
    assert client.read("fifo_free") == 0
    assert client.read("errors") == 0
    with pytest.raises(WriteRefused, match="vector queue is full"):
        client.queue_segments([(0, 32768, 32768)])
    assert client.read("vec_rejected") == 1
    assert client.read("errors") == 1
    # Nothing queued was lost: every jump comes out once the mode runs.
    client.write("jump_delay", 10)
    client.write("run", 1)
    board.run_until(lambda: client.read("fifo_free") == SHORT_QUEUE, timeout=20e-3)


def test_underrun_holds_with_the_laser_off_and_resumes_without_repeating():
    board, client = start_board()
    client.write("laser_prr", 500)
    client.write("jump_delay", 30)
    for name, value in NO_DELAYS.items():
        client.write(name, value)
    client.write("arm", 1)
    board.run_for(0.3e-3)
    client.write("run", 1)
    first = [("jump", 30000, 30000), ("mark", 30300, 30000)]
    queue(client, first)
    board.run_for(2e-3)
    assert client.read("vec_underruns") == 1
    quiet_from = len(board.laser_pins)
    board.run_for(1e-3)
    quiet = board.laser_pins[quiet_from:]
    assert not any(am for _, am, *_ in quiet)        # no emission while starved
    second = [("mark", 30300, 30300)]
    queue(client, second)
    board.run_for(2e-3)
    expected = job_model(first + second, 60, 1)
    assert runs_on_the_wires(board) == merge([(PARK, 0)] + expected)
    assert client.read("vec_underruns") == 2


# --- random jobs ----------------------------------------------------------------------------------

coordinate = st.integers(20000, 20400)
segment = st.tuples(st.sampled_from(["jump", "mark", "mark"]), coordinate, coordinate)


# Each example simulates a few milliseconds of the whole board: few examples, no shrinking.
@settings(max_examples=24, deadline=None, suppress_health_check=[HealthCheck.too_slow],
          phases=[Phase.explicit, Phase.reuse, Phase.generate])
@given(st.lists(segment, min_size=1, max_size=5), st.sampled_from([1, 2]),
       st.sampled_from([45, 60, 150]), st.tuples(coordinate, coordinate))
def test_random_jobs_match_the_model(job, pulses, pitch, start):
    """Short random jobs (repeated points, zero-length marks, jumps onto the current point)
    give the model's points with exactly the model's pulses."""
    # A jump into the jobs' 400-unit square first: a first mark from the park position would
    # be a line of hundreds of points (what the DDA's own tests and the fixed job above
    # cover), three quarters of each example's clocks.
    job = [("jump", *start)] + job + [("jump", 32768, 32768)]   # end with the laser off
    board, client, expected = run_job(job, prr_100hz=500, pulses=pulses, pitch=pitch)
    assert runs_on_the_wires(board) == merge([(PARK, 0)] + expected)
    assert client.read("errors") == 0


# --- builds with fewer modes ----------------------------------------------------------------------

def test_a_spiral_only_build_refuses_the_other_modes():
    """The modes left out, and their registers, do not exist: frames for them are refused and
    counted, like frames for unknown addresses."""
    board = SimBoard(modes=("spiral",))
    client = HostClient(SimSPITransport(board, clocks_per_sck=12))
    for write in (lambda: client.write("mode", 2),      # not built: refused
                  lambda: client.write("mode", 1),
                  lambda: client.queue_segments([(1, 0, 0)]),   # no such register here
                  lambda: client.write("ras_w", 100)):
        with pytest.raises(WriteRefused):
            write()
    assert client.read("mode") == 0
    assert client.read("errors") == 4
    with pytest.raises(ClientError):
        client.read("fifo_free")                # no answer but the refusal
    assert client.read("errors") == 5
    client.write("mode", 0)                     # still fine
    assert client.read("errors") == 5


@pytest.mark.parametrize("kwargs, message", [
    ({"modes": ()}, "modes must be some of"),
    ({"modes": ("spiral", "laser")}, "modes must be some of"),
    ({"modes": ("vector", "vector")}, "each once"),
    ({"modes": ("raster",)}, "start in spiral mode"),
])
def test_top_rejects_bad_mode_sets(kwargs, message):
    from galvoscan.gateware.top import GalvoScanTop
    with pytest.raises(ValueError, match=message):
        GalvoScanTop(clk_freq=4e6, **kwargs)


def test_the_words_the_host_packs_are_the_registers_documented_bits():
    """``vec_op`` as its description gives it (bit 0 the op, 1 = mark; bits 7:1 the corner
    hold), and a queued segment's word, from numbers written out here."""
    assert pack(VecOpWord, op=VectorOp.JUMP) == 0
    assert pack(VecOpWord, op=VectorOp.MARK) == 1
    assert pack(VecOpWord, op=VectorOp.MARK, corner_frames=5) == 0b1011
    assert pack(VecOpWord, op=VectorOp.MARK, corner_frames=127) == 255
    # op in bit 0, x in bits 16:1, y in 32:17, the corner hold in 39:33.
    assert pack(DelayedVectorCommand, op=VectorOp.MARK, x=0x1234, y=0xABCD, corner_frames=3) \
        == 1 | 0x1234 << 1 | 0xABCD << 17 | 3 << 33
    for bad in (128, -1, True, 1.0):
        with pytest.raises(ValueError, match="does not fit"):
            pack(VecOpWord, op=VectorOp.MARK, corner_frames=bad)


def test_vec_flush_empties_the_queue_and_stops_the_mode():
    """A job left half-queued (a host that died mid-job): vec_flush empties the queue and
    stops the sequencer where it is; the next job is taken and marks from its start."""
    from galvoscan.gateware.fields import STATUS_BITS
    from galvoscan.link.client import HostClient, WriteRefused
    from galvoscan.outputs.stream import JobStreamer
    from galvoscan.sim.board import SimTransport, SimulatedBoard
    # The job player's small vector build (8 places, a 0.2 ms lead), its player idle, on the
    # compiled board that tests/sim/test_compiled.py holds to Amaranth's simulator.
    board = SimulatedBoard(backend="compiled", **PLAYER_BOARD)
    client = HostClient(SimTransport(board))
    client.queue_segments([(1, x, 30000) for x in (30000, 31000, 32000)])
    client.write("run", 1)
    board.run_for(0.2e-3)
    assert client.read("fifo_free") < 8
    client.write("vec_flush", 1)
    board.run_for(20e-6)
    assert client.read("fifo_free") == 8
    status = client.read("status")
    assert not status >> STATUS_BITS["vector_busy"] & 1     # nothing queued or in hand
    frames = len(board.frames)
    board.run_for(0.2e-3)
    assert {(x, y) for _, x, y in board.frames[frames + 2:]} <= \
        {(x, y) for _, x, y in board.frames[frames - 1:frames + 2]}     # it stays put
    client.write("run", 0)
    report = JobStreamer(client, poll_s=0).run_vector(
        [("jump", 20000, 20000), ("mark", 20300, 20000)], {"pitch": 100}, timeout_s=1e9)
    assert report.segments == 3 and report.counters["vec_rejected"] == 0
    assert (20300, 20000) in {(x, y) for _, x, y in board.frames}
