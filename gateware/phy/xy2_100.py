"""XY2-100 transmitter: galvo positions onto the four-wire scan head bus."""

from fractions import Fraction

from amaranth.hdl import Cat, Const, Module, Mux, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out

from ..points import FIELD_CENTRE, FieldPoint


__all__ = ["XY2Transmitter", "FRAME_BITS", "frame_word", "clocks_per_bit"]


#: Bits in one XY2-100 frame: 3 control bits, 16 data bits, 1 parity bit.
FRAME_BITS = 20


def frame_word(control_bits, data):
    """The 20-bit frame for one axis, bit 19 sent first.

    ``C2 C1 C0 D15 … D0 P``, where ``P`` makes the parity of all 20 bits even. Accepts
    Amaranth values (used by the gateware) as well as integers (for documentation and tools).
    """
    if isinstance(data, int):
        head = (control_bits << 16) | data
        return (head << 1) | (bin(head).count("1") & 1)
    head = Cat(data, Const(control_bits, 3))
    return Cat(head.xor(), head)


def clocks_per_bit(clk_freq, bit_rate):
    """System clocks per XY2 bit; raises :exc:`ValueError` unless it is an even integer ≥ 2.

    Each half of ``xy2_clk`` must last a whole number of system clocks.
    """
    ratio = Fraction(clk_freq) / Fraction(bit_rate)
    if ratio.denominator != 1 or ratio < 2 or ratio.numerator % 2 != 0:
        raise ValueError(
            f"XY2 needs the system clock to be an even integer multiple (at least 2x) of the "
            f"bit rate, so that each half of xy2_clk is a whole number of system clocks; "
            f"{clk_freq:g} Hz / {bit_rate:g} Hz = {float(ratio):g}")
    return int(ratio)


class XY2Transmitter(wiring.Component):
    """XY2-100 transmitter for one X/Y scan head.

    Sends frames back to back, with no idle clock between them: 20 bits at ``bit_rate``, so
    100 000 frames/s (10 µs each) at the standard 2 Mbit/s. Each frame carries one position per
    axis. A new position is taken from :attr:`position` only at a frame boundary; when none is
    offered the last one is sent again. After reset the mirrors are parked at the field centre.

    SYNC, X and Y change together with the rising edge of ``xy2_clk`` (the receiver samples on
    the falling edge, half a bit later). SYNC is high for bits 1-19 and low for the parity bit.
    All outputs come straight from flip-flops, so they do not glitch.

    Parameters
    ----------
    clk_freq : int or float
        System clock frequency in Hz.
    bit_rate : int or float
        XY2 clock frequency in Hz: 2 MHz for XY2-100, 4 MHz for XY2-200. ``clk_freq / bit_rate``
        must be an even integer ≥ 2, since each half of ``xy2_clk`` lasts a whole number of
        system clocks.
    control_bits : int
        The three control bits C2 C1 C0. ``0b001`` (16-bit position) is what scan heads expect;
        the source paper's ``0b000`` is accepted for heads that want it.

    Interface attributes
    --------------------
    position : ``In(stream.Signature(FieldPoint))``
        Positions in galvo units. ``ready`` is high only in the last system clock of a frame.
    frame_strobe : ``Out(1)``
        High for one system clock per frame, when the next frame's position is taken: the
        10 µs base tick of the position sources.
    xy2_clk, xy2_sync, xy2_x, xy2_y : ``Out(1)``
        The bus, single-ended, for an RS-422 driver.
    """

    position: In(stream.Signature(FieldPoint))
    frame_strobe: Out(1)
    xy2_clk: Out(1)
    xy2_sync: Out(1)
    xy2_x: Out(1)
    xy2_y: Out(1)

    def __init__(self, *, clk_freq, bit_rate=2_000_000, control_bits=0b001):
        per_bit = clocks_per_bit(clk_freq, bit_rate)
        if not isinstance(control_bits, int) or not 0 <= control_bits <= 0b111:
            raise ValueError(f"control_bits must be a 3-bit integer, not {control_bits!r}")
        self.clk_freq = clk_freq
        self.bit_rate = bit_rate
        self.control_bits = control_bits
        #: System clocks per XY2 bit.
        self.clocks_per_bit = per_bit
        #: System clocks per frame.
        self.clocks_per_frame = FRAME_BITS * self.clocks_per_bit
        super().__init__()
        # The position of the frame being sent (made here so that the proof's helper
        # invariant can name it).
        self._latched = Signal(FieldPoint, init={"x": FIELD_CENTRE, "y": FIELD_CENTRE})
        self._bit = Signal(range(FRAME_BITS), init=FRAME_BITS - 1)    # bit number, 0 = C2

    @property
    def frame_rate(self):
        """Frames per second."""
        return self.bit_rate / FRAME_BITS

    def elaborate(self, platform):
        m = Module()

        per_bit = self.clocks_per_bit
        # The counters start on the last clock of a frame, so the first frame begins at once.
        tick = Signal(range(per_bit), init=per_bit - 1)        # system clocks into the bit
        bit = self._bit
        bit_end = tick == per_bit - 1
        frame_end = bit_end & (bit == FRAME_BITS - 1)

        m.d.sync += tick.eq(Mux(bit_end, 0, tick + 1))
        with m.If(bit_end):
            m.d.sync += bit.eq(Mux(frame_end, 0, bit + 1))

        # xy2_clk rises as each bit starts and falls halfway through it.
        with m.If(bit_end):
            m.d.sync += self.xy2_clk.eq(1)
        with m.Elif(tick == per_bit // 2 - 1):
            m.d.sync += self.xy2_clk.eq(0)

        # The position for the next frame: a new one if offered now, else the last one.
        latched = self._latched
        next_position = FieldPoint(Mux(self.position.valid, self.position.payload, latched))
        m.d.comb += [
            self.position.ready.eq(frame_end),
            self.frame_strobe.eq(frame_end),
        ]

        shift_x = Signal(FRAME_BITS)
        shift_y = Signal(FRAME_BITS)
        with m.If(frame_end):
            word_x = frame_word(self.control_bits, next_position.x)
            word_y = frame_word(self.control_bits, next_position.y)
            m.d.sync += [
                latched.eq(next_position),
                shift_x.eq(word_x),
                shift_y.eq(word_y),
                self.xy2_x.eq(word_x[-1]),
                self.xy2_y.eq(word_y[-1]),
                self.xy2_sync.eq(1),
            ]
        with m.Elif(bit_end):
            m.d.sync += [
                shift_x.eq(shift_x << 1),
                shift_y.eq(shift_y << 1),
                self.xy2_x.eq(shift_x[-2]),
                self.xy2_y.eq(shift_y[-2]),
                # Low for the parity bit, which is the one after bit 18.
                self.xy2_sync.eq(bit != FRAME_BITS - 2),
            ]

        return m
