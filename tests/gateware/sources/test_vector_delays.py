# amaranth: UnusedElaboratable=no
# (the parameter check builds tops that are never elaborated)

"""Vector mode's RTC delays (issue 17): the points on the XY2-100 wires, frame for frame, and
the laser's modulation edges on the DB25 pins, clock for clock, against a plain model of
SCANLAB's delay definitions (tests/support/vector_delay_model.py); bad delay values refused."""

from hypothesis import HealthCheck, Phase, example, given, settings, strategies as st
import pytest

from galvoscan.link.client import ClientError, HostClient, encode_write, WriteRefused
from galvoscan.gateware.top import ScanSettings

from sim_board import SimBoard, SimSPITransport
from vector_board import job_link, jobs_board, set_up_job
from vector_model import PARK
from vector_delay_model import frames_model, modulation_edges

CLK = 4e6
CLOCKS_PER_US = 4
#: 20 kHz: five frames a pulse, so the next segment is always set up in time at 4 MHz (no
#: stall frames, which the model leaves out).
PRR_100HZ = 200


def run(job, *, on=0, off=0, mark=0, polygon=0, jump=300, scaled=0, factors=None, pulses=1,
        pitch=60, extra_s=0.6e-3):
    board = jobs_board(CLK)
    client = set_up_job(board, job, [
        ("laser_prr", PRR_100HZ), ("pulses_per_point", pulses), ("pitch", pitch),
        ("jump_delay", jump), ("laser_on_delay", on), ("laser_off_delay", off),
        ("mark_delay", mark), ("polygon_delay", polygon), ("polygon_scaled", scaled),
        ("laser_power", 200)], factors=factors)
    # Until the job's last segment, the jump to the park position, is on the wires (every job
    # here marks away from it first), then for the longest the model can still put an edge on
    # the modulation pin after it (the jump's hold and the larger laser delay), and 0.3 ms
    # (30 frames) more in which nothing else may happen: compare() checks every frame and edge
    # from power-up to the end of the recording (which the reads below extend by 0.3 ms).
    points = sum(1 + abs(x - 20000) // pitch for _, x, _ in job)
    board.run_until(lambda: parked_again(board),
                    timeout=points * pulses * 60e-6 + (len(job) + 2) * 1e-3 * 0.4 + extra_s)
    board.run_for((jump + max(on, off, 0)) * 1e-6 + 0.3e-3)
    assert client.read("vec_stalls") == 0
    assert client.read("errors") == 0
    return board


def parked_again(board):
    """Whether a frame on the wires has left the park position and a later one is back."""
    positions = [f for _, f in board.xy2_frames()]
    away = next((i for i, p in enumerate(positions) if p != PARK), None)
    return away is not None and PARK in positions[away:]


def observed(board):
    pins = board.laser_pins
    sync = board.sync_pins
    starts = [i for i in range(1, len(sync)) if sync[i] and not sync[i - 1]]
    boundaries = starts[1:]                      # frame f in force from boundaries[f]
    positions = [f for _, f in board.xy2_frames()]
    prr = [c for c in range(1, len(pins)) if pins[c][2] and not pins[c - 1][2]]
    am = [(c, pins[c][1]) for c in range(1, len(pins)) if pins[c][1] != pins[c - 1][1]]
    return boundaries, positions, prr, am


def compare(board, job, *, on=0, off=0, mark=0, polygon=0, jump=300, scaled=0, factors=None,
            pulses=1, pitch=60):
    boundaries, positions, prr, am = observed(board)
    start = next(f for f, p in enumerate(positions) if p != PARK)
    last = min(len(positions), len(boundaries)) - 1
    frames = frames_model(job, boundaries=boundaries[:last + 1], pulse_clocks=prr, start=start,
                          pitch=pitch, pulses_per_point=pulses, jump_us=jump, mark_us=mark,
                          polygon_us=polygon, scaled=bool(scaled), factors=factors)
    assert [p for p, _ in frames] == positions[start:last]
    edges = modulation_edges(frames, boundaries=boundaries, start=start,
                             clocks_per_us=CLOCKS_PER_US, on_us=on, off_us=off)
    horizon = boundaries[last]
    assert [e for e in edges if e[0] < horizon] == [e for e in am if e[0] < horizon]
    return frames, edges


SQUARE = [("jump", 20000, 20000), ("mark", 20300, 20000), ("mark", 20300, 20300),
          ("mark", 20000, 20300), ("jump", 21000, 21000), ("mark", 21000, 21000),
          ("jump", 32768, 32768)]


def test_without_delays_the_laser_follows_the_points_as_before():
    """All delays 0: the modulation switches as the first marked point comes in force and as
    the first point after the marks does, as Wan et al.'s vector mode always did."""
    board = run(SQUARE, jump=50)
    frames, edges = compare(board, SQUARE, jump=50)
    assert len(edges) == 4                      # the square, then the dot


# A typical 10 mm head (docs/design/modes.md, "Laser and scanner delays"): the RTC's figures.
TYPICAL = {"on": 100, "off": 150, "mark": 200, "polygon": 100, "jump": 300}


def test_typical_delays_frame_for_frame_and_clock_for_clock():
    board = run(SQUARE, **TYPICAL)
    frames, edges = compare(board, SQUARE, **TYPICAL)
    # Each of the square's two corners is held 10 frames more with the laser on, its end 20
    # frames with the laser off, before the jump.
    held = {}
    for position, laser in frames:
        held[position, laser] = held.get((position, laser), 0) + 1
    assert held[(20300, 20000), 1] == held[(20300, 20300), 1] == 5 + 10   # 1 pulse: 5 frames
    assert held[(20000, 20300), 0] == 20
    # The square lights once: on 100 µs after its first point, off 150 µs after its last.
    assert [level for _, level in edges] == [1, 0, 1, 0]


@pytest.mark.parametrize("on", [-19, -7])
def test_negative_laser_on_delay_switches_on_before_the_first_point(on):
    job = SQUARE[:3] + [("jump", 32768, 32768)]
    board = run(job, on=on, off=40, mark=50, polygon=30)
    boundaries, positions, prr, am = observed(board)
    frames, edges = compare(board, job, on=on, off=40, mark=50, polygon=30)
    # The line's first point (where the jump ended) comes in force 30 frames after the jump's
    # (300 µs jump delay); the laser rises |on| µs before that.
    start = positions.index((20000, 20000))
    assert am[0] == (boundaries[start + 30] + 1 + on * CLOCKS_PER_US, 1)


def test_scaled_polygon_delay_holds_each_corner_as_the_host_says():
    """polygon_scaled: each corner is held for the frames sent with the mark leaving it (the
    host's polygon delay × (1 - cos φ)); 0 frames passes a corner straight on."""
    factors = [0, 0, 7, 0, 0, 0, 0]
    board = run(SQUARE, polygon=400, scaled=1, factors=factors, on=20, off=30, mark=30)
    compare(board, SQUARE, polygon=400, scaled=1, factors=factors, on=20, off=30, mark=30)


# --- random jobs and delays -------------------------------------------------------------------

coordinate = st.integers(20000, 20200)
segment = st.tuples(st.sampled_from(["jump", "mark", "mark"]), coordinate, coordinate)


# Each example simulates a few milliseconds of the whole board: few examples, no shrinking.
@settings(max_examples=16, deadline=None, suppress_health_check=[HealthCheck.too_slow],
          phases=[Phase.explicit, Phase.reuse, Phase.generate])
@given(st.lists(segment, min_size=1, max_size=4),
       st.integers(-19, 250), st.integers(0, 250), st.integers(0, 120), st.integers(0, 120),
       # A jump held for at least 40 µs: a segment's set-up takes 140 clocks, 35 µs at this
       # 4 MHz clock, and a shorter hold makes the next mark stall (a frame the model, which
       # leaves stalls out, does not have; hypothesis found one with an 8 µs jump).
       st.integers(40, 120), st.booleans(), st.lists(st.integers(0, 12), min_size=6,
                                                    max_size=6))
@example(job=[("jump", 20048, 20199), ("mark", 20133, 20169), ("mark", 20099, 20192),
              ("mark", 20187, 20034)], on=6, off=215, mark=15, polygon=120, jump=95,
         scaled=False, factors=[8, 5, 5, 1, 7, 2])
def test_random_jobs_and_delays_match_the_model(job, on, off, mark, polygon, jump, scaled,
                                                factors):
    """Short random jobs (dots, repeated points, corners) under random delays, however they
    order the laser's edges (a mark shorter than its laser-on delay minus laser-off delay never
    lights): the model's points, frame for frame, and its modulation edges, clock for clock."""
    job = [("jump", 20000, 20100)] + job + [("jump", 32768, 32768)]
    factors = [0] + factors[:len(job) - 2] + [0]
    # Two pulses a point: every marked point is held for at least a pulse period (50 µs), longer
    # than the next segment's 35 µs set-up. With one, a point whose pulse comes at once ends
    # before the next segment is ready and the mark stalls a frame (the documented stall of a
    # one-point segment; hypothesis found one behind a 41-unit mark and a polygon delay).
    delays = dict(on=on, off=off, mark=mark, polygon=polygon, jump=jump, scaled=int(scaled),
                  factors=factors, pulses=2)
    board = run(job, **delays)
    compare(board, job, **delays)


# --- bad values ----------------------------------------------------------------------------------

DELAY_NAMES = ("laser_on_delay", "laser_off_delay", "mark_delay", "polygon_delay",
               "polygon_scaled", "jump_delay")


@settings(max_examples=40, deadline=None)
@given(st.sampled_from(DELAY_NAMES), st.one_of(st.integers(-70000, -20), st.integers(4096, 70000),
                                                st.floats(), st.booleans(), st.text(max_size=3)))
def test_the_client_refuses_bad_delay_values(name, value):
    from galvoscan.gateware.host.regmap import BY_NAME
    reg = BY_NAME[name]
    if isinstance(value, int) and not isinstance(value, bool) and reg.low <= value <= reg.high:
        return
    with pytest.raises(ClientError, match=f"{name} takes an integer from {reg.low} to {reg.high}"):
        encode_write(name, value)


def test_the_board_refuses_out_of_range_delays_and_counts_them():
    """Raw frames past the client: each out-of-range value is refused, counted, and changes
    nothing; the signed laser-on delay reads back negative."""
    from galvoscan.gateware.host.regmap import BY_NAME
    from link_codec import command
    # The jobs' build, over the jobs' link.
    board = jobs_board(CLK)
    client = job_link(board)[1]
    client.write("laser_on_delay", -19)
    assert client.read("laser_on_delay") == -19
    bad = [("laser_on_delay", -20 & 0xFFFF), ("laser_on_delay", 1024),
           ("laser_on_delay", 0x8000), ("laser_off_delay", 1024), ("mark_delay", 4096),
           ("polygon_delay", 0xFFFF), ("polygon_scaled", 2)]
    seq = client.sequence()             # (each is refused, so the next expects it still)
    client.transport.transact([command(seq, BY_NAME[name].address, data) for name, data in bad])
    assert client.read("errors") == len(bad)
    assert client.read("laser_on_delay") == -19
    assert [client.read(n) for n in ("laser_off_delay", "mark_delay", "polygon_delay",
                                     "polygon_scaled")] == [BY_NAME[n].reset for n in (
        "laser_off_delay", "mark_delay", "polygon_delay", "polygon_scaled")]


def test_a_build_without_the_delays_has_none_of_their_registers():
    board = SimBoard(clk_freq=CLK, settings=ScanSettings(mode="vector", run=False),
                     vector_delays=False)
    client = HostClient(SimSPITransport(board, clocks_per_sck=12))
    with pytest.raises(WriteRefused):
        client.write("mark_delay", 100)         # no such register in this build
    with pytest.raises(WriteRefused):
        client.queue_segments([(3, 0, 0)])      # only 0 and 1 here
    assert client.read("errors") == 2


def test_the_delays_need_frames_of_whole_microseconds():
    """A bit rate whose frame is no whole number of µs (20 bits at 1.5 MHz: 13.3 µs) cannot
    count the delays in µs; without them it builds."""
    from galvoscan.gateware.top import GalvoScanTop
    with pytest.raises(ValueError, match="whole number of MHz and frames of whole µs"):
        GalvoScanTop(clk_freq=6e6, bit_rate=1.5e6, baud=500_000, vector_delays=True)
    GalvoScanTop(clk_freq=6e6, bit_rate=1.5e6, baud=500_000, vector_delays=False)
