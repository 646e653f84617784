# amaranth: UnusedElaboratable=no
"""Raster mode (gateware/sources/raster.py): the sequencer alone against a plain Python model
written here from its docstring and the docs' register table, and the whole board's raster
(the points decoded from the XY2-100 wires, the laser pulses counted on the DB25 pins) against
the analysis model :func:`galvoscan.analysis.patterns.raster_frames`."""

import itertools

from amaranth.sim import Simulator
from hypothesis import example, given, settings, strategies as st

import pytest

from galvoscan.analysis.patterns import raster_frames
from galvoscan.link.client import HostClient
from galvoscan.gateware.sources.raster import RasterSequencer
from galvoscan.gateware.fields import Mode

from sim_board import QUICK_SIM_BOARD, SimSPITransport, quick_board
from vector_board import pulses_per_frame


# --- the model ---------------------------------------------------------------------------------

def raster_model(*, x, y, width, height, spacing, step, along_y=False, one_way=False, gate=0,
                 frames):
    """(x, y, laser) per frame, galvo units: along a line 0, step, 2·step, … and then exactly
    the far edge; lines 0, spacing, 2·spacing, … as long as they are within the rectangle, then
    the first again; every other line backwards unless one way; the laser off for ``gate``
    frames at the start of every line but the very first; positions past 65535 clamped."""
    step, spacing = step or 1, spacing or 1
    length, across_length = (height, width) if along_y else (width, height)
    out, line = [], 0
    while len(out) < frames:
        for index, across in enumerate(range(0, across_length + 1, spacing)):
            backwards = index % 2 == 1 and not one_way
            for k, along in enumerate(itertools.chain(range(0, length, step), [length])):
                a = length - along if backwards else along
                px, py = (x + across, y + a) if along_y else (x + a, y + across)
                out.append((min(px, 65535), min(py, 65535), not (line > 0 and k < gate)))
                if len(out) == frames:
                    # (A field-wide rectangle at step 1 is billions of frames a pass.)
                    return out
            line += 1
    return out


def test_model_by_hand():
    # A 25 × 20 rectangle, lines 10 apart, 10 a frame: lines at y 0, 10, 20; serpentine.
    got = raster_model(x=100, y=200, width=25, height=20, spacing=10, step=10, frames=13)
    assert [(px, py) for px, py, _ in got] == [
        (100, 200), (110, 200), (120, 200), (125, 200),
        (125, 210), (115, 210), (105, 210), (100, 210),
        (100, 220), (110, 220), (120, 220), (125, 220),
        (100, 200)]
    # Along Y, one way, gated 2.
    got = raster_model(x=0, y=0, width=10, height=15, spacing=10, step=10, along_y=True,
                       one_way=True, gate=2, frames=7)
    assert got == [(0, 0, True), (0, 10, True), (0, 15, True),
                   (10, 0, False), (10, 10, False), (10, 15, True), (0, 0, False)]


@pytest.mark.parametrize("along_y, one_way", [(0, 0), (1, 1)])
def test_model_agrees_with_the_analysis_model(along_y, one_way):
    frames = raster_frames(corner=(300, 400), size=(95, 40), spacing=20, step=30,
                           lines_along="y" if along_y else "x", bidirectional=not one_way,
                           turn_gate=2, passes=2)
    mine = raster_model(x=300, y=400, width=95, height=40, spacing=20, step=30,
                        along_y=along_y, one_way=one_way, gate=2, frames=len(frames))
    assert mine == list(zip(frames.x.tolist(), frames.y.tolist(), map(bool, frames.laser)))


# --- the sequencer alone -------------------------------------------------------------------------

def run_sequencer(params, frames, *, ready=True):
    """Start the sequencer with ``params`` and strobe it ``frames`` times; returns (x, y, laser)
    per frame in galvo units (from the offsets it gives), and whether a point ever came without
    a strobe."""
    dut = RasterSequencer()
    out = []

    async def bench(ctx):
        names = {"x": dut.x, "y": dut.y, "width": dut.width, "height": dut.height,
                 "spacing": dut.spacing, "step": dut.step, "along_y": dut.along_y,
                 "one_way": dut.one_way, "gate": dut.turn_gate}
        for name, value in params.items():
            ctx.set(names[name], value)
        ctx.set(dut.points.ready, 1)
        await ctx.tick().repeat(3)
        assert not ctx.get(dut.points.valid) and not ctx.get(dut.laser)   # not running
        ctx.set(dut.run, 1)
        await ctx.tick().repeat(2)
        assert not ctx.get(dut.points.valid)                              # only on strobes
        for _ in range(frames):
            ctx.set(dut.frame_strobe, 1)
            await ctx.tick()
            ctx.set(dut.frame_strobe, 0)
            assert ctx.get(dut.points.valid)
            px, py = ctx.get(dut.points.payload.x), ctx.get(dut.points.payload.y)
            out.append((px + 32768, py + 32768, bool(ctx.get(dut.laser))))
            await ctx.tick()
            assert not ctx.get(dut.points.valid)
        ctx.set(dut.run, 0)
        await ctx.tick()
        assert not ctx.get(dut.laser)

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    return out


