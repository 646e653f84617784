"""Wobble: a small ellipse laid over the marked points of vector mode (SCANLAB's RTC calls it
wobbel; used to widen a welding or cleaning track).

While a marked point is held for its laser pulses, the stage sends the head a new position every
frame: the point plus the figure's offset at the frame's phase::

    offset = along · sin θ · u + across · cos θ · n,     θ = 2π · f · t

``u`` is the unit vector of the point's line (:class:`~.dda.LineDDA` works it out with the
line's steps), ``n`` is ``u`` turned a quarter to the left, ``along`` and ``across`` are the
amplitudes in galvo units and ``t`` counts frames from the first marked point of a mark: every
mark (after a jump, a stop, an underrun or a stall) starts at ``θ = 0``, one ``across`` to the
left of its first point, and the first frame after it that is not marked goes back to the point. Equal amplitudes give a circle, whatever the direction. Jump points, and every
point while the shape is off, pass unchanged, a frame's point as the sequencer gave it: the
pacer's timing (which frame a point reaches the head, how many pulses it gets) is not touched.

The arithmetic is cheap in cells: sines from a quarter-wave table in one block RAM (1024 steps a
turn, each sample at the middle of its step), and the seven products of a frame (two for the
figure, four to turn it onto the line, one for the phase step) one after the other through one
16 × 16 multiplier (one DSP), within :attr:`Wobble.CLOCKS` of the frame boundary. The frequency
register is in Hz: the phase (24 bits to a turn) advances ``⌊f × ⌊2^31 / frame rate⌉ / 2^7⌋``
a frame, the product made on the same multiplier, so the figure turns at ``f`` to within
10 ppm from 100 Hz up (0.6 % at 1 Hz).
"""

import math

from amaranth.hdl import Cat, Module, Mux, Signal, signed
from amaranth.lib import stream, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from ..fields import WobbleShape
from ..limits import WOBBLE_MAX_AMPLITUDE, WOBBLE_MAX_HZ
from ..points import OffsetPoint
from .dda import DIRECTION_BITS, Direction


__all__ = ["Wobble", "PHASE_BITS", "SINE_STEPS", "sine_table"]


#: Bits of the phase accumulator: 2^PHASE_BITS is a turn.
PHASE_BITS = 24
# The phase step is made in 2^-31 turns (f × round(2^31 / frame rate) fits the multiplier's
# 30 bits at 25 kHz and keeps its rounding within 10 ppm), then cut to the phase's bits.
_PHASE_SHIFT = 31 - PHASE_BITS
#: Sine samples per turn (a quarter of them stored).
SINE_STEPS = 1024
# Fractional bits of the stored sines.
_SINE_BITS = 15


def sine_table():
    """The stored quarter wave: sin of the middle of each of the first SINE_STEPS / 4 steps,
    in units of 2^-15."""
    quarter = SINE_STEPS // 4
    return [round((2 ** _SINE_BITS - 1) * math.sin(2 * math.pi * (j + 0.5) / SINE_STEPS))
            for j in range(quarter)]


