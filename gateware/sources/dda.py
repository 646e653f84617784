"""Line interpolation at a fixed pitch (Wan et al. 2018), for vector mode.

From a start point to an end point, the points ``P_k = round(P_0 + k·p·D/|D|)`` for every
``k ≥ 1`` with ``k·p < |D|``, then the end point itself. Each step is one pitch ``p`` along the
line: on the major axis ``p/√(1+m²)`` and on the minor one ``m`` times that (Wan et al.'s DDA,
which swaps the roles of x and y for ``|m| > 1``); rounding is half up. The end point is always hit
exactly and no point repeats: a segment of length ``L`` gives ``⌈L/p⌉`` points, one for a
segment no longer than the pitch, none for a zero-length one.

The per-segment arithmetic is done once, sequentially, at the start of a segment (140 clocks,
while the segment before is still being marked; a segment of one point after another of one
point can make the mirrors wait a frame at 12 MHz, see :class:`VectorSequencer`):

* ``D² = dx² + dy²``, exact, through one shared 16 × 16 multiplier (one DSP);
* ``L = √D²`` to 16 fractional bits (digit by digit, 33 clocks);
* the steps ``|dx|·p/L`` and ``|dy|·p/L`` to 32 fractional bits, one after the other
  (restoring division, 48 clocks each, on the square root's remainder and subtractor).

Then each point costs one clock: the positions are accumulated with 32 fractional bits, and
whether another point fits (``k·p < L``) is decided exactly with integers, by taking the pitch
from the whole part of ``L`` once a point: ``k·p < L`` holds exactly when ``k·p ≤ ⌊L⌋``, or,
when ``D²`` is a perfect square (the root's remainder is zero, ``L`` a whole number), when
``k·p < ⌊L⌋``. The accumulated error stays below 2⁻¹⁵ unit, so a point can differ from the
exact rounding only when the exact value lies that close to a half.

A zero-length segment gives nothing after 6 clocks; one no longer than the pitch gives its end
point after the square root (41 clocks), without the divisions.

Built with ``direction=True`` (for the wobble stage) it also gives the line's direction, the
unit vector ``|dx|/L`` and ``|dy|/L`` to 10 fractional bits (two more divisions, 13 clocks
each, so the set-up takes 166 clocks), kept until the next line longer than the pitch.
"""

from amaranth.hdl import Cat, Const, Module, Mux, Signal, signed, unsigned
from amaranth.lib import data, stream, wiring
from amaranth.lib.wiring import In, Out

from ..points import FieldPoint


__all__ = ["LineDDA", "Segment", "FRACTION_BITS", "DIRECTION_BITS", "Direction",
           "SETUP_CLOCKS", "DIRECTED_SETUP_CLOCKS"]


#: Clocks a segment's set-up takes (above): its first point is offered on the 140th clock,
#: counting the one that takes the segment as the first. The host's planner warns when
#: points come faster than this at the board's clock.
SETUP_CLOCKS = 140
#: The same with the line's direction worked out too (``direction=True``).
DIRECTED_SETUP_CLOCKS = 166


#: Fractional bits of the step and of the accumulated positions.
FRACTION_BITS = 32
# Fractional bits of the line length.
_LENGTH_FRACTION = 16

#: Fractional bits of the direction's components (1024 = 1.0): the wobble figure's few
#: thousand units at most turned onto the line within a few units.
DIRECTION_BITS = 10

#: A line's direction: magnitudes of its unit vector's components and their signs.
Direction = data.StructLayout({
    "ux": unsigned(DIRECTION_BITS + 1), "uy": unsigned(DIRECTION_BITS + 1),
    "negative_x": 1, "negative_y": 1,
})

#: A line to interpolate, in galvo units.
Segment = data.StructLayout({
    "x0": unsigned(16), "y0": unsigned(16),
    "x1": unsigned(16), "y1": unsigned(16),
})


