# amaranth: UnusedElaboratable=no
# (signature and parameter checks build components without elaborating them)

import math
import time

import pytest
from amaranth.hdl import Elaboratable, Module, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import connect
from hypothesis import HealthCheck, Phase, given, settings, strategies as st
from amaranth.lib.wiring import In, Out

from galvoscan.analysis.patterns import spiral_frames as analysis_spiral_frames
from galvoscan.gateware.field.scale import ScaleOffset
from galvoscan.gateware.phy.xy2_100 import XY2Transmitter
from galvoscan.gateware.points import OffsetPoint
from galvoscan.gateware.sources.spiral import PARK_FRAMES, SpiralSequencer
from galvoscan.gateware.sources.spiral_table import SpiralTable
from galvoscan.gateware.limits import FRAME_US
from galvoscan.gateware.top import GalvoScanTop, ScanSettings

from spiral_model import PARK, spiral_frames
from wires import frames_from_samples, record_falling_edges
from sim_board import quick_board


def test_sequencer_signature():
    sequencer = SpiralSequencer(SpiralTable(points=128))
    assert sequencer.signature.members == wiring.SignatureMembers({
        "frame_strobe": In(1), "run": In(1), "dwell": In(16),
        "x_first": In(range(128)), "x_last": In(range(128)),
        "y_first": In(range(128)), "y_last": In(range(128)),
        "points": Out(stream.Signature(OffsetPoint)),
    })
    assert SpiralSequencer.Signature(points=64).members["x_first"] == In(range(64))


def test_sequencer_with_interpolation_has_its_input():
    sequencer = SpiralSequencer(SpiralTable(points=128), interpolation=True)
    assert sequencer.signature.members["interpolate"] == In(1)
    assert "interpolate" not in SpiralSequencer(SpiralTable(points=128)).signature.members


def test_sequencer_rejects_bad_parameters():
    with pytest.raises(TypeError, match="table must be a SpiralTable"):
        SpiralSequencer([0] * 128)
    with pytest.raises(TypeError, match="points must be an integer"):
        SpiralSequencer.Signature(points=1)


def test_top_ports_have_the_fixed_names():
    top = GalvoScanTop(clk_freq=12e6)
    assert list(top.signature.members) == [
        "xy2_clk", "xy2_sync", "xy2_x", "xy2_y",
        "spi_sck", "spi_cs_n", "spi_copi", "spi_cipo", "uart_rx", "uart_tx",
        "laser_power", "laser_latch", "laser_mo", "laser_am", "laser_prr", "laser_enable",
        "laser_guide", "interlock_open", "laser_alarm"]


@pytest.mark.parametrize("kwargs, message", [
    ({"dwell": 0}, "dwell must be an integer from 1 to 65535"),
    ({"dwell": 70000}, "dwell must be"),
    ({"amp_x": -1}, "amp_x must be"),
    ({"center_y": 65536}, "center_y must be"),
    ({"dwell": 2.5}, "dwell must be"),
])
def test_settings_reject_bad_values(kwargs, message):
    with pytest.raises(ValueError, match=message):
        ScanSettings(**kwargs)


@pytest.mark.parametrize("x_range, y_range", [((0, 128), (1, 126)), ((5, 4), (1, 126)),
                                              ((0, 127), (-1, 126)), ((0,), (1, 126))])
def test_top_rejects_ranges_outside_the_table(x_range, y_range):
    with pytest.raises(ValueError, match="must be \\(first, last\\)"):
        GalvoScanTop(clk_freq=12e6, settings=ScanSettings(x_range=x_range, y_range=y_range))


def test_top_rejects_bad_clock():
    with pytest.raises(ValueError, match="even integer multiple"):
        GalvoScanTop(clk_freq=13e6)


class SpiralPath(Elaboratable):
    """The spiral's path through the system top, wired as :class:`GalvoScanTop` wires it in a
    build with only spiral mode and no correction stage (``modes=("spiral",),
    correction=None``): the sequencer's points into the buffered scale stage, its positions
    into the PHY, the PHY's frame strobe back to the sequencer, and the register values the
    top starts with (``settings.register_resets()``) held on their inputs. What the top adds
    around it (host link, register file, status, the source select, which in spiral mode
    passes the spiral's stream and ``run`` through unchanged) does nothing until a host
    writes. The PHY is the real :class:`XY2Transmitter` at ``clk_freq``: the XY2-100 wires."""

    def __init__(self, table, settings, *, clk_freq=4e6):
        self.table, self.settings, self.clk_freq = table, settings, clk_freq
        self.xy2_clk, self.xy2_sync, self.xy2_x, self.xy2_y = (Signal(name=name) for name in (
            "xy2_clk", "xy2_sync", "xy2_x", "xy2_y"))

    def elaborate(self, platform):
        m = Module()
        resets = self.settings.register_resets()
        m.submodules.spiral = spiral = SpiralSequencer(self.table, interpolation=True)
        m.submodules.scale = scale = ScaleOffset(buffered=True)
        for name in ("dwell", "x_first", "x_last", "y_first", "y_last", "run"):
            m.d.comb += getattr(spiral, name).eq(resets[name])
        m.d.comb += spiral.interpolate.eq(resets["spiral_interp"])
        for name in ("amp_x", "amp_y", "center_x", "center_y"):
            m.d.comb += getattr(scale, name).eq(resets[name])
        connect(m, spiral.points, scale.offsets)
        m.submodules.phy = phy = XY2Transmitter(clk_freq=self.clk_freq)
        connect(m, scale.positions, phy.position)
        m.d.comb += spiral.frame_strobe.eq(phy.frame_strobe)
        for name in ("xy2_clk", "xy2_sync", "xy2_x", "xy2_y"):
            m.d.comb += getattr(self, name).eq(getattr(phy, name))
        return m


