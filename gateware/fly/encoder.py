"""Quadrature encoders for marking on the fly: the belt's (or a rotary table's) position.

An incremental encoder gives two square waves, A and B, a quarter period apart. Each edge of
either is one count (×4 decoding: four counts an increment of the encoder's disc), and
which of the two leads says the direction. RTC5 and RTC6 take two such inputs (ENCODER X, Y)
at up to 4 MHz of counts, and have a simulated encoder for trials without a belt.
"""

from amaranth.hdl import Cat, Const, Module, Signal, signed
from amaranth.lib import wiring
from amaranth.lib.cdc import FFSynchronizer
from amaranth.lib.wiring import In, Out


__all__ = ["QUADRATURE_CYCLE", "COUNT_BITS", "ILLEGAL_BITS", "QuadratureDecoder",
           "SimulatedEncoder"]


#: The lines' states ``(A, B)`` in the order an encoder turning forward (counting up) passes
#: them: A leads B. Backward is the same cycle read the other way.
QUADRATURE_CYCLE = ((0, 0), (1, 0), (1, 1), (0, 1))
#: Bits of a count: signed, as the RTC's.
COUNT_BITS = 32
#: Bits of the count of illegal transitions (both lines changing between two samples).
ILLEGAL_BITS = 16


def _state(a, b):
    return a | (b << 1)


class QuadratureDecoder(wiring.Component):
    """One encoder's A/B lines as a signed count of edges (×4 decoding).

    Each line goes through its own two-flip-flop synchroniser; the decoder compares each
    clock's sample with the last one. One line changing is one count, up when the state moved
    forward through :data:`QUADRATURE_CYCLE` (A leads B), down when backward. Both lines
    changing between two samples is **illegal**: the encoder moved more than one edge in a
    clock, or noise hit a line. The count is then left as it was (its direction cannot be
    known, and a guess would move the marks) and :attr:`illegal` counts it. So at the
    12 MHz clock the inputs may carry up to 6 M counts a second, above the RTC's 4 MHz.

    The count saturates at the ends of its bits rather than wrap (at 4 M counts a second
    that is nine minutes of one direction: a job's fly offset starts from :attr:`clear`); the
    illegal count saturates at its 16 bits.

    Parameters
    ----------
    count_bits : int
        Bits of :attr:`count` (the RTC's 32; fewer only for the proofs' bounded checks,
        which must reach its ends).

    Interface attributes
    --------------------
    a, b : ``In(1)``
        The encoder's lines (asynchronous).
    clear : ``In(1)``
        Zero :attr:`count` and :attr:`illegal` (a job's start, ``fly_return``); an edge on
        the same clock is not counted.
    count : ``Out(signed(count_bits))``
        Edges counted, up minus down, two clocks after they reach the pins and one after
        the sample.
    illegal : ``Out(16)``
        Illegal transitions seen since the last :attr:`clear`.
    """

    def __init__(self, *, count_bits=COUNT_BITS):
        if not isinstance(count_bits, int) or isinstance(count_bits, bool) or \
                not 2 <= count_bits <= 64:
            raise ValueError(f"count_bits must be a whole number from 2 to 64, not "
                             f"{count_bits!r}")
        super().__init__({"a": In(1), "b": In(1), "clear": In(1),
                          "count": Out(signed(count_bits)), "illegal": Out(ILLEGAL_BITS)})
        #: The lines as sampled after the synchroniser, ``A | B << 1`` (for the spec).
        self.sampled = Signal(2)
        #: The sample before it (for the spec).
        self.previous = Signal(2, reset_less=True)

    def elaborate(self, platform):
        m = Module()
        m.submodules.sync = FFSynchronizer(Cat(self.a, self.b), self.sampled)
        # The last sample is never reset, so that the first comparison after a reset is with
        # the lines as they were, not with a made-up state (which could count a phantom edge).
        m.d.sync += self.previous.eq(self.sampled)

        forward, backward, illegal = self._steps(m)
        top, bottom = self._limits()
        with m.If(self.clear):
            m.d.sync += [self.count.eq(0), self.illegal.eq(0)]
        with m.Else():
            with m.If(forward & (self.count != top)):
                m.d.sync += self.count.eq(self.count + 1)
            with m.Elif(backward & (self.count != bottom)):
                m.d.sync += self.count.eq(self.count - 1)
            with m.If(illegal & (self.illegal != 2 ** ILLEGAL_BITS - 1)):
                m.d.sync += self.illegal.eq(self.illegal + 1)
        return m

    def _steps(self, m):
        """``(forward, backward, illegal)``: what the last two samples say, this clock."""
        forward, backward = Signal(), Signal()
        for k, (a, b) in enumerate(QUADRATURE_CYCLE):
            ahead, behind = QUADRATURE_CYCLE[(k + 1) % 4], QUADRATURE_CYCLE[k - 1]
            with m.If(self.previous == _state(a, b)):
                m.d.comb += [forward.eq(self.sampled == _state(*ahead)),
                             backward.eq(self.sampled == _state(*behind))]
        illegal = Signal()
        m.d.comb += illegal.eq((self.sampled ^ self.previous) == 0b11)
        return forward, backward, illegal

    def _limits(self):
        """The count's ends, where it stops."""
        bits = len(self.count)
        return (Const(2 ** (bits - 1) - 1, signed(bits)), Const(-2 ** (bits - 1), signed(bits)))


class SimulatedEncoder(wiring.Component):
    """An encoder of the board's own, for trials without a belt (the RTC's runs at 1 MHz of
    counts): A/B lines that step one state through :data:`QUADRATURE_CYCLE` every
    :attr:`period` clocks, forward (or backward with :attr:`reverse`) while :attr:`enable`.

    Parameters
    ----------
    period_bits : int
        Bits of :attr:`period` (16: down to 183 counts a second at 12 MHz).

    Interface attributes
    --------------------
    enable : ``In(1)``
        Run; while low the lines hold their state.
    reverse : ``In(1)``
        Count down.
    period : ``In(period_bits)``
        Clocks a count (2 or more: a decoder must see every state; 0 and 1 are taken as 2).
    a, b : ``Out(1)``
        The lines, registered.
    """

    def __init__(self, *, period_bits=16):
        if not isinstance(period_bits, int) or not 2 <= period_bits <= 32:
            raise ValueError(f"period_bits must be a whole number from 2 to 32, not "
                             f"{period_bits!r}")
        super().__init__({"enable": In(1), "reverse": In(1), "period": In(period_bits),
                          "a": Out(1), "b": Out(1)})

    def elaborate(self, platform):
        m = Module()
        phase = Signal(2)               # the position in QUADRATURE_CYCLE
        waited = Signal.like(self.period)
        due = Signal()
        m.d.comb += due.eq((waited + 1 >= self.period) & (waited >= 1))
        with m.If(~self.enable):
            m.d.sync += waited.eq(0)
        with m.Elif(due):
            m.d.sync += [waited.eq(0), phase.eq(phase + Cat(1, self.reverse))]
        with m.Else():
            m.d.sync += waited.eq(waited + 1)
        # The cycle's states in order are the Gray code of the phase.
        m.d.sync += [self.a.eq(phase[0] ^ phase[1]), self.b.eq(phase[1])]
        return m
