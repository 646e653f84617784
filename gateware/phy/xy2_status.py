"""XY2-100 status receiver: the scan head's state, sent back on its STATUS line.

Heads with a status channel answer each frame on it, in the frame's own format and timing:
three control bits ``001``, 16 data bits, even parity, framed by the controller's own SYNC and
clocked by its CLOCK (the head changes the line with the rising edge, as the controller changes
X and Y). RTC5/RTC6's ``get_head_status`` reads them: bit 0 = 1, bit 1 = 0, bit 3 PosAck X,
bit 4 PosAck Y, bit 6 Temp OK, bit 7 Power OK; a missing head reads 0.
"""

from amaranth.hdl import Cat, Module, Signal
from amaranth.lib import wiring
from amaranth.lib.cdc import FFSynchronizer
from amaranth.lib.wiring import In, Out

from .xy2_100 import FRAME_BITS


__all__ = ["XY2StatusReceiver", "STATUS_CODE", "MISSING_FRAMES", "HEAD_BITS"]


#: The control bits a status frame starts with (C2 C1 C0): a 16-bit word.
STATUS_CODE = 0b001
#: Frames without a good one after which the head counts as missing (80 µs at XY2-100): one
#: frame hit by noise is counted, not taken for a head gone.
MISSING_FRAMES = 8
#: The head status word's bits, as RTC5/RTC6's ``get_head_status`` has them.
HEAD_BITS = {"one": 0, "zero": 1, "pos_ack_x": 3, "pos_ack_y": 4, "temp_ok": 6, "power_ok": 7}


class XY2StatusReceiver(wiring.Component):
    """The head's STATUS line, read in step with the transmitter's frames, checked as strictly
    as a head checks ours: a frame is taken only with the code ``001`` and even parity over its
    20 bits.

    The line goes through a two-flip-flop synchroniser. Each bit is sampled on the last clock
    of its bit time, counted from :attr:`frame_strobe` (the transmitter's: the frame's first
    bit starts on the next clock), which reads the line two clocks before: ``clocks_per_bit -
    2`` clocks after the head's rising edge, time for its driver and the cable.

    Parameters
    ----------
    clocks_per_bit : int
        System clocks per XY2 bit, the transmitter's (at least 4, so that the sample, two
        clocks late, falls in the second half of the bit).
    missing_frames : int
        Frames refused in a row that make the head missing (:data:`MISSING_FRAMES`; fewer
        only for the proof's bounded checks).

    Interface attributes
    --------------------
    status_line : ``In(1)``
        The head's STATUS line (asynchronous; a receiver's output, low with no head).
    frame_strobe : ``In(1)``
        The transmitter's :attr:`~.xy2_100.XY2Transmitter.frame_strobe`.
    status : ``Out(16)``
        The data bits of the last frame taken; 0 while :attr:`missing`.
    missing : ``Out(1)``
        No frame taken in the last ``missing_frames`` frames (and from reset until one is).
    good, bad : ``Out(1)``
        High for one clock as a frame is taken, or refused.
    """

    def __init__(self, *, clocks_per_bit, missing_frames=MISSING_FRAMES):
        if not isinstance(clocks_per_bit, int) or isinstance(clocks_per_bit, bool) or \
                clocks_per_bit < 4 or clocks_per_bit % 2:
            raise ValueError(f"the status receiver needs an even number of clocks a bit, 4 or "
                             f"more, not {clocks_per_bit!r}")
        if not isinstance(missing_frames, int) or isinstance(missing_frames, bool) or \
                not 1 <= missing_frames <= 255:
            raise ValueError(f"missing_frames must be a whole number from 1 to 255, not "
                             f"{missing_frames!r}")
        self.clocks_per_bit = clocks_per_bit
        self.missing_frames = missing_frames
        super().__init__({"status_line": In(1), "frame_strobe": In(1), "status": Out(16),
                          "missing": Out(1, init=1), "good": Out(1), "bad": Out(1)})
        #: The synchronised line (for the spec).
        self.line = Signal()
        #: The bits sampled so far in this frame, the first (C2) highest once all 20 are in.
        self.bits = Signal(FRAME_BITS)
        # The bit's clocks and the frame's bits sampled (FRAME_BITS: none being received), and
        # the frames since the last one taken (for the spec's helper invariants).
        self._tick = Signal(range(clocks_per_bit))
        self._bit = Signal(range(FRAME_BITS + 1), init=FRAME_BITS)
        self._without = Signal(range(missing_frames + 1), init=missing_frames)

    def elaborate(self, platform):
        m = Module()
        m.submodules.sync = FFSynchronizer(self.status_line, self.line)

        per_bit = self.clocks_per_bit
        tick, bit = self._tick, self._bit
        sample = (tick == per_bit - 1) & (bit != FRAME_BITS)
        # Frames since the last one taken (held at missing_frames).
        without = self._without

        m.d.sync += [self.good.eq(0), self.bad.eq(0)]
        with m.If(bit != FRAME_BITS):
            m.d.sync += tick.eq(tick + 1)
            with m.If(sample):
                m.d.sync += [tick.eq(0), bit.eq(bit + 1), self.bits.eq(Cat(self.line, self.bits))]
        # (The last bit's sample falls on the strobe of the next frame, which restarts the
        # count after it.)
        with m.If(self.frame_strobe):
            m.d.sync += [tick.eq(0), bit.eq(0)]

        word = Cat(self.line, self.bits[:FRAME_BITS - 1])     # the frame, C2 at the top
        taken = self._taken(word)
        with m.If(sample & (bit == FRAME_BITS - 1)):
            with m.If(taken):
                m.d.sync += [self.good.eq(1), without.eq(0), self.missing.eq(0),
                             self.status.eq(self._data(word))]
            with m.Else():
                m.d.sync += self.bad.eq(1)
                # A head lost reads 0, as RTC's reads a missing head: its Power OK and Temp OK
                # are then 0, not the last word's.
                with m.If(without >= self.missing_frames - 1):
                    m.d.sync += [self.missing.eq(1), self.status.eq(0)]
                with m.If(without != self.missing_frames):
                    m.d.sync += without.eq(without + 1)
        return m

    def _taken(self, word):
        """Whether a whole frame ``word`` (C2 at the top) is one to take."""
        return (word[FRAME_BITS - 3:] == STATUS_CODE) & ~word.xor()

    def _data(self, word):
        """The 16 data bits of frame ``word``."""
        return word[1:17]