def pass_length(*, width, height, spacing, step, along_y=False, **_):
    """Frames in one pass over the rectangle."""
    length, across_length = (height, width) if along_y else (width, height)
    return (across_length // (spacing or 1) + 1) * (len(range(0, length, step or 1)) + 1)


CASES = {
    "serpentine along x": dict(x=30000, y=31000, width=95, height=40, spacing=20, step=30),
    "one way along x": dict(x=30000, y=31000, width=95, height=40, spacing=20, step=30,
                            one_way=1),
    "serpentine along y": dict(x=40000, y=20000, width=33, height=70, spacing=25, step=10,
                               along_y=1),
    "one way along y": dict(x=40000, y=20000, width=33, height=70, spacing=25, step=10,
                            along_y=1, one_way=1),
    "turn gate": dict(x=1000, y=2000, width=60, height=30, spacing=10, step=15, gate=2),
    "turn gate longer than a line": dict(x=1000, y=2000, width=30, height=20, spacing=10,
                                         step=15, gate=5, one_way=1),
    "turn gate along y": dict(x=0, y=0, width=20, height=50, spacing=10, step=20, gate=1,
                              along_y=1),
    "step a divisor of the length": dict(x=100, y=100, width=90, height=30, spacing=15,
                                         step=30),
    "height not a multiple of the spacing": dict(x=100, y=100, width=40, height=29,
                                                 spacing=10, step=40),
    "step longer than the line": dict(x=5, y=5, width=10, height=10, spacing=5, step=500),
    "step and spacing 0 are taken as 1": dict(x=50, y=60, width=3, height=2, spacing=0,
                                              step=0),
    "a point": dict(x=32768, y=32768, width=0, height=0, spacing=7, step=7, gate=1),
    "a single line": dict(x=10, y=10, width=50, height=0, spacing=10, step=20, gate=1),
    "clamped past 65535 along x": dict(x=65000, y=65500, width=1000, height=60, spacing=20,
                                       step=300),
    "clamped past 65535 along y": dict(x=65500, y=65400, width=70, height=400, spacing=25,
                                       step=90, along_y=1, one_way=1),
    "the whole field": dict(x=0, y=0, width=65535, height=65535, spacing=30000, step=20000),
    "corner at the far edge": dict(x=65535, y=65535, width=65535, height=65535,
                                   spacing=65535, step=65535, gate=1),
}


@pytest.mark.parametrize("params", CASES.values(), ids=CASES.keys())
def test_sequencer_matches_the_model(params):
    """Two passes and a bit more: the fill starts again from the first line (gated from the
    second pass on)."""
    frames = min(2 * pass_length(**params) + 3, 400)
    assert run_sequencer(params, frames) == raster_model(**params, frames=frames)


def test_stopping_starts_again_at_the_first_line_ungated():
    params = dict(x=100, y=100, width=20, height=20, spacing=10, step=10, gate=2)
    first = run_sequencer(params, 7)
    dut = RasterSequencer()
    out = []

    async def bench(ctx):
        for name, value in (("x", 100), ("y", 100), ("width", 20), ("height", 20),
                            ("spacing", 10), ("step", 10), ("turn_gate", 2)):
            ctx.set(getattr(dut, name), value)
        ctx.set(dut.points.ready, 1)
        await ctx.tick().repeat(2)
        for run_frames in (5, 7):
            ctx.set(dut.run, 1)
            for _ in range(run_frames):
                ctx.set(dut.frame_strobe, 1)
                await ctx.tick()
                ctx.set(dut.frame_strobe, 0)
                out.append((ctx.get(dut.points.payload.x) + 32768,
                            ctx.get(dut.points.payload.y) + 32768, bool(ctx.get(dut.laser))))
                await ctx.tick()
            ctx.set(dut.run, 0)
            # Stopped: strobes give no points and the laser is off.
            ctx.set(dut.frame_strobe, 1)
            await ctx.tick()
            ctx.set(dut.frame_strobe, 0)
            assert not ctx.get(dut.laser)
            await ctx.tick()
            assert not ctx.get(dut.points.valid)

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    assert out[:5] == first[:5] and out[5:] == first
    assert first == raster_model(**params, frames=7)


def test_first_line_ungated_with_run_high_from_reset():
    dut = RasterSequencer()
    lasers = []

    async def bench(ctx):
        for name, value in (("width", 20), ("height", 20), ("spacing", 10), ("step", 10),
                            ("turn_gate", 2)):
            ctx.set(getattr(dut, name), value)
        ctx.set(dut.points.ready, 1)
        ctx.set(dut.run, 1)
        for _ in range(3):
            ctx.set(dut.frame_strobe, 1)
            await ctx.tick()
            ctx.set(dut.frame_strobe, 0)
            lasers.append(ctx.get(dut.laser))
            await ctx.tick()

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    assert lasers == [1, 1, 1]


corner = st.one_of(st.integers(0, 65535), st.integers(65300, 65535))
size = st.one_of(st.integers(0, 120), st.integers(60000, 65535))


@settings(max_examples=40, deadline=None)
@given(corner, corner, size, size, st.integers(0, 70), st.integers(0, 70), st.booleans(),
       st.booleans(), st.integers(0, 4))
# (The whole field at step and spacing 1: the model once built a pass of 4e9 frames first.)
@example(0, 0, 65535, 65535, 0, 0, False, False, 0)
def test_random_rectangles_against_the_model(x, y, width, height, spacing, step, along_y,
                                             one_way, gate):
    # Spacing and step scaled with the size, so that every example sees line ends and turns.
    if max(width, height) > 1000:
        step, spacing = step * 900 + 1, spacing * 900 + 1
    params = dict(x=x, y=y, width=width, height=height, spacing=spacing, step=step,
                  along_y=int(along_y), one_way=int(one_way), gate=gate)
    assert run_sequencer(params, 150) == raster_model(**params, frames=150)


# --- on the whole board (moved from tests/gateware/sources/test_vector.py) --------------------------------------

RASTER_CASES = [
    # corner, size, spacing, step, flags (bit 0 along y, bit 1 one way), turn gate
    ((30000, 31000), (95, 40), 20, 30, 0, 0),
    ((30000, 31000), (95, 40), 20, 30, 2, 2),
    ((40000, 20000), (33, 70), 25, 10, 1, 3),
]


@pytest.mark.parametrize("corner, size, spacing, step, flags, gate", RASTER_CASES)
def test_raster_matches_the_analysis_model(corner, size, spacing, step, flags, gate):
    """The raster the analysis compares with the spiral is the one the gateware draws: on the
    default build (on the compiled board, which tests/sim/test_compiled.py holds to Amaranth's
    simulator, raster included), switched from the spiral it starts in to raster mode over
    SPI, as a host does."""
    board = quick_board(record_laser=True)
    client = HostClient(SimSPITransport(board, clocks_per_sck=12))
    for name, value in (("run", 0), ("mode", Mode.RASTER.value),
                        ("ras_x", corner[0]), ("ras_y", corner[1]), ("ras_w", size[0]),
                        ("ras_h", size[1]), ("ras_spacing", spacing), ("ras_step", step),
                        ("ras_flags", flags), ("ras_turn_gate", gate),
                        ("laser_prr", 1000), ("arm", 1)):
        client.write(name, value)
    board.run_for(QUICK_SIM_BOARD["mo_lead"] + 0.1e-3)       # (the laser ready)
    sent = len(board.xy2_frames())
    client.write("run", 1)
    model = raster_frames(corner=corner, size=size, spacing=spacing, step=step,
                          lines_along="y" if flags & 1 else "x",
                          bidirectional=not flags & 2, turn_gate=gate, passes=2)
    board.run_for((len(model) + 20) * 10e-6)
    per_frame = pulses_per_frame(board)
    first = sent + [f for f, _ in per_frame[sent:]].index((corner[0], corner[1]))
    got = per_frame[first:first + len(model)]
    assert [f for f, _ in got] == list(zip(model.x.tolist(), model.y.tolist()))
    # The laser is off exactly on the gated frames; at 100 kHz the others get a pulse each.
    counts = [n for _, n in got]
    assert all(n == 0 for n, on in zip(counts, model.laser) if not on)
    lit = [n for n, on in zip(counts, model.laser) if on]
    assert abs(sum(lit) - len(lit)) <= 1 and max(lit) <= 2
    assert (gate == 0) == all(model.laser)
