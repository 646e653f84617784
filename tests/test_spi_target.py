# amaranth: UnusedElaboratable=no
"""The SPI target alone (gateware/host/spi_target.py), driven by a mode-0 host written here:
SCK idles low, the host sets COPI while SCK is low and both sides sample on the rising edge.
Checked against a model of the README's SPI rules: a frame is exactly what is clocked in while
``cs_n`` is low (reported with its length, so frames that are not 32 bits can be discarded
whole), and a reply is shifted out on CIPO, most significant bit first, during the next frame."""

from amaranth.sim import Simulator
from hypothesis import given, settings, strategies as st
import pytest

from galvoscan.gateware.host.spi_target import SPITarget


HALF = 6            # system clocks per half SCK period: SCK = clk / 12, the stated maximum


def to_bits(word, n=32):
    return [(word >> (n - 1 - i)) & 1 for i in range(n)]


def to_word(bits):
    word = 0
    for b in bits:
        word = word << 1 | b
    return word


def run_target(transactions, *, half=HALF, idle=8):
    """Each transaction is a dict: ``bits`` clocked in; ``reply``, a word offered on
    ``replies`` (held until taken) before ``cs_n`` falls, or None; ``glitch``, (after how many
    bits, clocks) ``cs_n`` goes high in the middle, or None. Returns (frame events, CIPO as the
    host sampled it on each rising edge, per transaction)."""
    dut = SPITarget()
    events, cipo = [], []

    async def host(ctx):
        ctx.set(dut.frames.ready, 1)
        await ctx.tick().repeat(4)
        for t in transactions:
            reply = t.get("reply")
            if reply is not None:
                # Offered as the decoder offers it: held until the target takes it.
                ctx.set(dut.replies.payload, reply)
                ctx.set(dut.replies.valid, 1)
            await ctx.tick().repeat(idle)
            ctx.set(dut.cs_n, 0)
            await ctx.tick().repeat(half)
            seen = []
            glitch = t.get("glitch")
            for i, bit in enumerate(t["bits"] + [None]):
                if glitch is not None and glitch[0] == i:
                    ctx.set(dut.cs_n, 1)
                    await ctx.tick().repeat(glitch[1])
                    ctx.set(dut.cs_n, 0)
                    await ctx.tick().repeat(half)
                if bit is None:
                    break
                ctx.set(dut.copi, bit)
                await ctx.tick().repeat(half)
                seen.append(ctx.get(dut.cipo))       # the host samples as SCK rises
                ctx.set(dut.sck, 1)
                await ctx.tick().repeat(half)
                ctx.set(dut.sck, 0)
            await ctx.tick().repeat(half)
            ctx.set(dut.cs_n, 1)
            cipo.append(seen)
        await ctx.tick().repeat(8)             # the last frame through the synchronisers

    async def reply_taken(ctx):
        while True:
            taken = ctx.get(dut.replies.valid) and ctx.get(dut.replies.ready)
            await ctx.tick()
            if taken:
                ctx.set(dut.replies.valid, 0)

    async def monitor(ctx):
        async for _, _, valid, word, bits in ctx.tick().sample(
                dut.frames.valid, dut.frames.payload.word, dut.frames.payload.bits):
            if valid:
                events.append((word, bits))

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(host)
    sim.add_testbench(monitor, background=True)
    sim.add_testbench(reply_taken, background=True)
    sim.run()
    return events, cipo


def model(transactions):
    """The frame events and CIPO bits the rules call for."""
    events, cipo = [], []
    pending = None
    for t in transactions:
        if t.get("reply") is not None:
            pending = t["reply"]
        bits = t["bits"]
        glitch = t.get("glitch")
        parts = [bits] if glitch is None else [bits[:glitch[0]], bits[glitch[0]:]]
        seen = []
        for part in parts:
            # A frame: the last 32 bits clocked in, and how many (saturating at 33).
            events.append((to_word(part[-32:]), min(len(part), 33)))
            # The waiting reply goes out during it (then zeros); only once.
            out = to_bits(pending) if pending is not None else []
            seen += (out + [0] * len(part))[:len(part)]
            pending = None
        cipo.append(seen)
    return events, cipo


def frame(word, **kw):
    return {"bits": to_bits(word), **kw}


# --- frames ------------------------------------------------------------------------------------

def test_a_32_bit_frame_is_handed_on_whole():
    transactions = [frame(0x04000564), frame(0x81020364), frame(0xFFFFFFFF), frame(0)]
    events, _ = run_target(transactions)
    assert events == [(0x04000564, 32), (0x81020364, 32), (0xFFFFFFFF, 32), (0, 32)]


