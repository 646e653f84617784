"""Linear interpolation between two spiral points, one axis: a serial divider once per point and
a Bresenham step once per frame.

Frame ``k`` (``0 … d-1``) of a point ``p`` held ``d`` frames, whose successor is ``q``, shows::

    p + sign(q - p) × floor(|q - p| × k / d)

the displacement rounded towards ``p``: the path never overshoots, and it is the same walked
either way. With ``|q - p| = Q·d + R`` (``0 ≤ R < d``) the displacement after ``k`` frames is
``Q·k + floor(R·k / d)``, so each frame adds ``Q``, plus 1 whenever an accumulator of ``R``
steps past ``d`` (Bresenham).

Cells are what the UP5K lacks, so: one division per point (16 clocks, one subtractor) rather
than one per frame or a reciprocal; dwells of up to :data:`MAX_INTERPOLATED_DWELL` frames,
which keeps the remainder, the accumulator and the divisor 8 bits wide; and the magnitude made
without a negation: for ``q < p`` the divider takes ``~(q - p) = |q - p| - 1`` and the missing
1 enters the accumulator as a carry (``|q - p| = Q·d + (R + 1)``, and ``R + 1 ≤ d``).
"""

from amaranth.hdl import Cat, Module, Mux, Signal, signed
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out


__all__ = ["AxisInterpolator", "DIVIDE_CLOCKS", "MAX_INTERPOLATED_DWELL"]


#: Longest dwell, in frames, that is interpolated; a point held longer is held (and jumped
#: from) as without interpolation. 255 frames is 2.55 ms a point, ten times slower than any
#: spiral the analysis finds useful.
MAX_INTERPOLATED_DWELL = 255

#: Clocks ``divide`` must stay high after ``start``: one per quotient bit. A frame is at least
#: 40 clocks (two clocks per XY2 bit), so the quotient is ready long before the first step.
DIVIDE_CLOCKS = 16


class AxisInterpolator(wiring.Component):
    """One axis of the spiral's linear interpolation.

    Interface attributes
    --------------------
    start : ``In(1)``
        Take the way from the position (``p``) to ``q`` as the dividend.
    q : ``In(signed(16))``
        The next table point, sampled on ``start``.
    divide : ``In(1)``
        High for :data:`DIVIDE_CLOCKS` clocks after ``start``: one quotient bit a clock.
    frames : ``In(8)``
        The dwell ``d``, 1 … :data:`MAX_INTERPOLATED_DWELL`, held by the caller from ``start``
        to the point's end.
    step : ``In(1)``
        Move one frame on, after the division: the ``d``-th step lands on ``q`` exactly.
    position : ``Out(signed(16))``
        ``p`` plus the displacement after the steps so far. The position is never loaded: it
        reaches each table point by the last step from the one before (from wherever it was,
        in one step, for the first point after a start).
    """

    start: In(1)
    q: In(signed(16))
    divide: In(1)
    frames: In(8)
    step: In(1)
    position: Out(signed(16))

    def elaborate(self, platform):
        m = Module()

        towards_minus = Signal()            # q < p
        quotient = Signal(16)               # the dividend while dividing, then Q (^ sign)
        remainder = Signal(8)               # partial remainder, then R (< d)
        error = Signal(8)                   # (R + towards_minus)·k mod d: Bresenham's (< d)

        difference = Signal(signed(17))
        m.d.comb += difference.eq(self.q - self.position)
        negative = difference[16]

        # One "add, then take d off if that leaves no less than 0" serves both the restoring
        # division (the remainder doubled plus the next dividend bit) and the Bresenham step
        # (the accumulator plus R, plus 1 for q < p): they never run on the same clock.
        addend = Signal(8)
        carry_in = Signal()
        total = Signal(9)
        past = Signal(signed(10))
        m.d.comb += [
            addend.eq(Mux(self.divide, remainder, error)),
            carry_in.eq(Mux(self.divide, quotient[15], towards_minus)),
            total.eq(addend + remainder + carry_in),
            past.eq(total - self.frames),
        ]
        fits = past >= 0
        kept = Mux(fits, past[:8], total[:8])

        with m.If(self.start):
            m.d.sync += [
                towards_minus.eq(negative),
                quotient.eq(difference[:16] ^ Cat(*[negative] * 16)),
                remainder.eq(0),
                error.eq(0),
            ]
        with m.Elif(self.divide):
            # The quotient bits go in already complemented for q < p, so that a step adds the
            # quotient's two's complement with no more cells.
            m.d.sync += [
                quotient.eq(Cat(fits ^ towards_minus, quotient[:15])),
                remainder.eq(kept),
            ]
        with m.Elif(self.step):
            # q < p: the quotient holds ~Q; adding ~Q + (1 - carry) subtracts Q + carry.
            m.d.sync += [
                error.eq(kept),
                self.position.eq(self.position + quotient + (fits ^ towards_minus)),
            ]

        return m
