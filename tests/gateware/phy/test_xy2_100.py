# amaranth: UnusedElaboratable=no
# (signature and parameter checks build components without elaborating them)

import pytest
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out
from amaranth.sim import Simulator

from galvoscan.gateware.phy.xy2_100 import XY2Transmitter, frame_word
from galvoscan.gateware.points import FieldPoint

from wires import SYNC_PATTERN, frames_from_samples, record_falling_edges


# --- signature and parameters ---------------------------------------------------------------------

def test_signature():
    phy = XY2Transmitter(clk_freq=12_000_000)
    assert phy.signature.members == wiring.SignatureMembers({
        "position": In(stream.Signature(FieldPoint)),
        "frame_strobe": Out(1),
        "xy2_clk": Out(1), "xy2_sync": Out(1), "xy2_x": Out(1), "xy2_y": Out(1),
    })
    assert phy.clocks_per_bit == 6
    assert phy.clocks_per_frame == 120
    assert phy.frame_rate == 100_000


@pytest.mark.parametrize("clk_freq, bit_rate", [
    (12e6, 4e6),        # ratio 3: odd
    (10e6, 3e6),        # not an integer
    (2e6, 2e6),         # ratio 1
    (1e6, 2e6),         # ratio 1/2
    (25e6, 2e6),        # 12.5
])
def test_bad_clock_ratio(clk_freq, bit_rate):
    with pytest.raises(ValueError, match=r"even integer multiple \(at least 2x\)"):
        XY2Transmitter(clk_freq=clk_freq, bit_rate=bit_rate)


@pytest.mark.parametrize("control_bits", [-1, 8, 1.0, "001"])
def test_bad_control_bits(control_bits):
    with pytest.raises(ValueError, match="control_bits must be a 3-bit integer"):
        XY2Transmitter(clk_freq=12e6, control_bits=control_bits)


def test_xy2_200_ratio():
    assert XY2Transmitter(clk_freq=12e6, bit_rate=4e6 * 1.5).clocks_per_bit == 2
    assert XY2Transmitter(clk_freq=48e6, bit_rate=4e6).frame_rate == 200_000


# --- the paper's figure 7 -------------------------------------------------------------------------

# X = 136 = 0x0088 and Y = 264 = 0x0108, written out by hand from the XY2-100 protocol: control
# bits, 16 data bits MSB first, then a parity bit that makes the count of ones even (three ones
# so far → 1).
FIG7_X = "001" + "0000000010001000" + "1"
FIG7_Y = "001" + "0000000100001000" + "1"
# The paper's own control bits 000: two ones in the data → parity 0.
FIG7_X_000 = "000" + "0000000010001000" + "0"
FIG7_Y_000 = "000" + "0000000100001000" + "0"


def offer_once(phy, x, y):
    async def testbench(ctx):
        ctx.set(phy.position.valid, 1)
        ctx.set(phy.position.payload.x, x)
        ctx.set(phy.position.payload.y, y)
        await ctx.tick().until(phy.position.ready)
        ctx.set(phy.position.valid, 0)
    return testbench


@pytest.mark.parametrize("clocks_per_bit", [2, 6])
@pytest.mark.parametrize("control_bits, want_x, want_y", [
    (0b001, FIG7_X, FIG7_Y),
    (0b000, FIG7_X_000, FIG7_Y_000),
])
def test_figure_7_bit_by_bit(clocks_per_bit, control_bits, want_x, want_y):
    clk_freq = clocks_per_bit * 2e6
    phy = XY2Transmitter(clk_freq=clk_freq, control_bits=control_bits)
    samples = record_falling_edges(phy, clk_freq, frames=3,
                                   extra_testbench=offer_once(phy, 136, 264))
    sync = "".join(str(s) for s, _, _ in samples)
    x = "".join(str(b) for _, b, _ in samples)
    y = "".join(str(b) for _, _, b in samples)
    assert sync == SYNC_PATTERN * 3
    # Offered before the first frame, the pair goes out in it and is then repeated.
    assert x == want_x * 3
    assert y == want_y * 3


def test_frame_word_matches_hand_written_bits():
    assert format(frame_word(0b001, 136), "020b") == FIG7_X
    assert format(frame_word(0b001, 264), "020b") == FIG7_Y


