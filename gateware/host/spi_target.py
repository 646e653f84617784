"""SPI target (mode 0): command frames from a host microcontroller or an FTDI adapter."""

from amaranth.hdl import Cat, Module, Mux, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.cdc import FFSynchronizer
from amaranth.lib.wiring import In, Out

from .crc import SerialCRC16
from .frames import ANSWER_BYTES, COMMAND_BITS, PAYLOAD_BITS, Answer, CommandFrame


__all__ = ["SPITarget", "MIN_CLOCKS_PER_SCK"]


#: System clocks per SCK period this target supports: 1 MHz SCK at a 12 MHz system clock. The
#: pins cross two synchroniser flip-flops, and CIPO must change after a falling SCK edge and
#: settle before the next rising one, so each half of SCK needs 6 system clocks.
MIN_CLOCKS_PER_SCK = 12

_ANSWER_BITS = ANSWER_BYTES * 8
_DATA_BITS = Answer.size        # an answer's bits before its CRC


class SPITarget(wiring.Component):
    """SPI mode 0 target: SCK idles low, both sides sample on the rising edge.

    A frame is everything clocked in between ``cs_n`` falling and rising. When ``cs_n`` rises
    the frame is handed on: its first :data:`~.frames.PAYLOAD_BITS` bits, and whether it was
    whole (exactly :data:`~.frames.COMMAND_BITS` bits) with a CRC that holds (computed a bit
    a clock as the bits come in). All pins pass through :class:`~amaranth.lib.cdc.FFSynchronizer`,
    so SCK may be at most the system clock / :data:`MIN_CLOCKS_PER_SCK`.

    The answer to a frame is taken between frames (the decoder offers it a few clocks after
    the frame ends) and shifted out on CIPO during the next frame, most significant bit
    first, with its CRC after it (computed as the bits go out); with no answer waiting, CIPO
    sends zeros (whose CRC fails: never an answer). An answer is sent once, in the next
    frame, however short.

    Parameters
    ----------
    kept_bits : int
        Bits of a frame kept and handed on (64: all before the CRC; 32: ``seq``, address and
        data, for a build without vector mode; the rest is handed on as zeros, and checked
        all the same).

    Interface attributes
    --------------------
    sck, cs_n, copi : ``In(1)``
        Pins, asynchronous. ``cs_n`` idles high.
    cipo : ``Out(1)``
        Data to the host; driven all the time (a point-to-point link).
    frames : ``Out(stream.Signature(CommandFrame))``
        One event per ``cs_n`` low period, held until taken (the frame's registers hold
        until the next frame starts).
    replies : ``In(stream.Signature(Answer))``
        Answers for the host's next frame: taken between frames (``ready`` is low while a
        frame is being clocked); a newer one replaces one not yet sent.
    """

    sck: In(1)
    cs_n: In(1, init=1)
    copi: In(1)
    cipo: Out(1)
    frames: Out(stream.Signature(CommandFrame))
    replies: In(stream.Signature(Answer))

    def __init__(self, *, kept_bits=PAYLOAD_BITS):
        if kept_bits not in (32, PAYLOAD_BITS):
            raise ValueError(f"kept_bits must be 32 or {PAYLOAD_BITS}, not {kept_bits!r}")
        self.kept_bits = kept_bits
        super().__init__()
        # Frame assembly state, made here (not in elaborate) so that the proof harness can state
        # invariants about it: k-induction cannot otherwise bound a frame that lasts for ever.
        self._selected = Signal()                 # cs_n has been seen low
        self._bits = Signal(range(COMMAND_BITS + 2))
        self._shift = Signal(kept_bits)
        self._check = SerialCRC16()

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
        m.submodules.check = check = self._check
        # The frame handed on is the assembly registers themselves (no copy): they hold until
        # the next frame starts.
        m.d.comb += [
            self.frames.payload.payload.eq(shift << (PAYLOAD_BITS - len(shift))),
            self.frames.payload.intact.eq((bits == COMMAND_BITS) & (check.crc == 0)),
        ]

        # --- the answer out ------------------------------------------------------------------
        m.submodules.answer_check = answer_check = SerialCRC16()
        answer = Signal(_DATA_BITS)
        answered = Signal()                       # an answer waits, or is going out
        sent = Signal(range(_ANSWER_BITS + 1))    # its bits gone out
        m.d.comb += self.cipo.eq(answered & Mux(sent < _DATA_BITS, answer[-1],
                                                answer_check.crc[15]))

        with m.If(self.frames.ready):
            m.d.sync += self.frames.valid.eq(0)

        m.d.comb += self.replies.ready.eq(~selected)
        with m.If(self.replies.valid & ~selected):
            m.d.sync += [answer.eq(self.replies.payload), answered.eq(1)]

        with m.If(~cs_n & ~selected):
            # Frame start: the answer waiting, if any, goes out from now (its first bit is on
            # CIPO already).
            m.d.comb += [check.clear.eq(1), answer_check.clear.eq(1)]
            m.d.sync += [selected.eq(1), bits.eq(0), shift.eq(0), sent.eq(0),
                         self.frames.valid.eq(0)]
        with m.Elif(~cs_n & selected):
            with m.If(sck_rise):
                m.d.comb += [check.enable.eq(1), check.bit.eq(copi)]
                with m.If(bits < self.kept_bits):
                    m.d.sync += shift.eq(Cat(copi, shift))
                with m.If(bits != COMMAND_BITS + 1):
                    m.d.sync += bits.eq(bits + 1)
            with m.If(sck_fall & (sent != _ANSWER_BITS)):
                m.d.sync += sent.eq(sent + 1)
                with m.If(sent < _DATA_BITS):
                    m.d.comb += [answer_check.enable.eq(1), answer_check.bit.eq(answer[-1])]
                    m.d.sync += answer.eq(answer << 1)
                with m.Else():
                    m.d.comb += answer_check.shift.eq(1)
        with m.Elif(cs_n & selected):
            # Frame end: hand it on, whatever its length.
            m.d.sync += [selected.eq(0), self.frames.valid.eq(1), answered.eq(0)]
        return m
