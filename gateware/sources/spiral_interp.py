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
    origin : ``In(1)``
        The position jumps to ``p`` (a table point is shown).
    p : ``In(signed(16))``
        The table point, sampled on ``origin``.
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
        Move one frame on (at most ``d - 1`` times per point, after the division).
    position : ``Out(signed(16))``
        ``p`` plus the displacement after the steps so far.
    """

    origin: In(1)
    p: In(signed(16))
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

        # Restoring division: shift the next dividend bit into the remainder; keep the
        # difference with d if it is not negative. The quotient bits go in already complemented
        # for q < p, so a step adds the quotient's two's complement with no more cells.
        trial = Signal(signed(10))
        m.d.comb += trial.eq(Cat(quotient[15], remainder) - self.frames)
        fits = trial >= 0

        # Bresenham: R (+1 for q < p) more per frame; past d, one unit more this frame.
        sum_error = Signal(9)
        past = Signal(signed(10))
        m.d.comb += [
            sum_error.eq(error + remainder + towards_minus),
            past.eq(sum_error - self.frames),
        ]
        carry = past >= 0

        with m.If(self.origin):
            m.d.sync += self.position.eq(self.p)
        with m.Elif(self.start):
            m.d.sync += [
                towards_minus.eq(negative),
                quotient.eq(difference[:16] ^ Cat(*[negative] * 16)),
                remainder.eq(0),
                error.eq(0),
            ]
        with m.Elif(self.divide):
            m.d.sync += [
                quotient.eq(Cat(fits ^ towards_minus, quotient[:15])),
                remainder.eq(Mux(fits, trial[:8], Cat(quotient[15], remainder[:7]))),
            ]
        with m.Elif(self.step):
            # q < p: the quotient holds ~Q; adding ~Q + (1 - carry) subtracts Q + carry.
            m.d.sync += [
                error.eq(Mux(carry, past[:8], sum_error[:8])),
                self.position.eq(self.position + quotient + (carry ^ towards_minus)),
            ]

        return m
