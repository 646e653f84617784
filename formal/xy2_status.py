"""The XY2-100 status receiver, as properties of what it takes off the head's STATUS line."""

from amaranth.asserts import AnySeq
from amaranth.hdl import (Assert, ClockDomain, Cover, Elaboratable, Module, ResetSignal,
                          Signal)

from ..gateware.phy.xy2_100 import FRAME_BITS
from ..gateware.phy.xy2_status import STATUS_CODE


__all__ = ["XY2StatusSpec"]


class XY2StatusSpec(Elaboratable):
    """A status receiver, for every level of the STATUS line, every frame strobe (on time,
    early or never) and every reset.

    The spec reads the synchronised line at its own instants: the clocks ``k ×
    clocks_per_bit`` (k = 1 … 20) after a frame strobe, counted by one counter from the
    strobe. Each 20th sample completes a frame; the frame is good if its first three bits are
    ``001`` and its 20 bits have even parity. Proved:

    * **taken**: the receiver takes a frame (``good``) exactly when the spec's frame is good,
      and then its status is that frame's 16 data bits; it refuses (``bad``) exactly the
      others; the status changes on nothing else but a head found missing;
    * **missing**: after the receiver's ``missing_frames`` frames refused in a row, and from
      reset until a frame is taken, the head is missing and its status reads 0.

    Parameters
    ----------
    receiver : a :class:`~galvoscan.gateware.phy.xy2_status.XY2StatusReceiver` (or a broken one)
    helpers : bool
        State the helper invariants tying the receiver's counters and bits to the spec's.
    """

    def __init__(self, receiver, *, helpers=True):
        self.receiver = receiver
        self.helpers = helpers

    def elaborate(self, platform):
        m = Module()
        m.domains.sync = ClockDomain()
        m.submodules.dut = dut = self.receiver
        m.d.comb += [ResetSignal("sync").eq(AnySeq(1)), dut.status_line.eq(AnySeq(1)),
                     dut.frame_strobe.eq(AnySeq(1))]
        per_bit = dut.clocks_per_bit
        missing_frames = dut.missing_frames
        done = FRAME_BITS * per_bit + 1

        # Clocks since the strobe (1 on the clock after it), held at `done` once the frame's
        # last sample is past (and from reset: no frame yet).
        since = Signal(range(done + 1), init=done)
        sampling = Signal()
        m.d.comb += sampling.eq((since != done) & (since % per_bit == 0) & (since != 0))
        with m.If(dut.frame_strobe):
            m.d.sync += since.eq(1)
        with m.Elif(since == FRAME_BITS * per_bit):
            m.d.sync += since.eq(done)
        with m.Elif(since != done):
            m.d.sync += since.eq(since + 1)

        # The frame as the spec samples it, first bit highest.
        bits = Signal(FRAME_BITS)
        with m.If(sampling):
            m.d.sync += bits.eq((bits << 1) | dut.line)
        word = Signal(FRAME_BITS)
        m.d.comb += word.eq((bits << 1) | dut.line)
        complete = sampling & (since == FRAME_BITS * per_bit)
        good = Signal()
        m.d.comb += good.eq((word >> (FRAME_BITS - 3) == STATUS_CODE) & (word.xor() == 0))

        # What must show on the next clock.
        was_complete, was_good, data = Signal(), Signal(), Signal(16)
        m.d.sync += [was_complete.eq(complete), was_good.eq(complete & good),
                     data.eq(word >> 1)]
        refused = Signal(range(missing_frames + 1), init=missing_frames)
        with m.If(complete & good):
            m.d.sync += refused.eq(0)
        with m.Elif(complete & (refused != missing_frames)):
            m.d.sync += refused.eq(refused + 1)
        last_status = Signal(16)
        m.d.sync += last_status.eq(dut.status)
        became_missing = Signal()
        m.d.sync += became_missing.eq(complete & ~good & (refused >= missing_frames - 1))

        m.d.comb += Assert(dut.good == was_good,
                           "a frame is taken exactly when its code is 001 and its parity even")
        m.d.comb += Assert(dut.bad == (was_complete & ~was_good),
                           "every other frame is refused")
        m.d.comb += Assert(~dut.good | (dut.status == data),
                           "a frame taken gives its 16 data bits")
        m.d.comb += Assert(dut.good | became_missing | (dut.status == last_status),
                           "the status changes only when a frame is taken or the head is lost")
        m.d.comb += Assert((refused != missing_frames) | (dut.missing & (dut.status == 0)),
                           "a head refused for its missing frames in a row is missing and reads 0")

        if self.helpers:
            bit, tick = dut._bit, dut._tick
            m.d.comb += [
                Assert(bit <= FRAME_BITS),
                Assert(since <= done),
                Assert(refused <= missing_frames),
                Assert((since == done) == (bit == FRAME_BITS)),
                Assert((since == done) | (since == bit * per_bit + tick + 1)),
                Assert(bits == dut.bits),
                Assert(refused == dut._without),
                Assert(dut.missing == (refused == missing_frames)),
                Assert(dut.missing | (refused != missing_frames)),
                Assert(~dut.missing | (dut.status == 0)),
            ]
        m.d.comb += Cover(dut.good & (dut.status == 0x00C9))
        return m