def replay(table, settings, points, *, clocks_per_bit=2, path_only=False, **top_kwargs):
    """Frames decoded from the system top's wires, enough for ``points`` spiral points; with
    ``path_only``, from the wires of :class:`SpiralPath` (the spiral-only top's scan path)."""
    clk_freq = clocks_per_bit * 2e6
    if path_only:
        assert not top_kwargs
        top = SpiralPath(table, settings, clk_freq=clk_freq)
    else:
        top = GalvoScanTop(clk_freq=clk_freq, table=table, settings=settings, **top_kwargs)
    samples = record_falling_edges(top, clk_freq, frames=PARK_FRAMES + points * settings.dwell)
    return frames_from_samples(samples)


def expected(table, settings, points):
    return spiral_frames(table.x, table.y, points, dwell=settings.dwell,
                         interp=settings.spiral_interp, x_range=settings.x_range, y_range=settings.y_range,
                         gain=(settings.amp_x, settings.amp_y),
                         centre=(settings.center_x, settings.center_y))


@pytest.mark.slow
def test_full_pattern_replays_point_for_point():
    """All lcm(128, 126) = 8064 points of the precessing spiral, 3 frames (30 µs) each, linear
    interpolation between them (the reset), on the XY2-100 wires of the default build from
    power-up, decoded by the tests' reader, equal the model frame for frame: 24,194 frames,
    a quarter of a second of the board. (Points held without interpolation: test_held_points
    and others.) On the compiled board, which tests/sim/test_compiled.py holds to Amaranth's
    simulator record for record; the first 60 points are replayed on Amaranth's here too."""
    table, settings = SpiralTable(), ScanSettings()
    assert settings.spiral_interp == 1
    points = math.lcm(128, 126)
    assert points == 8064
    total = PARK_FRAMES + points * settings.dwell
    board = quick_board()
    start = time.monotonic()
    board.run_for((total + 1) * FRAME_US * 1e-6)
    frames = [frame for _, frame in board.xy2_frames()][:total]
    print(f"full replay: {len(frames)} frames in {time.monotonic() - start:.1f} s")
    assert len(frames) == total
    assert frames[:3 * 60 + PARK_FRAMES] == replay(table, settings, 60)
    assert frames == expected(table, settings, points)
    # The scan analysis' numpy model of the same pattern (galvoscan.analysis) is what the
    # gateware emits, so its dose figures speak of the real output.
    model = analysis_spiral_frames(table, dwell=settings.dwell, interpolation="linear")
    assert frames[2:] == list(zip(model.x.tolist(), model.y.tolist()))
    # The pattern closes: the next point would be the first again (its first frame is the
    # table point itself), and the last point's frames walk towards it.
    assert expected(table, settings, points + 1)[-settings.dwell] == frames[2]


@pytest.mark.parametrize("dwell", [1, 2, 5])
@pytest.mark.parametrize("interp", [0, 1])
def test_dwell(dwell, interp):
    table, settings = SpiralTable(), ScanSettings(dwell=dwell, spiral_interp=interp)
    assert replay(table, settings, 150) == expected(table, settings, 150)


def test_held_points():
    """Interpolation off: each point is held for its dwell and the mirror jumps, as before
    interpolation was built; the full pattern's first points are those of the linear replay."""
    table, settings = SpiralTable(), ScanSettings(spiral_interp=0)
    # (On the spiral-only top's scan path, SpiralPath; test_dwell replays held points on the
    # default build's wires.)
    frames = replay(table, settings, 400, path_only=True)
    assert frames == expected(table, settings, 400)
    assert all(frames[i] == frames[i + 1] == frames[i + 2] for i in range(2, len(frames), 3))
    linear = expected(table, ScanSettings(), 400)
    assert frames[2::3] == linear[2::3] and frames != linear


