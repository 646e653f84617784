# amaranth: UnusedElaboratable=no
"""The XY2-100 status receiver (gateware/phy/xy2_status.py) beside the real transmitter, with a
scan head modelled here from the protocol: it answers each frame on STATUS, changing the line
a little after each rising CLOCK edge, the first bit with the one SYNC rises on."""

import pytest
from amaranth.hdl import Elaboratable, Module
from amaranth.sim import Simulator
from hypothesis import given, settings, strategies as st

from galvoscan.gateware.phy.xy2_100 import XY2Transmitter
from galvoscan.gateware.phy.xy2_status import MISSING_FRAMES, XY2StatusReceiver


CLK_FREQ = 12_000_000


class PhyAndReceiver(Elaboratable):
    def __init__(self):
        self.phy = XY2Transmitter(clk_freq=CLK_FREQ)
        self.receiver = XY2StatusReceiver(clocks_per_bit=self.phy.clocks_per_bit)

    def elaborate(self, platform):
        m = Module()
        m.submodules.phy, m.submodules.receiver = self.phy, self.receiver
        m.d.comb += self.receiver.frame_strobe.eq(self.phy.frame_strobe)
        return m


def status_frame(word, *, code=0b001):
    """The 20 bits a head sends for ``word``: the code, the data, even parity (first first)."""
    bits = [int(c) for c in f"{code:03b}{word:016b}"]
    return bits + [sum(bits) % 2]


def receive(frames, *, delay_clocks=1):
    """The head sends ``frames`` (lists of 20 bits, or None for a frame with the line low: no
    head), one a transmitter frame, its line changing ``delay_clocks`` after each rising CLOCK
    edge. Returns after each frame the receiver's ``(status, missing)``, and the good and bad
    frames counted (the transmitter's first frame, begun at power-up before the head saw a
    SYNC rise, is one more bad frame: the line was low)."""
    top = PhyAndReceiver()
    phy, receiver = top.phy, top.receiver
    after, counts = [], {"good": 0, "bad": 0}

    async def head(ctx):
        frame = -1
        bit = None
        pending = []                     # (clock due, level)
        clock, last_clk, last_sync = 0, 0, 1
        ends = []
        while len(after) < len(frames):
            await ctx.tick()
            clock += 1
            clk, sync = ctx.get(phy.xy2_clk), ctx.get(phy.xy2_sync)
            if clk and not last_clk:
                bit = 0 if (sync and not last_sync) else (None if bit is None else bit + 1)
                if bit == 0:
                    frame += 1
                    if frame > 0:
                        ends.append(clock)
                if bit is not None and 0 <= frame < len(frames):
                    bits = frames[frame]
                    pending.append((clock + delay_clocks, 0 if bits is None else bits[bit]))
                last_sync = sync
            last_clk = clk
            while pending and pending[0][0] <= clock:
                ctx.set(receiver.status_line, pending.pop(0)[1])
            counts["good"] += ctx.get(receiver.good)
            counts["bad"] += ctx.get(receiver.bad)
            if ends and clock == ends[-1] + 8:
                # (Read a few clocks into the next frame: the last bit's sample and check.)
                after.append((ctx.get(receiver.status), ctx.get(receiver.missing)))
                ends.clear()

    sim = Simulator(top)
    sim.add_clock(1 / CLK_FREQ)
    sim.add_testbench(head)
    sim.run()
    return after, counts


def test_a_heads_words_are_taken_frame_by_frame():
    words = [0b1100_1001, 0b1101_1001, 0x0000, 0xFFFF, 0b0100_1001]
    after, counts = receive([status_frame(w) for w in words])
    assert after == [(w, 0) for w in words]
    assert counts == {"good": len(words), "bad": 1}


@pytest.mark.parametrize("delay", [0, 1, 2, 3])
def test_the_heads_delay_within_the_bit(delay):
    after, _ = receive([status_frame(0xA5C3)] * 2, delay_clocks=delay)
    assert after == [(0xA5C3, 0)] * 2


@settings(max_examples=10, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 0xFFFF), st.sampled_from(["ok", "parity", "code",
                                                                   "bit"]),
                          st.integers(0, 19)), min_size=1, max_size=10))
def test_corrupt_frames_are_counted_and_never_taken(cases):
    frames, want = [], []
    status, missing, without = 0, 1, MISSING_FRAMES
    for word, damage, position in cases:
        bits = status_frame(word)
        if damage == "parity":
            bits[19] ^= 1
        elif damage == "code":
            bits = status_frame(word, code=[0b000, 0b011, 0b101, 0b111][position % 4])
        elif damage == "bit":
            bits[position] ^= 1
        frames.append(bits)
        # The model: a frame with the code 001 and even parity is taken; any other is
        # counted, and the eighth in a row without a good one makes the head missing.
        good = bits[:3] == [0, 0, 1] and sum(bits) % 2 == 0
        if good:
            status, missing, without = word, 0, 0
        else:
            without = min(MISSING_FRAMES, without + 1)
            if without == MISSING_FRAMES:
                status, missing = 0, 1
        want.append((status, missing))
    after, counts = receive(frames)
    assert after == want
    assert counts["good"] + counts["bad"] == len(frames) + 1


def test_no_head_is_missing_and_reads_0_and_a_head_gone_becomes_missing():
    after, counts = receive([None] * 3)
    assert after == [(0, 1)] * 3 and counts == {"good": 0, "bad": 4}
    frames = [status_frame(0xC9)] + [None] * MISSING_FRAMES + [status_frame(0xC1)]
    after, _ = receive(frames)
    assert after == [(0xC9, 0)] * MISSING_FRAMES + [(0, 1), (0xC1, 0)]


@pytest.mark.parametrize("per_bit", [2, 3, 5, 6.0, True])
def test_the_clocks_a_bit_are_checked(per_bit):
    with pytest.raises(ValueError, match="clocks a bit"):
        XY2StatusReceiver(clocks_per_bit=per_bit)
