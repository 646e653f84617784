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
    """XY2-100 transmitter for one X/Y scan head, and optionally its Z channel (a focus shifter
    such as SCANLAB's varioSCAN, on its own data line in the same frame).

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
    z : bool
        Drive a third data line, ``xy2_z``, with :attr:`z` in every frame (the same control
        bits and parity as X and Y).

    Interface attributes
    --------------------
    position : ``In(stream.Signature(FieldPoint))``
        Positions in galvo units. ``ready`` is high only in the last system clock of a frame.
    frame_strobe : ``Out(1)``
        High for one system clock per frame, when the next frame's position is taken: the
        10 µs base tick of the position sources.
    xy2_clk, xy2_sync, xy2_x, xy2_y : ``Out(1)``
        The bus, single-ended, for an RS-422 driver.
    z : ``In(16)``, with ``z``
        The Z channel's position in galvo units (32768: the middle of the focus shifter's
        range), taken with each frame's position, at the frame boundary.
    xy2_z : ``Out(1)``, with ``z``
        The Z data line.
    """

    def __init__(self, *, clk_freq, bit_rate=2_000_000, control_bits=0b001, z=False):
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
        #: The Z channel is driven.
        self.z_axis = bool(z)
        members = {"position": In(stream.Signature(FieldPoint)), "frame_strobe": Out(1),
                   "xy2_clk": Out(1), "xy2_sync": Out(1), "xy2_x": Out(1), "xy2_y": Out(1)}
        if self.z_axis:
            members.update({"z": In(16), "xy2_z": Out(1)})
        super().__init__(members)
        # The position of the frame being sent (made here so that the proof's helper
        # invariant can name it), and its Z.
        self._latched = Signal(FieldPoint, init={"x": FIELD_CENTRE, "y": FIELD_CENTRE})
        self._latched_z = Signal(16, init=FIELD_CENTRE)
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

        # Each data line: its value for the next frame, what it latches, and its wire.
        lines = [(next_position.x, None, self.xy2_x, "x"),
                 (next_position.y, None, self.xy2_y, "y")]
        if self.z_axis:
            lines.append((self.z, self._latched_z, self.xy2_z, "z"))
        with m.If(frame_end):
            m.d.sync += [latched.eq(next_position), self.xy2_sync.eq(1)]
        with m.Elif(bit_end):
            # Low for the parity bit, which is the one after bit 18.
            m.d.sync += self.xy2_sync.eq(bit != FRAME_BITS - 2)
        for value, latch, wire, axis in lines:
            shift = Signal(FRAME_BITS, name=f"shift_{axis}")
            with m.If(frame_end):
                word = frame_word(self.control_bits, value)
                m.d.sync += [shift.eq(word), wire.eq(word[-1])]
                if latch is not None:
                    m.d.sync += latch.eq(value)
            with m.Elif(bit_end):
                m.d.sync += [shift.eq(shift << 1), wire.eq(shift[-2])]

        return m