def test_interpolated_frames_walk_between_the_points():
    """Linear: every frame moves; frame k of d is part of the way to the next point, never past
    it, and the points themselves are where and when they were."""
    table, settings = SpiralTable(), ScanSettings(dwell=4, spiral_interp=1)
    frames = replay(table, settings, 100)
    assert frames == expected(table, settings, 100)
    points = frames[2::4]
    assert points == expected(table, ScanSettings(dwell=4, spiral_interp=0), 100)[2::4]
    for i in range(len(points) - 1):
        walk = frames[2 + 4 * i: 2 + 4 * i + 5]
        for axis in (0, 1):
            values = [f[axis] for f in walk]
            assert values == sorted(values) or values == sorted(values, reverse=True)
    assert all(a != b for a, b in zip(frames[2:], frames[3:]))


def test_a_build_without_interpolation_holds_points_and_has_no_register():
    table, settings = SpiralTable(), ScanSettings(dwell=2)
    top = GalvoScanTop(clk_freq=4e6, table=table, settings=settings, spiral_interpolation=False)
    assert "spiral_interp" not in top.regmap
    assert "spiral_interp" in GalvoScanTop(clk_freq=4e6).regmap
    held = expected(table, ScanSettings(dwell=2, spiral_interp=0), 60)
    assert replay(table, settings, 60, spiral_interpolation=False) == held


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow],
          phases=[Phase.explicit, Phase.reuse, Phase.generate])
@given(st.data())
def test_interpolation_over_random_tables_ranges_and_dwells(data):
    """Random tables, address ranges (a wrap from the last address to the first is a long way
    back), gains and dwells (1 … 9, and a long one): the wires equal the model. (On the
    spiral-only top's scan path, :class:`SpiralPath`, without the host link around it.)"""
    points = data.draw(st.sampled_from([8, 16, 32]), label="table points")
    table = SpiralTable(points=points, sampling=data.draw(st.sampled_from(["gaussian", "uniform"])),
                        sigma=data.draw(st.sampled_from([0.3, 1.0, 2.0, 50.0])))
    ranges = []
    for _ in range(2):
        first = data.draw(st.integers(0, points - 1))
        ranges.append((first, data.draw(st.integers(first, points - 1))))
    dwell = data.draw(st.one_of(st.integers(1, 9), st.just(300)), label="dwell")
    count = max(3, min(40, 600 // dwell))
    scan = ScanSettings(dwell=dwell, spiral_interp=data.draw(st.integers(0, 1)),
                        x_range=ranges[0], y_range=ranges[1],
                        amp_x=data.draw(st.integers(0, 65535)),
                        amp_y=data.draw(st.sampled_from([32768, 65535, 1000])),
                        center_x=data.draw(st.integers(0, 65535)), center_y=32768)
    assert replay(table, scan, count, path_only=True) == \
        expected(table, scan, count)


def test_ranges_gain_centre_and_saturation():
    table = SpiralTable(sampling="uniform")
    settings = ScanSettings(dwell=2, x_range=(10, 20), y_range=(3, 40), amp_x=50000,
                            amp_y=16384, center_x=60000, center_y=1000)
    frames = replay(table, settings, 120)
    assert frames == expected(table, settings, 120)
    # The X axis was pushed past the edge: it sits at 65535, it never wraps to small values.
    assert max(x for x, _ in frames) == 65535
    assert min(x for x, _ in frames[PARK_FRAMES:]) > 32768


def test_smaller_table():
    table = SpiralTable(points=64, sigma=0.5)
    settings = ScanSettings(dwell=1, x_range=(0, 63), y_range=(1, 62))
    assert replay(table, settings, 400) == expected(table, settings, 400)


def test_board_clock_ratio_gives_the_same_frames():
    """At the iCEBreaker's 12 MHz (6 clocks per bit) the wires carry the same frames."""
    table, settings = SpiralTable(), ScanSettings()
    assert replay(table, settings, 60, clocks_per_bit=6) == expected(table, settings, 60)


def test_stopped_scanner_stays_parked():
    table, settings = SpiralTable(), ScanSettings(run=False)
    assert replay(table, settings, 20) == [PARK] * (PARK_FRAMES + 60)


def test_top_with_a_512_point_table():
    """A top built for a 512-point table takes the table's whole address range (the register
    map's ranges come from the build) and its wires carry the model's spiral."""
    table = SpiralTable(points=512)
    settings = ScanSettings(dwell=1, x_range=(0, 511), y_range=(1, 510))
    top = GalvoScanTop(clk_freq=4e6, table=table, settings=settings)
    assert top.regmap["x_last"].high == 511 and top.regmap["y_last"].reset == 510
    assert replay(table, settings, 40) == expected(table, settings, 40)


def test_source_select_checks_its_modes():
    from galvoscan.gateware.host.regmap import Mode
    from galvoscan.gateware.sources.select import SourceSelect
    assert len(SourceSelect([Mode.SPIRAL, Mode.VECTOR]).sources) == 2
    for modes in ([], [Mode.SPIRAL, Mode.SPIRAL], ["spiral"]):
        with pytest.raises(ValueError, match="modes must be distinct Mode members"):
            SourceSelect(modes)
