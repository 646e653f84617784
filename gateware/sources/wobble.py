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
register is in Hz: the phase (31 bits, 2^31 to a turn) advances ``f × ⌊2^31 / frame rate⌉`` a
frame, the product made on the same multiplier, so the figure turns at ``f`` to within 10 ppm.
"""

import math

from amaranth.hdl import Module, Mux, Signal, signed
from amaranth.lib import stream, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from ..host.regmap import WOBBLE_MAX_AMPLITUDE, WOBBLE_MAX_HZ, WobbleShape
from ..points import OffsetPoint
from .dda import DIRECTION_BITS, Direction


__all__ = ["Wobble", "PHASE_BITS", "SINE_STEPS", "sine_table"]


#: Bits of the phase accumulator: 2^PHASE_BITS is a turn.
PHASE_BITS = 31
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
    CLOCKS = 10

    def __init__(self, *, frame_rate):
        #: Phase step per Hz and frame, in 2^-31 turns.
        self.phase_per_hz = round(2 ** PHASE_BITS / frame_rate)
        if not 0 < self.phase_per_hz < 2 ** 15 or WOBBLE_MAX_HZ > frame_rate / 4:
            raise ValueError(f"the wobble stage needs a frame rate from {4 * WOBBLE_MAX_HZ} to "
                             f"{2 ** PHASE_BITS} frames/s, not {frame_rate!r}")
        self.frame_rate = frame_rate
        super().__init__()

    def elaborate(self, platform):
        m = Module()
        m.submodules.sines = sines = Memory(shape=_SINE_BITS, depth=SINE_STEPS // 4,
                                            init=sine_table())
        sine = sines.read_port()
        quarter_bits = (SINE_STEPS // 4).bit_length() - 1

        # One multiplier, shared (one DSP): operands on one clock, product on the next.
        mul_a = Signal(16)
        mul_b = Signal(16)
        product = Signal(32)
        m.d.sync += product.eq(mul_a * mul_b)

        phase = Signal(PHASE_BITS)
        step = Signal(range(10))
        busy = Signal()
        wobbling = Signal()                 # this frame's point is marked and the shape is on
        tick = Signal()                     # the clock after a strobe: the sequencer has spoken
        m.d.sync += tick.eq(self.frame_strobe)

        # Sine of the step the phase is in, then its cosine (a quarter turn on): the quarter
        # wave read forwards or backwards, the sign from the half turn.
        index = phase[-10:]
        quadrant = Mux(step == 0, index[quarter_bits:], index[quarter_bits:] + 1)[:2]
        offset_in_quarter = index[:quarter_bits]
        m.d.comb += sine.addr.eq(offset_in_quarter ^ quadrant[0].replicate(quarter_bits))
        negative_sin = Signal()
        negative_cos = Signal()
        # The figure's two terms, magnitudes (below 2^12) and signs.
        along_term = Signal(12)
        across_term = Signal(12)
        along_x = Signal()                  # the along term's sign in x (else -)
        # Offsets · 2^14, accumulated with the sign of each product.
        acc_x = Signal(signed(30))
        acc_y = Signal(signed(30))
        subtract = Signal()
        to_x = Signal()
        d = self.direction
        m.d.sync += step.eq(Mux(busy, step + 1, 0))

        with m.Switch(step):
            with m.Case(0):
                m.d.sync += [negative_sin.eq(quadrant[1]), acc_x.eq(0), acc_y.eq(0)]
            with m.Case(1):
                m.d.sync += negative_cos.eq(quadrant[1])
                m.d.comb += [mul_a.eq(Mux(wobbling, self.along, 0)), mul_b.eq(sine.data)]
            with m.Case(2):
                m.d.comb += [mul_a.eq(Mux(wobbling, self.across, 0)), mul_b.eq(sine.data)]
                m.d.sync += along_term.eq(product[_SINE_BITS:])
            with m.Case(3):
                m.d.comb += [mul_a.eq(along_term), mul_b.eq(d.ux)]
                m.d.sync += across_term.eq(product[_SINE_BITS:])
            with m.Case(4):             # x += along · sin · ux
                m.d.comb += [mul_a.eq(across_term), mul_b.eq(d.uy),
                             subtract.eq(negative_sin ^ d.negative_x), to_x.eq(1)]
            with m.Case(5):             # x -= across · cos · uy
                m.d.comb += [mul_a.eq(along_term), mul_b.eq(d.uy),
                             subtract.eq(~(negative_cos ^ d.negative_y)), to_x.eq(1)]
            with m.Case(6):             # y += along · sin · uy
                m.d.comb += [mul_a.eq(across_term), mul_b.eq(d.ux),
                             subtract.eq(negative_sin ^ d.negative_y)]
            with m.Case(7):             # y += across · cos · ux
                m.d.comb += [mul_a.eq(self.frequency), mul_b.eq(self.phase_per_hz),
                             subtract.eq(negative_cos ^ d.negative_x)]
            with m.Case(8):             # the next frame's phase
                m.d.sync += phase.eq(Mux(wobbling, phase + product, 0))
        with m.If((step >= 4) & (step <= 7)):
            term = Mux(subtract, -product[:27], product[:27])
            with m.If(to_x):
                m.d.sync += acc_x.eq(acc_x + term)
            with m.Else():
                m.d.sync += acc_y.eq(acc_y + term)

        # The point with its offset, clamped at the field's edge.
        base = self.line_points.payload
        with m.If(self.points.ready):
            m.d.sync += self.points.valid.eq(0)
        with m.If(step == 8):
            m.d.sync += busy.eq(0)
            for axis, acc in (("x", acc_x), ("y", acc_y)):
                total = Signal(signed(18), name=f"total_{axis}")
                m.d.comb += total.eq(getattr(base, axis) + (acc >> DIRECTION_BITS))
                low, high = -2 ** 15, 2 ** 15 - 1
                m.d.sync += getattr(self.points.payload, axis).eq(
                    Mux(total < low, low, Mux(total > high, high, total)))
                with m.If((total < low) | (total > high)):
                    m.d.comb += self.clipped.eq(1)
            m.d.sync += self.points.valid.eq(1)

        # At the clock after a strobe: a new point, or a marked point held while the shape is
        # on, gives this frame a position.
        m.d.comb += self.line_points.ready.eq(tick)
        with m.If(tick):
            on = (self.shape == WobbleShape.ELLIPSE) & self.marking
            m.d.sync += wobbling.eq(on)
            # The first frame after wobbling goes back to the point itself.
            with m.If(self.line_points.valid | on | wobbling):
                m.d.sync += busy.eq(1)
            with m.Elif(~on):
                m.d.sync += phase.eq(0)
        return m