# --- timing on every system clock -----------------------------------------------------------------

def record_every_clock(phy, clk_freq, cycles, testbench=None):
    sim = Simulator(phy)
    sim.add_clock(1 / clk_freq)
    levels = []

    async def watch(ctx):
        # From power-up (before the first clock edge) on.
        for cycle in range(cycles):
            levels.append((ctx.get(phy.xy2_clk), ctx.get(phy.xy2_sync), ctx.get(phy.xy2_x),
                           ctx.get(phy.xy2_y), ctx.get(phy.frame_strobe)))
            await ctx.tick()

    sim.add_testbench(watch)
    if testbench is not None:
        sim.add_testbench(testbench, background=True)
    sim.run()
    return levels


@pytest.mark.parametrize("clocks_per_bit", [2, 4, 6])
def test_clock_edges_and_back_to_back_frames(clocks_per_bit):
    clk_freq = clocks_per_bit * 2e6
    phy = XY2Transmitter(clk_freq=clk_freq)
    frames = 6
    levels = record_every_clock(phy, clk_freq, frames * 20 * clocks_per_bit + 1,
                                offer_once(phy, 0xA5C3, 0x3C5A))
    clk = [lv[0] for lv in levels]
    rises = [i for i in range(1, len(clk)) if clk[i] and not clk[i - 1]]
    falls = [i for i in range(1, len(clk)) if not clk[i] and clk[i - 1]]
    # A continuous clock: a rise every bit, a fall half a bit later.
    assert all(b - a == clocks_per_bit for a, b in zip(rises, rises[1:]))
    assert all(f - r == clocks_per_bit // 2 for r, f in zip(rises, falls))
    # SYNC, X and Y change only on the system clock where xy2_clk rises.
    for i in range(1, len(levels)):
        if levels[i][1:4] != levels[i - 1][1:4]:
            assert i in rises, f"data changed at clock {i}, not on a rising xy2_clk"
    # SYNC rises every 20 bits, with no idle clock: frames back to back.
    sync = [lv[1] for lv in levels]
    sync_rises = [i for i in range(1, len(sync)) if sync[i] and not sync[i - 1]]
    assert len(sync_rises) == frames
    assert all(b - a == 20 * clocks_per_bit for a, b in zip(sync_rises, sync_rises[1:]))
    # The frame strobe comes once per frame, on the clock before SYNC rises.
    strobes = [i for i, lv in enumerate(levels) if lv[4]]
    assert [s + 1 for s in strobes[:frames]] == sync_rises


def test_position_taken_only_at_frame_boundary():
    """A position offered mid-frame waits for the next frame; the running frame is unchanged;
    when nothing is offered the last position repeats."""
    clk_freq = 4e6
    phy = XY2Transmitter(clk_freq=clk_freq)

    async def offer_mid_frame(ctx):
        await ctx.tick().repeat(45)             # into frame 1 (each frame is 40 clocks)
        ctx.set(phy.position.valid, 1)
        ctx.set(phy.position.payload.x, 1234)
        ctx.set(phy.position.payload.y, 65535)
        await ctx.tick().until(phy.position.ready)
        ctx.set(phy.position.valid, 0)

    samples = record_falling_edges(phy, clk_freq, frames=5, extra_testbench=offer_mid_frame)
    assert frames_from_samples(samples) == [
        (32768, 32768), (32768, 32768), (1234, 65535), (1234, 65535), (1234, 65535)]


def test_stream_held_valid_is_taken_each_frame():
    """A source that keeps offering gets one position taken per frame, in order."""
    clk_freq = 4e6
    phy = XY2Transmitter(clk_freq=clk_freq)
    wanted = [(i * 4099 % 65536, 65535 - i * 77) for i in range(6)]

    async def source(ctx):
        for x, y in wanted:
            ctx.set(phy.position.valid, 1)
            ctx.set(phy.position.payload.x, x)
            ctx.set(phy.position.payload.y, y)
            await ctx.tick().until(phy.position.ready)
        ctx.set(phy.position.valid, 0)

    samples = record_falling_edges(phy, clk_freq, frames=7, extra_testbench=source)
    assert frames_from_samples(samples) == wanted + [wanted[-1]]
