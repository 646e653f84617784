"""Pixel lines can only keep the laser off: properties of the vector sequencer's laser
decision with pixel words in its queue (issue 37).

The sequencer is the real one (with the RTC delays and pixel lines, as built) with its line
interpolator replaced by a free one (:class:`FreeLineDDA`: any points, any number, after any
set-up), so what is proved holds for every line the DDA can step, and the proof stays small.
Every input is free on every clock: the queue's commands (op, pixels bit, x, y, corner hold),
the frame strobe, the PRR's early pulses, run, every register and the reset. Two harnesses
restrict the commands (and nothing else):

* ``"words"``: no mark and no pixel line, any pixel words and jumps: **the laser is never on**
  (a pixel word, anywhere, lights nothing outside a mark);
* ``"dark_lines"``: pixel lines, jumps and pixel words whose bits are all 0, no plain mark:
  **the laser is never on** (a line's points are lit by their bits and nothing else: not its
  first point, not a corner hold after it, not a point past its words).

With plain marks as well, a line's points are the points the same mark would step (the same
interpolator), so together these say a pixel bit can only gate a mark's points off.
"""

from amaranth.asserts import AnySeq
from amaranth.hdl import (Assert, Assume, ClockDomain, Cover, Elaboratable, Module, ResetSignal,
                          Signal)
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out

from ..gateware.points import FieldPoint
from ..gateware.sources.dda import Segment
from ..gateware.sources.vector import OP_JUMP, OP_MARK, VectorSequencer


__all__ = ["FreeLineDDA", "FreeDDASequencer", "PixelLineSpec", "HARNESSES"]


#: The restrictions on the queue's commands, each a harness of the proof.
HARNESSES = ("words", "dark_lines")


class FreeLineDDA(wiring.Component):
    """The :class:`~galvoscan.gateware.sources.dda.LineDDA`'s interface, with free points:
    after it takes a segment it is busy, and offers points at any positions, on any clocks,
    until one it hands on is marked ``last`` (or it stops with none, as a zero-length segment
    does)."""

    segment: In(stream.Signature(Segment))
    pitch: In(16)
    points: Out(stream.Signature(FieldPoint))
    busy: Out(1)
    last: Out(1)

    def elaborate(self, platform):
        m = Module()
        active = Signal()
        m.d.comb += [
            self.segment.ready.eq(~active),
            self.busy.eq(active),
            self.points.valid.eq(active & AnySeq(1)),
            self.points.payload.eq(AnySeq(FieldPoint.size)),
            self.last.eq(AnySeq(1)),
        ]
        with m.If(self.segment.valid & self.segment.ready):
            m.d.sync += active.eq(1)
        with m.Elif(self.points.valid & self.points.ready & self.last):
            m.d.sync += active.eq(0)
        with m.Elif(active & ~self.points.valid & AnySeq(1)):
            m.d.sync += active.eq(0)            # (ended with no point, or no more)
        return m


class FreeDDASequencer(VectorSequencer):
    """The vector sequencer as built with pixel lines, its interpolator free."""

    def __init__(self):
        super().__init__(frame_us=10, delays=True, pixel_lines=True)

    def _line_dda(self):
        return FreeLineDDA()


class PixelLineSpec(Elaboratable):
    """The properties above, for SymbiYosys.

    Parameters
    ----------
    dut : a :class:`FreeDDASequencer` (or a component of its signature that wraps one: the
        broken designs)
    harness : str
        One of :data:`HARNESSES`: what the queue's commands may be.
    helpers : bool
        State the helper invariants (on the sequencer's slot, held point and pixel bits); the
        broken designs' bounded checks leave them out.
    """

    def __init__(self, dut, *, harness, helpers=True):
        if harness not in HARNESSES:
            raise ValueError(f"harness must be one of {', '.join(HARNESSES)}, not {harness!r}")
        self.dut = dut
        self.harness = harness
        self.helpers = helpers

    def elaborate(self, platform):
        m = Module()
        m.domains.sync = ClockDomain()
        m.d.comb += ResetSignal("sync").eq(AnySeq(1))
        m.submodules.dut = dut = self.dut
        inner = getattr(dut, "inner", dut)      # (the sequencer, inside a broken one)
        command = dut.commands.payload
        m.d.comb += [
            dut.commands.valid.eq(AnySeq(1)),
            command.eq(AnySeq(len(command.as_value()))),
            dut.points.ready.eq(AnySeq(1)),
        ]
        for name in ("frame_strobe", "pulse_ahead", "run", "pitch", "pulses_per_point",
                     "jump_delay", "mark_delay", "polygon_delay", "polygon_scaled"):
            port = getattr(dut, name)
            m.d.comb += port.eq(AnySeq(len(port)))

        is_word = command.pixels & (command.op == OP_JUMP)
        is_line = command.pixels & (command.op == OP_MARK)
        is_mark = ~command.pixels & (command.op == OP_MARK)
        if self.harness == "words":
            allowed = ~is_mark & ~is_line
        else:
            allowed = ~is_mark & (~is_word | ((command.x == 0) & (command.y == 0)))
        m.d.comb += Assume(~dut.commands.valid | allowed)

        m.d.comb += Assert(~dut.laser, "the laser stays off")

        if self.helpers:
            slot_lit = inner._slot_valid & inner._slot_mark & inner._slot_gate
            if self.harness == "words":
                m.d.comb += [
                    Assert(~inner._stepping, "helper: no line is stepped"),
                    Assert(~(inner._slot_valid & inner._slot_mark), "helper: no marked point"),
                    Assert(~inner._holding_mark, "helper: no marked point held"),
                ]
            else:
                m.d.comb += [
                    Assert(inner._pixel_bits == 0, "helper: every pixel bit is 0"),
                    Assert(~inner._stepping | inner._pixel_line, "helper: lines only"),
                    Assert(~slot_lit, "helper: no lit point waits"),
                    Assert(~inner._holding_mark | ~inner._held_gate,
                           "helper: the marked point held is dark"),
                ]

        # Not vacuous: pixel words are taken and points handed on; with dark lines, a line's
        # point is held for its pulses (dark) and the line goes on to the next.
        taken = Signal()
        m.d.comb += taken.eq(dut.points.valid & dut.points.ready)
        m.d.comb += Cover(dut.commands.valid & dut.commands.ready & is_word)
        if self.harness == "words":
            m.d.comb += Cover(taken)
        else:
            m.d.comb += Cover(taken & inner._holding_mark & inner._pixel_line &
                              inner._stepping)
        return m