@pytest.mark.parametrize("n", [0, 1, 8, 24, 31, 33, 34, 40, 64])
def test_frames_of_other_lengths_are_reported_with_their_length(n):
    """Cut short or overlong: the length tells the decoder to drop it whole (over 32 it stops
    counting at 33); the next 32-bit frame is whole again."""
    bits = [(0x5A3C >> (i % 16)) & 1 for i in range(n)]
    events, _ = run_target([{"bits": bits}, frame(0x04000964)])
    assert events == [(to_word(bits[-32:]), min(n, 33)), (0x04000964, 32)]


@pytest.mark.parametrize("half", [6, 7, 10, 25])
def test_sck_at_clk_over_12_and_slower(half):
    transactions = [frame(0x12345678, reply=0x9ABCDEF0), frame(0x0F0F0F0F)]
    assert run_target(transactions, half=half) == model(transactions)


# --- replies on CIPO ------------------------------------------------------------------------------

def test_reply_goes_out_during_the_next_frame_then_zeros():
    transactions = [frame(0x81000064), frame(0x80000064, reply=0x81ABCD64), frame(0x80000064),
                    frame(0x80000064)]
    events, cipo = run_target(transactions)
    assert cipo[0] == [0] * 32                       # nothing waiting: zeros
    assert to_word(cipo[1]) == 0x81ABCD64            # most significant bit first
    assert cipo[2] == [0] * 32 and cipo[3] == [0] * 32   # sent once
    assert [bits for _, bits in events] == [32] * 4


def test_a_reply_waits_for_the_next_frame_and_goes_out_once():
    transactions = [frame(0x80000064, reply=0x22222222), frame(0)]
    _, cipo = run_target(transactions, idle=40)
    assert to_word(cipo[0]) == 0x22222222 and cipo[1] == [0] * 32


def test_a_reply_is_cut_off_by_a_short_frame_and_not_sent_again():
    transactions = [{"bits": [1] * 10, "reply": 0xF0F0F0F0}, frame(0)]
    events, cipo = run_target(transactions)
    assert cipo[0] == to_bits(0xF0F0F0F0)[:10] and cipo[1] == [0] * 32
    assert events == [(0x3FF, 10), (0, 32)]


def test_cipo_after_the_reply_in_a_long_frame_is_zero():
    transactions = [{"bits": [1] * 40, "reply": 0xFFFFFFFF}]
    events, cipo = run_target(transactions)
    assert cipo[0] == [1] * 32 + [0] * 8
    assert events == [(0xFFFFFFFF, 33)]


# --- cs_n glitches --------------------------------------------------------------------------------

def test_a_cs_n_pulse_without_clocks_is_an_empty_frame():
    events, _ = run_target([{"bits": []}, frame(0x04000564)])
    assert events == [(0, 0), (0x04000564, 32)]


@pytest.mark.parametrize("at", [1, 16, 31])
@pytest.mark.parametrize("clocks", [1, 2, 5])
def test_cs_n_glitch_splits_a_frame_into_two_that_are_not_32_bits(at, clocks):
    transactions = [frame(0xDEADBE64, glitch=(at, clocks), reply=0xCAFEF00D),
                    frame(0x04000564)]
    events, cipo = run_target(transactions)
    assert (events, cipo) == model(transactions)
    assert [bits for _, bits in events] == [at, 32 - at, 32]


# --- random transactions -----------------------------------------------------------------------

transaction = st.fixed_dictionaries({
    "bits": st.one_of(st.lists(st.integers(0, 1), min_size=32, max_size=32),
                      st.lists(st.integers(0, 1), max_size=40)),
    "reply": st.one_of(st.none(), st.integers(0, 2 ** 32 - 1)),
}).flatmap(lambda t: st.one_of(
    st.just(t),
    st.tuples(st.integers(0, len(t["bits"])), st.integers(1, 4)).map(
        lambda g: {**t, "glitch": g})))


@settings(max_examples=40, deadline=None)
@given(st.lists(transaction, min_size=1, max_size=5), st.sampled_from([6, 6, 9]),
       st.integers(1, 20))
def test_random_transactions_against_the_model(transactions, half, idle):
    """Random bit streams of any length, 32-bit frames, cs_n glitches, replies waiting for
    their frame, at SCK = clk/12 or slower."""
    assert run_target(transactions, half=half, idle=idle) == model(transactions)
