# amaranth: UnusedElaboratable=no
# (signature and parameter checks build components without elaborating them)
"""The distortion correction stage against the table's reference arithmetic, alone and on the
system top's pins."""

import numpy as np
import pytest
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out
from amaranth.sim import Simulator
from hypothesis import given, settings, strategies as st, HealthCheck, Phase

from galvoscan.link.client import HostClient, WriteRefused
from galvoscan.correction.upload import upload_table
from galvoscan.gateware.field.correction import FieldCorrection
from galvoscan.gateware.field.correction_table import TABLE_SIZES, CorrectionTable
from galvoscan.gateware.points import FieldPoint
from galvoscan.gateware.sources.spiral_table import SpiralTable
from galvoscan.gateware.top import GalvoScanTop, ScanSettings

from sim_board import SimBoard, SimSPITransport
from spiral_model import PARK, spiral_points


SLOW = settings(max_examples=12, deadline=None, phases=[Phase.explicit, Phase.generate],
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


def random_table(n, rng, low=-32768, high=32767):
    return CorrectionTable(rng.integers(low, high + 1, (n, n)), rng.integers(low, high + 1, (n, n)))


def bilinear_float(table, x, y):
    """Textbook bilinear interpolation in floating point, written apart from the reference."""
    spacing = 65536 / (table.n - 1)
    i, j = int(x // spacing), int(y // spacing)
    u, v = x / spacing - i, y / spacing - j

    def at(grid):
        return ((1 - u) * (1 - v) * grid[j, i] + u * (1 - v) * grid[j, i + 1] +
                (1 - u) * v * grid[j + 1, i] + u * v * grid[j + 1, i + 1])

    return at(table.dx), at(table.dy)


# --- the table and its reference ---------------------------------------------------------------

@pytest.mark.parametrize("n", TABLE_SIZES)
def test_reference_is_bilinear_interpolation_to_a_unit(n):
    rng = np.random.default_rng(n)
    table = random_table(n, rng, -3000, 3000)
    for x, y in rng.integers(0, 65536, (300, 2)):
        ox, oy = table.offsets(x, y)
        fx, fy = bilinear_float(table, float(x), float(y))
        # Two roundings to the unit on the way (top/bottom rows, then between them).
        assert abs(ox - fx) <= 1.0 and abs(oy - fy) <= 1.0


def test_reference_hits_the_nodes_and_saturates():
    table = CorrectionTable(np.full((5, 5), -200), np.full((5, 5), 300))
    assert table.node_spacing == 16384
    x, y, clipped = table.apply([0, 100, 16384, 65535], [65535, 65400, 16384, 0])
    assert x.tolist() == [0, 0, 16184, 65335]
    assert y.tolist() == [65535, 65535, 16684, 300]
    assert clipped.tolist() == [True, True, False, False]


@pytest.mark.parametrize("dx, dy, message", [
    (np.zeros((4, 4)), np.zeros((4, 4)), "5, 9, 17, 33, 65 nodes"),
    (np.zeros((5, 5)), np.zeros((5, 4)), "square tables of the same size"),
    (np.full((5, 5), 40000), np.zeros((5, 5)), "dx offsets must lie in"),
    (np.zeros((5, 5)), np.full((5, 5), 0.5), "dy must hold whole galvo units"),
    (np.zeros(5), np.zeros(5), "square tables"),
])
def test_table_rejects_bad_values(dx, dy, message):
    with pytest.raises(ValueError, match=message):
        CorrectionTable(dx, dy)


def test_table_resamples_and_packs_words():
    rng = np.random.default_rng(3)
    big = random_table(65, rng, -100, 100)
    small = big.resampled(17)
    assert np.array_equal(small.dx, big.dx[::4, ::4])
    assert small.resampled(65).resampled(17) == small
    word = CorrectionTable(np.full((5, 5), -2), np.full((5, 5), 3)).words()[0]
    assert word == (3 << 16) | 0xFFFE
    with pytest.raises(ValueError, match="n must be one of"):
        big.resampled(10)


# --- the stage alone -----------------------------------------------------------------------------

def test_signature_and_parameters():
    stage = FieldCorrection(CorrectionTable.identity(9))
    assert stage.signature.members == wiring.SignatureMembers({
        "positions_in": In(stream.Signature(FieldPoint)),
        "positions_out": Out(stream.Signature(FieldPoint)),
        "enable": In(1), "write_node": In(range(81)), "write_dx": In(16), "write_dy": In(16),
        "write_en": In(1), "write_pending": Out(1), "clipped": Out(1),
    })
    with pytest.raises(TypeError, match="table must be a CorrectionTable"):
        FieldCorrection([[0]])


def run_stage(table, points, *, enable=1, writes=(), sink_stalls=0):
    """Push points through the stage; optionally write nodes (node, dx, dy) while it runs.
    Returns the output points, the clipped flags, and the clock of each write's request."""
    dut = FieldCorrection(table)
    sim = Simulator(dut)
    sim.add_clock(1e-6)
    out, clipped = [], []

    async def source(ctx):
        ctx.set(dut.enable, enable)
        for x, y in points:
            ctx.set(dut.positions_in.payload.x, int(x))
            ctx.set(dut.positions_in.payload.y, int(y))
            ctx.set(dut.positions_in.valid, 1)
            await ctx.tick().until(dut.positions_in.ready)
            ctx.set(dut.positions_in.valid, 0)

    async def sink(ctx):
        for _ in points:
            if sink_stalls:
                await ctx.tick().repeat(sink_stalls)
            ctx.set(dut.positions_out.ready, 1)
            x, y = await ctx.tick().sample(dut.positions_out.payload.x,
                                           dut.positions_out.payload.y) \
                .until(dut.positions_out.valid)
            ctx.set(dut.positions_out.ready, 0)
            out.append((x, y))

    async def flags(ctx):
        async for _, _, flag in ctx.tick().sample(dut.clipped):
            if flag:
                clipped.append(len(out))

    async def writer(ctx):
        for delay, (node, dx, dy) in writes:
            await ctx.tick().repeat(delay)
            ctx.set(dut.write_node, node)
            ctx.set(dut.write_dx, dx & 0xFFFF)
            ctx.set(dut.write_dy, dy & 0xFFFF)
            ctx.set(dut.write_en, 1)
            await ctx.tick()
            ctx.set(dut.write_en, 0)
            # Hold the values until the write is made, as the register file does.
            await ctx.tick().until(~dut.write_pending)

    sim.add_testbench(source)
    sim.add_testbench(sink)
    sim.add_testbench(flags, background=True)
    if writes:
        sim.add_testbench(writer)
    sim.run()
    return out, clipped


def edge_points(table):
    """Corners, first and last cells, both sides of every node line."""
    spacing = table.node_spacing
    lines = sorted({0, 1, 65534, 65535} |
                   {min(max(k * spacing + d, 0), 65535) for k in range(table.n) for d in (-1, 0, 1)})
    return [(x, y) for x in lines[::3] for y in lines[1::3]] + \
        [(0, 0), (0, 65535), (65535, 0), (65535, 65535)]


@pytest.mark.parametrize("n", TABLE_SIZES)
def test_stage_equals_the_reference_at_edges_and_random_points(n):
    rng = np.random.default_rng(100 + n)
    table = random_table(n, rng)                    # full-range offsets: saturates often
    points = edge_points(table) + [tuple(p) for p in rng.integers(0, 65536, (150, 2))]
    out, clipped = run_stage(table, points, sink_stalls=3)
    x, y, flags = table.apply([p[0] for p in points], [p[1] for p in points])
    assert out == list(zip(x.tolist(), y.tolist()))
    # Each clamped point raised `clipped` once, while it was made.
    assert len(clipped) == int(flags.sum()) > 0


@SLOW
@given(st.sampled_from(TABLE_SIZES), st.integers(0, 2**32 - 1), st.data())
def test_stage_equals_the_reference_hypothesis(n, seed, data):
    rng = np.random.default_rng(seed)
    span = data.draw(st.sampled_from([100, 3000, 32767]))
    table = random_table(n, rng, -span, span)
    points = data.draw(st.lists(st.tuples(st.integers(0, 65535), st.integers(0, 65535)),
                                min_size=1, max_size=40))
    out, _ = run_stage(table, points)
    x, y, _ = table.apply([p[0] for p in points], [p[1] for p in points])
    assert out == list(zip(x.tolist(), y.tolist()))


def test_disabled_stage_passes_points_unchanged():
    table = random_table(9, np.random.default_rng(7))
    points = edge_points(table)[:40]
    out, clipped = run_stage(table, points, enable=0)
    assert out == points and clipped == []


def test_writes_never_tear_a_point():
    """Nodes rewritten at random moments while points stream through: every point equals the
    reference under one of the tables the writes pass through, in order. A point made from a
    mix of two tables (or from a half-written node) would match none of them."""
    rng = np.random.default_rng(11)
    table = random_table(5, rng, -20000, 20000)
    # Points all over the field, so that every node takes part in many of them.
    points = [tuple(p) for p in rng.integers(0, 65536, (400, 2))]
    writes, tables = [], [table]
    for _ in range(40):
        node = int(rng.integers(0, 25))
        dx, dy = (int(v) for v in rng.integers(-20000, 20001, 2))
        writes.append((int(rng.integers(1, 60)), (node, dx, dy)))
        tables.append(tables[-1].with_node(node % 5, node // 5, dx, dy))
    out, _ = run_stage(table, points, writes=writes)
    xs, ys = [p[0] for p in points], [p[1] for p in points]
    answers = [list(zip(*(v.tolist() for v in t.apply(xs, ys)[:2]))) for t in tables]
    state = 0
    for k, point in enumerate(out):
        while state < len(tables) and answers[state][k] != point:
            state += 1
        assert state < len(tables), f"point {k} {point} is from no table in the sequence"
    assert state > 0                                   # the writes were seen
    # After the last write, the stage holds the last table.
    final, _ = run_stage(tables[-1], points[:50])
    assert final == answers[-1][:50]


# --- on the system top's pins --------------------------------------------------------------------

def test_correction_on_the_wires_through_the_host_link():
    """A spiral through a non-identity table, read off the XY2-100 wires, equals the reference
    applied to the spiral model; the host then switches correction off, and rewrites a node
    through the SPI pins, and the wires follow."""
    rng = np.random.default_rng(5)
    # 5 x 5 nodes (a node's address still a multiply by 5, not a shift): the whole new table
    # below is 100 frames through the SPI pins, where 9 x 9 was 324.
    table = random_table(5, rng, -1500, 1500)
    spiral = SpiralTable()
    settings_ = ScanSettings(dwell=1)
    # On the compiled board (held to Amaranth's, tests/sim/test_compiled.py): the new table's
    # hundred frames through the SPI pins took over a minute on Amaranth's.
    board = SimBoard(table=spiral, settings=settings_, correction=table, backend="compiled")
    client = HostClient(SimSPITransport(board))
    board.run_for(1.5e-3)
    frames = [f for _, f in board.xy2_frames()]
    # The whole pattern (8064 points), for membership; the run starts at its beginning.
    points = spiral_points(spiral.x, spiral.y, 8064, x_range=(0, 127), y_range=(1, 126))
    x, y, _ = table.apply([p[0] for p in points], [p[1] for p in points])
    assert frames[:2] == [PARK, PARK]
    want = list(zip(x.tolist(), y.tolist()))
    assert frames[2:2 + len(want)] == want[:len(frames) - 2]
    assert client.read("cor_nodes") == 5

    # Off: the wires carry the plain spiral again.
    client.write("cor_enable", 0)
    # Frames that end more than 20 µs after the write (not the two on their way): a frame's
    # time is the end of the run in which it ended, so the 20 µs are a run of their own.
    board.run_for(20e-6)
    since = board.now
    board.run_for(1e-3)
    plain = set(points)
    later = [f for t, f in board.xy2_frames() if t > since]
    assert later and all(f in plain for f in later)

    # A new table through the registers, then on again: the wires follow the new table.
    new = random_table(5, rng, -1500, 1500)
    upload_table(client, new, verify=True)
    client.write("cor_enable", 1)
    board.run_for(20e-6)
    since = board.now
    board.run_for(1e-3)
    later = [f for t, f in board.xy2_frames() if t > since]
    x, y, _ = new.apply([p[0] for p in points], [p[1] for p in points])
    corrected = set(zip(x.tolist(), y.tolist()))
    assert later and all(f in corrected for f in later)
    assert client.read("errors") == 0


def test_top_without_correction_refuses_its_registers():
    board = SimBoard(correction=None)
    client = HostClient(SimSPITransport(board))
    assert client.read("errors") == 0
    for name, value in (("cor_enable", 0), ("cor_write", 1)):   # unknown in this build
        with pytest.raises(WriteRefused, match=name):
            client.write(name, value)
    assert client.read("errors") == 2


def test_top_rejects_a_bad_correction():
    with pytest.raises(TypeError, match="correction must be a CorrectionTable or None"):
        GalvoScanTop(clk_freq=12e6, correction="lens.ctb")