class Wobble(wiring.Component):
    """Lays the wobble figure over marked vector points, between the sequencer and the source
    select.

    Parameters
    ----------
    frame_rate : int or float
        XY2 frames per second (100 000 at XY2-100).

    Interface attributes
    --------------------
    line_points : ``In(stream.Signature(OffsetPoint))``
        The vector sequencer's points, handed on at frame strobes. Its payload is read while the
        point is held (the sequencer keeps it until the next one).
    direction : ``In(Direction)``
        The direction of that point's line (the sequencer holds it with the point).
    marking : ``In(1)``
        The sequencer's laser decision for the frame decided at the last strobe.
    frame_strobe : ``In(1)``
        The PHY's frame strobe.
    shape : ``In(WobbleShape)``; along, across : ``In(12)``; frequency : ``In(15)``
        The ``wob_*`` registers: figure, amplitudes in galvo units, turns per second.
    points : ``Out(stream.Signature(OffsetPoint))``
        To the source select: a point each frame while wobbling, else each point as it came.
    clipped : ``Out(1)``
        One clock when a point with its offset went past the field's edge and was clamped.
    """

    line_points: In(stream.Signature(OffsetPoint))
    direction: In(Direction)
    marking: In(1)
    frame_strobe: In(1)
    shape: In(WobbleShape)
    along: In(range(WOBBLE_MAX_AMPLITUDE + 1))
    across: In(range(WOBBLE_MAX_AMPLITUDE + 1))
    frequency: In(range(WOBBLE_MAX_HZ + 1))
    points: Out(stream.Signature(OffsetPoint))
    clipped: Out(1)

    #: Clocks from a frame strobe to the point being offered on :attr:`points`.
    CLOCKS = 11

    def __init__(self, *, frame_rate):
        self.check_frame_rate(frame_rate)
        #: Phase step per Hz and frame, in 2^-31 turns.
        self.phase_per_hz = round(2 ** (PHASE_BITS + _PHASE_SHIFT) / frame_rate)
        self.frame_rate = frame_rate
        super().__init__()

    @staticmethod
    def check_frame_rate(frame_rate):
        """Raise ValueError unless the stage can run at ``frame_rate`` frames a second: at
        least four frames a turn at the highest frequency (XY2-100's 100 000 and up)."""
        if not isinstance(frame_rate, (int, float)) or not \
                4 * WOBBLE_MAX_HZ <= frame_rate < 2 ** (PHASE_BITS + _PHASE_SHIFT):
            raise ValueError(f"the wobble stage needs at least {4 * WOBBLE_MAX_HZ} frames/s "
                             f"(four frames a turn at {WOBBLE_MAX_HZ} Hz), not {frame_rate!r}")

    def elaborate(self, platform):
        m = Module()
        m.submodules.sines = sines = Memory(shape=_SINE_BITS, depth=SINE_STEPS // 4,
                                            init=sine_table())
        sine = sines.read_port()
        quarter_bits = (SINE_STEPS // 4).bit_length() - 1

        # One multiplier, shared (one DSP): operands on one clock, product on the next. Every
        # operand is a magnitude; the signs are kept beside them and applied when summing.
        mul_a = Signal(16)
        mul_b = Signal(16)
        product = Signal(32)
        m.d.sync += product.eq(mul_a * mul_b)

        phase = Signal(PHASE_BITS)
        step = Signal(range(10))
        busy = Signal()
        wobbling = Signal()                 # this frame's point is marked and the shape is on
        tick = Signal()                     # the clock after a strobe: the sequencer has spoken
        m.d.sync += [tick.eq(self.frame_strobe), step.eq(Mux(busy, step + 1, 0))]

        # Sine of the step the phase is in, then its cosine (a quarter turn on): the quarter
        # wave read forwards or backwards, the sign from the half turn.
        index = phase[-(quarter_bits + 2):]
        quadrant = (index[quarter_bits:] + (step != 0))[:2]
        m.d.comb += sine.addr.eq(index[:quarter_bits] ^ quadrant[0].replicate(quarter_bits))
        negative_sin = Signal()
        negative_cos = Signal()
        # The figure's two terms before turning onto the line: magnitudes below 2^12.
        along_term = Signal(12)
        across_term = Signal(12)

        d = self.direction
        negative = Signal()                 # the sign of this clock's product in the sum
        with m.Switch(step):
            with m.Case(0):
                m.d.sync += negative_sin.eq(quadrant[1])
            with m.Case(1):
                m.d.sync += negative_cos.eq(quadrant[1])
                m.d.comb += [mul_a.eq(self.along), mul_b.eq(sine.data)]
            with m.Case(2):
                m.d.comb += [mul_a.eq(self.across), mul_b.eq(sine.data)]
                m.d.sync += along_term.eq(product[_SINE_BITS:])
            with m.Case(3):
                m.d.comb += [mul_a.eq(along_term), mul_b.eq(d.ux)]
                m.d.sync += across_term.eq(product[_SINE_BITS:])
            with m.Case(4):             # x = along · sin · ux …
                m.d.comb += [mul_a.eq(across_term), mul_b.eq(d.uy),
                             negative.eq(negative_sin ^ d.negative_x)]
            with m.Case(5):             # … - across · cos · uy
                m.d.comb += [mul_a.eq(along_term), mul_b.eq(d.uy),
                             negative.eq(~(negative_cos ^ d.negative_y))]
            with m.Case(6):             # y = along · sin · uy …
                m.d.comb += [mul_a.eq(across_term), mul_b.eq(d.ux),
                             negative.eq(negative_sin ^ d.negative_y)]
            with m.Case(7):             # … + across · cos · ux
                m.d.comb += [mul_a.eq(self.frequency), mul_b.eq(self.phase_per_hz),
                             negative.eq(negative_cos ^ d.negative_x)]

        # The offset, one axis after the other: each term is a product · 2^-14 (the
        # direction's fraction), added or subtracted by its sign in one adder (the
        # complement and a carry in, through an extra low bit).
        offset = Signal(signed(15))
        term = product[DIRECTION_BITS:DIRECTION_BITS + 13]
        first = (step == 4) | (step == 6)
        flip = negative.replicate(len(offset))
        summed = (Cat(1, Mux(first, 0, offset)) + Cat(negative, term ^ flip))[1:]
        with m.If((step >= 4) & (step <= 7)):
            m.d.sync += offset.eq(Mux(wobbling, summed, 0))

        # The point plus its offset, saturated at the field's edge (a sum that overflows 16
        # bits takes the edge nearest to it).
        base = self.line_points.payload
        total = Signal(signed(17))
        m.d.comb += total.eq(Mux(step == 6, base.x, base.y) + offset)
        overflow = total[16] ^ total[15]
        clamped = Mux(overflow, Cat((~total[16]).replicate(15), total[16]), total[:16])
        with m.If(self.points.ready):
            m.d.sync += self.points.valid.eq(0)
        with m.If(step == 6):
            m.d.sync += self.points.payload.x.eq(clamped)
            m.d.comb += self.clipped.eq(overflow)
        with m.If(step == 8):
            m.d.sync += [
                self.points.payload.y.eq(clamped),
                self.points.valid.eq(1),
                busy.eq(0),
                # The next frame's phase (2^-31 turns in the product).
                phase.eq(Mux(wobbling, phase + product[_PHASE_SHIFT:], 0)),
            ]
            m.d.comb += self.clipped.eq(overflow)

        # At the clock after a strobe: a new point, or a marked point held while the shape is
        # on, gives this frame a position.
        m.d.comb += self.line_points.ready.eq(tick)
        with m.If(tick):
            on = (self.shape == WobbleShape.ELLIPSE) & self.marking
            m.d.sync += wobbling.eq(on)
            # The first frame after wobbling goes back to the point itself.
            with m.If(self.line_points.valid | on | wobbling):
                m.d.sync += busy.eq(1)
            with m.Else():
                m.d.sync += phase.eq(0)
        return m