class LineDDA(wiring.Component):
    """Steps along one segment at a time, at the pitch given with it.

    Interface attributes
    --------------------
    segment : ``In(stream.Signature(Segment))``
        The next line; taken when the previous one has given all its points.
    pitch : ``In(16)``
        Galvo units between points, 1 … 65535 (0 is taken as 1); sampled when a segment is
        taken.
    points : ``Out(stream.Signature(FieldPoint))``
        The segment's points after its start, the end point last.
    busy : ``Out(1)``
        A segment is being set up or stepped.
    direction : ``Out(Direction)``, with ``direction=True``
        The direction of the last line longer than the pitch (+X after reset): that of the
        points being given, or, for a line no longer than the pitch, of the line before.

    Parameters
    ----------
    direction : bool
        Work out each line's direction too (:attr:`direction`).
    last : ``Out(1)``
        The point offered is the segment's end point.
    """

    def __init__(self, *, direction=False):
        self.with_direction = bool(direction)
        members = {
            "segment": In(stream.Signature(Segment)),
            "pitch": In(16),
            "points": Out(stream.Signature(FieldPoint)),
            "busy": Out(1),
            "last": Out(1),
        }
        if self.with_direction:
            members["direction"] = Out(Direction, init={"ux": 1 << DIRECTION_BITS})
        super().__init__(members)

    def elaborate(self, platform):
        m = Module()
        F = FRACTION_BITS
        G = _LENGTH_FRACTION

        x1 = Signal(16)
        y1 = Signal(16)
        pitch = Signal(16)
        negative_x = Signal()
        negative_y = Signal()
        ax = Signal(16)            # |dx|
        ay = Signal(16)
        # One 16 × 16 multiplier (one DSP), shared: operands on one clock, product the next.
        mul_a = Signal(16)
        mul_b = Signal(16)
        product = Signal(32)
        m.d.sync += product.eq(mul_a * mul_b)
        phase = Signal(range(3))
        # One remainder and one subtractor serve the square root and both divisions.
        radicand = Signal(34)      # D² (exact), then the zero bits that follow it
        remainder = Signal(36)
        root = Signal(18 + G)      # ⌊L · 2^G⌋ < 2^(17+G)
        steps = Signal(range(64))
        second_axis = Signal()
        step_x = Signal(16 + F)    # per point, units · 2^F, magnitudes
        step_y = Signal(16 + F)
        # Stepping state.
        acc_x = Signal(17 + F)     # position + ½, units · 2^F
        acc_y = Signal(17 + F)
        # Whether another point fits: ⌊L⌋ − k·p, and whether L is a whole number (D² a perfect
        # square), when k·p < L needs ⌊L⌋ − k·p > 0 rather than ≥ 0.
        left = Signal(17)          # L < 65536·√2 < 2^17
        exact = Signal()
        after = Signal(18)         # ⌊L⌋ − (k + 1)·p; bit 17 set when negative
        m.d.comb += after.eq(left - pitch)
        fits = Signal()
        m.d.comb += fits.eq(~after[17] & ~(exact & (after == 0)))

        # Square-root step: bring down two bits, try (root << 2) | 1. Division step: bring
        # down a zero, try the root. Both subtract from the same remainder.
        in_sqrt = Signal()
        brought = Mux(in_sqrt, Cat(radicand[-2:], remainder), remainder << 1)[:37]
        trial = Mux(in_sqrt, Cat(Const(1, 2), root), root)
        trial_fits = brought >= trial
        next_remainder = Mux(trial_fits, brought - trial, brought)[:36]

        # Only the idle state takes a segment.
        m.d.comb += self.busy.eq(~self.segment.ready)

        with m.FSM():
            with m.State("IDLE"):
                m.d.comb += self.segment.ready.eq(1)
                with m.If(self.segment.valid):
                    p = self.segment.payload
                    delta_x = Signal(signed(17))
                    delta_y = Signal(signed(17))
                    m.d.comb += [delta_x.eq(p.x1 - p.x0), delta_y.eq(p.y1 - p.y0)]
                    m.d.sync += [
                        x1.eq(p.x1),
                        y1.eq(p.y1),
                        pitch.eq(Mux(self.pitch == 0, 1, self.pitch)),
                        negative_x.eq(delta_x[16]),
                        negative_y.eq(delta_y[16]),
                        # |d| = (d XOR sign) + sign
                        ax.eq((delta_x[:16] ^ delta_x[16].replicate(16)) + delta_x[16]),
                        ay.eq((delta_y[:16] ^ delta_y[16].replicate(16)) + delta_y[16]),
                        acc_x.eq(Cat(Const(1 << (F - 1), F), p.x0)),   # x0 + ½, for rounding
                        acc_y.eq(Cat(Const(1 << (F - 1), F), p.y0)),
                        phase.eq(0),
                    ]
                    m.next = "SQUARES"
            with m.State("SQUARES"):
                # D² straight into the square root's radicand.
                with m.Switch(phase):
                    with m.Case(0):
                        m.d.comb += [mul_a.eq(ax), mul_b.eq(ax)]
                    with m.Case(1):
                        m.d.comb += [mul_a.eq(ay), mul_b.eq(ay)]
                        m.d.sync += radicand.eq(product)
                    with m.Case(2):
                        m.d.sync += radicand.eq(radicand + product)
                m.d.sync += phase.eq(phase + 1)
                with m.If(phase == 2):
                    m.next = "CHECK"
            with m.State("CHECK"):
                m.d.sync += [remainder.eq(0), root.eq(0), steps.eq(17 + G - 1)]
                with m.If((ax | ay) == 0):
                    m.next = "IDLE"                        # zero length: no point
                with m.Else():
                    m.next = "SQRT"
            with m.State("SQRT"):
                m.d.comb += in_sqrt.eq(1)
                m.d.sync += [
                    radicand.eq(radicand << 2),
                    remainder.eq(next_remainder),
                    root.eq(Cat(trial_fits, root)),
                    steps.eq(steps - 1),
                ]
                with m.If(steps == 0):
                    m.next = "COUNT"
            with m.State("COUNT"):
                m.d.sync += [left.eq(root[G:]), exact.eq(remainder == 0),
                             second_axis.eq(0)]
                m.next = "PRODUCT"
            with m.State("PRODUCT"):
                # |dx|·p (then |dy|·p): the division's dividend.
                m.d.comb += [mul_a.eq(Mux(second_axis, ay, ax)), mul_b.eq(pitch)]
                m.next = "LOAD"
                with m.If(~second_axis & ~fits):
                    m.next = "END"                         # one pitch or less: the end only
            with m.State("LOAD"):
                # |dx|·p < L·2^G, so the division starts with the whole product as its
                # remainder; the quotient |dx|·p·2^F / L < p·2^F has 16 + F bits.
                m.d.sync += [remainder.eq(product), steps.eq(16 + F - 1)]
                m.next = "DIVIDE"
            with m.State("DIVIDE"):
                m.d.sync += [remainder.eq(next_remainder), steps.eq(steps - 1)]
                with m.If(second_axis):
                    m.d.sync += step_y.eq(Cat(trial_fits, step_y))
                with m.Else():
                    m.d.sync += step_x.eq(Cat(trial_fits, step_x))
                with m.If(steps == 0):
                    m.d.sync += second_axis.eq(1)
                    with m.If(second_axis):
                        if self.with_direction:
                            m.d.sync += second_axis.eq(0)
                            m.next = "UNIT_LOAD"
                        else:
                            m.next = "NEXT"
                    with m.Else():
                        m.next = "PRODUCT"
            if self.with_direction:
                # The unit vector, |dx|/L then |dy|/L, on the same remainder and subtractor:
                # |dx|·2^(B+1) < L·2^G, so B + 2 quotient bits give |dx|·2^B / L ≤ 2^B.
                B = DIRECTION_BITS
                unit = Signal(B + 2)
                with m.State("UNIT_LOAD"):
                    m.d.sync += [remainder.eq(Mux(second_axis, ay, ax) << (G - 2)),
                                 steps.eq(B + 1)]
                    m.next = "UNIT"
                with m.State("UNIT"):
                    m.d.sync += [remainder.eq(next_remainder), steps.eq(steps - 1),
                                 unit.eq(Cat(trial_fits, unit))]
                    with m.If(steps == 0):
                        m.d.sync += second_axis.eq(1)
                        with m.If(second_axis):
                            m.d.sync += [self.direction.uy.eq(Cat(trial_fits, unit)),
                                         self.direction.negative_x.eq(negative_x),
                                         self.direction.negative_y.eq(negative_y)]
                            m.next = "NEXT"
                        with m.Else():
                            m.d.sync += self.direction.ux.eq(Cat(trial_fits, unit))
                            m.next = "UNIT_LOAD"
            with m.State("NEXT"):
                # Is there a point k·p < L before the end?
                with m.If(fits):
                    m.d.sync += [
                        left.eq(after),
                        # acc ± step as one adder: add the complement and one to subtract.
                        acc_x.eq(acc_x + Cat(step_x ^ negative_x.replicate(len(step_x)),
                                             negative_x.replicate(len(acc_x) - len(step_x)))
                                 + negative_x),
                        acc_y.eq(acc_y + Cat(step_y ^ negative_y.replicate(len(step_y)),
                                             negative_y.replicate(len(acc_y) - len(step_y)))
                                 + negative_y),
                    ]
                    m.next = "STEP"
                with m.Else():
                    m.next = "END"
            with m.State("STEP"):
                m.d.comb += [
                    self.points.valid.eq(1),
                    self.points.payload.x.eq(acc_x[F:F + 16]),
                    self.points.payload.y.eq(acc_y[F:F + 16]),
                ]
                with m.If(self.points.ready):
                    m.next = "NEXT"
            with m.State("END"):
                m.d.comb += [
                    self.points.valid.eq(1),
                    self.last.eq(1),
                    self.points.payload.x.eq(x1),
                    self.points.payload.y.eq(y1),
                ]
                with m.If(self.points.ready):
                    m.next = "IDLE"
        return m
