"""SPI target (mode 0): command frames from a host microcontroller or an FTDI adapter."""

from amaranth.hdl import Cat, Module, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.cdc import FFSynchronizer
from amaranth.lib.wiring import In, Out

from .frames import FRAME_BITS, CommandFrame


__all__ = ["SPITarget", "MIN_CLOCKS_PER_SCK"]


#: System clocks per SCK period this target supports: 1 MHz SCK at a 12 MHz system clock. The
#: pins cross two synchroniser flip-flops, and CIPO must change after a falling SCK edge and
#: settle before the next rising one, so each half of SCK needs 6 system clocks.
MIN_CLOCKS_PER_SCK = 12


class SPITarget(wiring.Component):
    """SPI mode 0 target: SCK idles low, both sides sample on the rising edge.

    A frame is everything clocked in between ``cs_n`` falling and rising. When ``cs_n`` rises
    the frame is handed on with the number of bits it had (saturating at 33), so the decoder can
    reject a frame cut short or overlong as a whole. All pins pass through
    :class:`~amaranth.lib.cdc.FFSynchronizer`, so SCK may be at most the system clock /
    :data:`MIN_CLOCKS_PER_SCK`.

    A reply (to a read request) is shifted out on CIPO, most significant bit first, during the
    next frame; with no reply waiting, CIPO sends zeros.

    Interface attributes
    --------------------
    sck, cs_n, copi : ``In(1)``
        Pins, asynchronous. ``cs_n`` idles high.
    cipo : ``Out(1)``
        Data to the host; driven all the time (a point-to-point link).
    frames : ``Out(stream.Signature(CommandFrame))``
        One event per ``cs_n`` low period, to be taken on the clock it is offered (the
        command decoder always takes SPI frames at once).
    replies : ``In(stream.Signature(32))``
        Words for the host's next frame: taken as a frame starts (the decoder holds a reply
        until then, and answers no other read over SPI meanwhile).
    """

    sck: In(1)
    cs_n: In(1, init=1)
    copi: In(1)
    cipo: Out(1)
    frames: Out(stream.Signature(CommandFrame))
    replies: In(stream.Signature(32))

    def __init__(self):
        super().__init__()
        # Frame assembly state, made here (not in elaborate) so that the proof harness can state
        # invariants about it: k-induction cannot otherwise bound a frame that lasts for ever.
        self._selected = Signal()                 # cs_n has been seen low
        self._bits = Signal(range(FRAME_BITS + 2))
        self._shift = Signal(FRAME_BITS)

    def elaborate(self, platform):
        m = Module()

        sck, cs_n, copi = Signal(), Signal(init=1), Signal()
        m.submodules.sck_sync = FFSynchronizer(self.sck, sck)
        m.submodules.cs_n_sync = FFSynchronizer(self.cs_n, cs_n, init=1)
        m.submodules.copi_sync = FFSynchronizer(self.copi, copi)

        sck_q = Signal()
        m.d.sync += sck_q.eq(sck)
        sck_rise = sck & ~sck_q
        sck_fall = ~sck & sck_q

        selected, bits, shift = self._selected, self._bits, self._shift
        # The frame handed on is the assembly registers themselves (no copy: 38 logic cells).
        # A next frame clears them a clock after this one is offered at the soonest, and the
        # decoder takes an SPI frame on the clock it is offered.
        m.d.comb += [self.frames.payload.word.eq(shift), self.frames.payload.bits.eq(bits)]

        reply = Signal(32)
        with m.If(self.frames.ready):
            m.d.sync += self.frames.valid.eq(0)

        with m.If(~cs_n & ~selected):
            # Frame start: take the reply, if one is waiting (it waits in the decoder, not in
            # a copy here); its first bit goes out now.
            waiting = self.replies.valid
            m.d.comb += self.replies.ready.eq(1)
            m.d.sync += [selected.eq(1), bits.eq(0), shift.eq(0)]
            m.d.sync += [reply.eq(self.replies.payload & waiting.replicate(32)),
                         self.cipo.eq(self.replies.payload[-1] & waiting)]
        with m.Elif(~cs_n & selected):
            with m.If(sck_rise):
                m.d.sync += shift.eq(Cat(copi, shift))
                with m.If(bits != FRAME_BITS + 1):
                    m.d.sync += bits.eq(bits + 1)
            with m.If(sck_fall):
                m.d.sync += [reply.eq(reply << 1), self.cipo.eq(reply[-2])]
        with m.Elif(cs_n & selected):
            # Frame end: hand it on, whatever its length.
            m.d.sync += [
                selected.eq(0),
                self.frames.valid.eq(1),
                self.cipo.eq(0),
            ]
        return m
