"""The encoders of marking on the fly, as properties of the count a decoder keeps."""

from amaranth.asserts import AnySeq
from amaranth.hdl import (Assert, ClockDomain, Cover, Elaboratable, Module, ResetSignal,
                          Signal, signed)

from ..gateware.fly.encoder import ILLEGAL_BITS


__all__ = ["QuadratureSpec"]


#: Where each state of the lines ``(A, B)`` lies in a turn of the disc, in edges forward.
_EDGE_OF = {(0, 0): 0, (1, 0): 1, (1, 1): 2, (0, 1): 3}


class QuadratureSpec(Elaboratable):
    """A quadrature decoder's count, for every sequence of its lines, clears and resets.

    The lines, ``clear`` and the reset are free on every clock. The spec keeps its own count
    from the decoder's samples: between two samples the disc moved by the difference of their
    places in a turn (:data:`_EDGE_OF`), modulo 4: one edge forward is +1, one back is −1, none
    is 0, and two (both lines changed) cannot be told from two the other way, so it moves
    nothing and is an illegal transition. Proved:

    * **count**: the decoder's count is the spec's: it moves at most one edge a clock, only
      in the direction the lines went, and stops at the ends of its bits: it never wraps;
    * **illegal**: its illegal count is the spec's: every two-edge step is counted (up to
      its 16 bits) and moves nothing;
    * **clear**, **reset**: both zero the two counts; the first step after a reset is read
      against the lines as they were (no phantom edge).
    """

    def __init__(self, decoder):
        self.decoder = decoder

    def elaborate(self, platform):
        m = Module()
        m.domains.sync = ClockDomain()
        m.submodules.dut = dut = self.decoder
        m.d.comb += [ResetSignal("sync").eq(AnySeq(1)), dut.a.eq(AnySeq(1)),
                     dut.b.eq(AnySeq(1)), dut.clear.eq(AnySeq(1))]

        # The sample before, as the spec remembers it (kept across a reset, as the lines are).
        previous = Signal(2, reset_less=True)
        m.d.sync += previous.eq(dut.sampled)
        step = Signal(signed(3))
        two_edges = Signal()
        with m.Switch(dut.sampled << 2 | previous):
            for (a0, b0), before in _EDGE_OF.items():
                for (a1, b1), after in _EDGE_OF.items():
                    with m.Case((a1 | b1 << 1) << 2 | (a0 | b0 << 1)):
                        moved = (after - before) % 4
                        m.d.comb += [step.eq({0: 0, 1: 1, 2: 0, 3: -1}[moved]),
                                     two_edges.eq(moved == 2)]

        bits = len(dut.count)
        top, bottom = 2 ** (bits - 1) - 1, -2 ** (bits - 1)
        count = Signal(signed(bits + 2))
        illegal = Signal(ILLEGAL_BITS + 1)
        wide = Signal(signed(bits + 2))
        m.d.comb += wide.eq(count + step)
        with m.If(dut.clear):
            m.d.sync += [count.eq(0), illegal.eq(0)]
        with m.Else():
            with m.If(wide > top):
                m.d.sync += count.eq(top)
            with m.Elif(wide < bottom):
                m.d.sync += count.eq(bottom)
            with m.Else():
                m.d.sync += count.eq(wide)
            with m.If(two_edges & (illegal != 2 ** ILLEGAL_BITS - 1)):
                m.d.sync += illegal.eq(illegal + 1)

        m.d.comb += Assert(dut.previous == previous,
                           "the decoder compares each sample with the last")
        m.d.comb += Assert(dut.count == count,
                           "the count follows the lines edge by edge and never wraps")
        m.d.comb += Assert(dut.illegal == illegal,
                           "a two-edge step is counted as illegal and moves nothing")
        m.d.comb += Cover((dut.count == -2) & (dut.illegal == 1))
        return m
