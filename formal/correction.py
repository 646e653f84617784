"""The distortion correction stage's table writes and point stream, as properties."""

from amaranth.asserts import AnySeq
from amaranth.hdl import Assert, ClockDomain, Cover, Elaboratable, Module, ResetSignal, Signal

from ..gateware.field.correction import FieldCorrection


__all__ = ["CorrectionSpec"]


class CorrectionSpec(Elaboratable):
    """No torn point, no lost write, a well-behaved stream: for every input sequence and reset.

    All inputs (points and their valid, the sink's ready, enable, the write port) and the reset
    are free on every clock, except that the write port's node and offsets hold while a write
    is pending, as the register file holds them (a new command frame takes hundreds of clocks).
    Proved:

    * **no torn point**: the table RAM is never written between taking a point and presenting
      it, so every point is interpolated from one table;
    * **no lost write**: a requested write is made within ``CLOCKS`` clocks;
    * **stream**: a presented point stays, unchanged, until it is taken; a point is taken only
      when the output is free; a point taken is presented ``CLOCKS`` clocks later.

    Parameters
    ----------
    stage : a :class:`FieldCorrection` (or a broken one)
    """

    def __init__(self, stage):
        self.stage = stage

    def elaborate(self, platform):
        m = Module()
        m.domains.sync = ClockDomain()
        m.submodules.dut = dut = self.stage
        m.d.comb += ResetSignal("sync").eq(AnySeq(1))
        for port in (dut.positions_in.valid, dut.positions_in.payload.x,
                     dut.positions_in.payload.y, dut.positions_out.ready, dut.enable,
                     dut.write_en):
            m.d.comb += port.eq(AnySeq(len(port)))
        owed = Signal()                       # a write was asked for and not made yet
        # The write port's values hold while a write is owed.
        held = [Signal.like(dut.write_node), Signal(16), Signal(16)]
        free = [AnySeq(len(dut.write_node)), AnySeq(16), AnySeq(16)]
        for port, hold, value in zip((dut.write_node, dut.write_dx, dut.write_dy), held, free):
            m.d.comb += port.eq(value)
            with m.If(owed & ~dut.write_en):
                m.d.comb += port.eq(hold)
            m.d.sync += hold.eq(port)

        reset = ResetSignal("sync")
        taken = dut.positions_in.valid & dut.positions_in.ready
        presented = dut.positions_out.valid

        # --- no torn point ------------------------------------------------------------------
        taken_q = Signal()                    # a point was taken (enabled) and not yet shown
        with m.If(reset):
            m.d.sync += taken_q.eq(0)
        with m.Elif(taken & dut.enable):
            m.d.sync += taken_q.eq(1)
        with m.Elif(presented):
            m.d.sync += taken_q.eq(0)
        in_flight = Signal()
        m.d.comb += in_flight.eq(taken_q & ~presented)
        age = Signal(range(FieldCorrection.CLOCKS + 2))   # clocks since it was taken
        with m.If(reset | ~in_flight):
            m.d.sync += age.eq(0)
        with m.Elif(age != FieldCorrection.CLOCKS + 1):
            m.d.sync += age.eq(age + 1)
        m.d.comb += [
            Assert(~(in_flight & dut._ram_write), "no table write while a point is made"),
            Assert(in_flight == dut._busy, "helper: in flight while the stage is busy"),
            Assert(age < FieldCorrection.CLOCKS, "a taken point is presented within CLOCKS"),
        ]

        # --- no lost write ------------------------------------------------------------------
        with m.If(reset | dut._ram_write):
            m.d.sync += owed.eq(0)
        with m.Elif(dut.write_en):
            m.d.sync += owed.eq(1)
        waited = Signal(range(FieldCorrection.CLOCKS + 2))
        with m.If(reset | ~owed | dut._ram_write):
            m.d.sync += waited.eq(0)
        with m.Elif(waited != FieldCorrection.CLOCKS + 1):
            m.d.sync += waited.eq(waited + 1)
        m.d.comb += [
            Assert(waited < FieldCorrection.CLOCKS,
                   "a requested write is made within CLOCKS clocks"),
            Assert(owed == dut.write_pending, "helper: a write is owed while one is pending"),
        ]

        # --- stream rules -------------------------------------------------------------------
        held_valid = Signal()
        held_x = Signal(16)
        held_y = Signal(16)
        m.d.sync += [
            held_valid.eq(presented & ~dut.positions_out.ready & ~reset),
            held_x.eq(dut.positions_out.payload.x),
            held_y.eq(dut.positions_out.payload.y),
        ]
        m.d.comb += [
            Assert(~held_valid | (presented & (dut.positions_out.payload.x == held_x) &
                                  (dut.positions_out.payload.y == held_y)),
                   "a presented point stays until taken"),
            Assert(~dut.positions_in.ready | ~presented | dut.positions_out.ready,
                   "a point is taken only when the output is free"),
        ]

        # --- covers -------------------------------------------------------------------------
        wrote = Signal()
        with m.If(dut._ram_write):
            m.d.sync += wrote.eq(1)
        m.d.comb += [
            Cover(in_flight & dut.write_pending, "a write waits for a point"),
            Cover(wrote & presented & ~dut._busy & (dut.positions_out.payload.x != 0),
                  "a corrected point after a table write"),
        ]
        return m
