"""The RTC's laser delays on vector mode's modulation (SCANLAB RTC5/6 manuals: LaserOn and
LaserOff delays; EzCad's "open" and "close" TC).

The vector sequencer decides each frame's laser at the frame strobe that hands its point on;
that point reaches the head two frames later. Without delays the modulation follows the
decision exactly then. Here a rising edge of the decision comes out ``on_delay`` µs after that
moment (negative: before it, down to one µs after the decision), a falling edge ``off_delay`` µs
after it, each placed to the clock: an edge ``d`` µs late comes ``d × clk_freq / 1 MHz`` clocks
late. Counted in µs by one prescaler held in step with the frames, so no multiplier.

Each edge waits in a counter of its own, so a short mark still shines between its delayed
edges. When edges come out of order (a mark's falling edge due before its own rising one,
or the next mark's rising edge due before this one's falling one), the edge decided later wins
and the stale one is dropped: a mark shorter than ``on_delay - off_delay`` never lights. One
edge of each direction waits at a time; a newer one replaces it (only a config that breaks
the RTC's own rule, laser-off delay shorter than mark delay + jump delay + laser-on delay,
gets there).
"""

from amaranth.hdl import Module, Signal, signed
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from ..limits import LASER_ON_LEAD_US


__all__ = ["LaserDelays"]


class LaserDelays(wiring.Component):
    """Delays the rising and falling edges of a frame-timed laser decision.

    Parameters
    ----------
    clocks_per_us : int
        System clocks per µs (the clock must be a whole number of MHz).
    lead_us : int
        µs from a decision to the moment its frame reaches the head (two frames).

    Interface attributes
    --------------------
    frame_strobe : ``In(1)``
        The PHY's frame strobe; decisions change on the clock after it.
    run : ``In(1)``
        Low: the output goes low at once and waiting edges are dropped.
    decision : ``In(1)``
        The laser the sequencer wants for the frame it last handed on.
    on_delay : ``In(signed(11))``
        µs, ``1 - lead_us`` … 1023.
    off_delay : ``In(10)``
        µs.
    marking : ``Out(1)``
        The decision with its edges delayed.
    """

    frame_strobe: In(1)
    run: In(1)
    decision: In(1)
    on_delay: In(signed(11))
    off_delay: In(10)
    marking: Out(1)

    def __init__(self, *, clocks_per_us, lead_us):
        if not isinstance(clocks_per_us, int) or clocks_per_us < 2:
            raise ValueError(f"the laser delays need a clock of a whole number of MHz, at "
                             f"least 2, not {clocks_per_us!r} clocks per µs")
        self.clocks_per_us = clocks_per_us
        self.lead_us = lead_us
        super().__init__()

    def elaborate(self, platform):
        m = Module()
        # µs ticks, restarted by every frame strobe (a frame is a whole number of µs, so this
        # only keeps them in step): an edge due d µs after a strobe comes d µs of clocks later.
        phase = Signal(range(self.clocks_per_us))
        tick = Signal()
        m.d.comb += tick.eq(phase == self.clocks_per_us - 1)
        with m.If(self.frame_strobe | tick):
            m.d.sync += phase.eq(0)
        with m.Else():
            m.d.sync += phase.eq(phase + 1)

        previous = Signal()
        m.d.sync += previous.eq(self.decision)
        rise = self.decision & ~previous
        fall = ~self.decision & previous
        # Each counts µs down from its delay; the edge is due on the tick that takes it to
        # -lead_us, lead_us µs of ticks after a delay of 0 (when the point reaches the head).
        on_left = Signal(signed(11))
        off_left = Signal(signed(11))
        on_waiting = Signal()
        off_waiting = Signal()
        on_newer = Signal()         # the waiting rising edge was decided after the falling one
        due = 1 - self.lead_us
        # (At or below with a lead shorter than the register's reach, XY2-200's: a negative
        # delay beyond it comes as early as it can.)
        if self.lead_us < LASER_ON_LEAD_US:
            on_due = on_waiting & tick & (on_left <= due)
        else:
            on_due = on_waiting & tick & (on_left == due)
        off_due = off_waiting & tick & (off_left == due)
        with m.If(tick):
            m.d.sync += [on_left.eq(on_left - 1), off_left.eq(off_left - 1)]
        with m.If(on_due):
            m.d.sync += [self.marking.eq(1), on_waiting.eq(0)]
            with m.If(on_newer):
                m.d.sync += off_waiting.eq(0)       # stale: decided before this edge
        with m.If(off_due):
            m.d.sync += [self.marking.eq(0), off_waiting.eq(0)]
            with m.If(~on_newer):
                m.d.sync += on_waiting.eq(0)
        with m.If(on_due & off_due):
            # Both on one clock: the newer wins.
            m.d.sync += self.marking.eq(on_newer)
        with m.If(rise):
            m.d.sync += [on_left.eq(self.on_delay), on_waiting.eq(1), on_newer.eq(1)]
        with m.If(fall):
            m.d.sync += [off_left.eq(self.off_delay), off_waiting.eq(1), on_newer.eq(0)]
        with m.If(~self.run):
            m.d.sync += [self.marking.eq(0), on_waiting.eq(0), off_waiting.eq(0)]
        return m
