"""The distortion correction stage's table writes and point stream, as properties."""

from amaranth.asserts import AnySeq
from amaranth.hdl import (Assert, Cat, ClockDomain, Cover, Elaboratable, Module, Mux,
                          ResetSignal, Signal)

from amaranth.lib.wiring import connect

from ..gateware.field.correction import FieldCorrection
from ..gateware.field.correction_table import CorrectionTable
from ..gateware.host.command import CommandDecoder
from ..gateware.host.registers import RegisterFile
from ..gateware.host.regmap import register_map


__all__ = ["CorrectionSpec", "CorrectionLinkSpec"]


class CorrectionSpec(Elaboratable):
    """No torn point, no lost write, a well-behaved stream: for every input sequence and reset.

    All inputs (points and their valid, the sink's ready, enable, the write port) and the reset
    are free on every clock: the write port's node and offsets may change while a write waits
    (a frame from the other link can change the registers behind them). Proved:

    * **no torn point**: the table RAM is never written between taking a point and presenting
      it, so every point is interpolated from one table;
    * **no lost write**: a requested write is made within ``CLOCKS`` clocks, and it stores the
      node and offsets the port showed on the clock it was asked for;
    * **stream**: a presented point stays, unchanged, until it is taken; a point is taken only
      when the output is free; a point taken is presented ``CLOCKS`` clocks later.

    Parameters
    ----------
    stage : a :class:`FieldCorrection` (or a broken one)
    helpers : bool
        State the helper invariants (left out in the broken stages' bounded checks, so that
        their counterexamples break the properties themselves).
    points_at_origin : bool
        Every point offered is (0, 0) instead of free (the rest stays free): a restriction
        for the broken stages' bounded checks only, never for the proof. A counterexample
        found with it is one with free points too. The properties are about when the table
        is written and with what, and whether the output holds, not about the interpolated
        values; fixed coordinates make the interpolation's multiplier weights constants,
        which spares the solver most of its work (31 s down to 10 s for a lost write).
    """

    def __init__(self, stage, *, helpers=True, points_at_origin=False):
        self.stage = stage
        self.helpers = helpers
        self.points_at_origin = points_at_origin

    def elaborate(self, platform):
        m = Module()
        m.domains.sync = ClockDomain()
        m.submodules.dut = dut = self.stage
        m.d.comb += ResetSignal("sync").eq(AnySeq(1))
        for port in (dut.positions_in.valid, dut.positions_out.ready, dut.enable,
                     dut.write_en):
            m.d.comb += port.eq(AnySeq(len(port)))
        for port in (dut.positions_in.payload.x, dut.positions_in.payload.y):
            m.d.comb += port.eq(0 if self.points_at_origin else AnySeq(len(port)))
        for port in (dut.write_node, dut.write_dx, dut.write_dy):
            m.d.comb += port.eq(AnySeq(len(port)))
        owed = Signal()                       # a write was asked for and not made yet

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
            Assert(age < FieldCorrection.CLOCKS, "a taken point is presented within CLOCKS"),
        ]
        if self.helpers:
            m.d.comb += Assert(in_flight == dut._busy, "helper: in flight while the stage is busy")

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
        m.d.comb += Assert(waited < FieldCorrection.CLOCKS,
                           "a requested write is made within CLOCKS clocks")
        if self.helpers:
            m.d.comb += Assert(owed == dut.write_pending,
                               "helper: a write is owed while one is pending")
        # What the write was asked to store: the port on the clock of the request (a request
        # while one is owed is not a new one: the register file refuses those).
        asked_node = Signal.like(dut.write_node)
        asked_dx, asked_dy = Signal(16), Signal(16)
        with m.If(dut.write_en & ~owed):
            m.d.sync += [asked_node.eq(dut.write_node), asked_dx.eq(dut.write_dx),
                         asked_dy.eq(dut.write_dy)]
        node = Mux(owed, asked_node, dut.write_node)
        dx = Mux(owed, asked_dx, dut.write_dx)
        dy = Mux(owed, asked_dy, dut.write_dy)
        m.d.comb += Assert(~dut._ram_write |
                           ((dut._ram_addr == node) & (dut._ram_data == Cat(dx, dy))),
                           "a table write stores the node and offsets asked for")

        if self.helpers:
            # Helper invariants (proved too), so that a short induction is enough: a point's
            # step is its age, a waiting write started after its point did and the stage holds
            # what it was asked for.
            m.d.comb += [
                Assert(~in_flight | (dut._step == age), "helper: step is the point's age"),
                Assert(~owed | dut._busy | dut._ram_write, "helper: owed only while busy"),
                Assert(~(owed & dut._busy) | (waited < dut._step),
                       "helper: a waiting write started after its point"),
                Assert(~owed | ((dut._held_node == asked_node) &
                                (dut._held_data == Cat(asked_dx, asked_dy))),
                       "helper: the stage holds what was asked"),
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


class CorrectionLinkSpec(Elaboratable):
    """Table writes through the host link: what a ``cor_write`` frame asks for is what the
    table gets, with both links live and the reset free.

    Frames from both links are free on every clock (any frame event, any contents: both
    transports at once, a superset of what the SPI target and UART port hand on), and so are the
    points through the stage, its sink and ``cor_enable``. The real decoder, register file and
    correction stage, wired as in the system top. Proved:

    * every table write stores the ``cor_node``, ``cor_dx``, ``cor_dy`` that the registers held
      when its ``cor_write`` frame was accepted, whatever frames come after it;
    * an accepted ``cor_write`` is made within ``CLOCKS + 1`` clocks, and one is never accepted
      while another waits (it is refused, and the decoder counts it).

    Parameters
    ----------
    nodes : int
        Correction table nodes per axis (the RAM's size does not enter the properties).
    make_stage : callable
        Builds the correction stage (the tests pass broken ones).
    helpers : bool
        State the helper invariants.
    refuse_while_waiting : bool
        Wire ``cor_write_ready`` as the top does (False: the register file never refuses, a
        broken top for the tests).
    points_at_origin : bool
        Every point offered is (0, 0): a restriction for bounded checks only, as in
        :class:`CorrectionSpec`.
    """

    def __init__(self, *, nodes=5, make_stage=None, helpers=True, refuse_while_waiting=True,
                 points_at_origin=False):
        self.nodes = nodes
        self.points_at_origin = points_at_origin
        self.refuse_while_waiting = refuse_while_waiting
        self.make_stage = make_stage or (lambda: FieldCorrection(CorrectionTable.identity(nodes)))
        self.helpers = helpers

    def elaborate(self, platform):
        m = Module()
        m.domains.sync = ClockDomain()
        m.d.comb += ResetSignal("sync").eq(AnySeq(1))
        regmap = register_map(correction_nodes=self.nodes)
        m.submodules.decoder = decoder = CommandDecoder()
        # The register file without its read path: a value read is anything at all.
        m.submodules.registers = regs = RegisterFile(regmap, read_back=False)
        m.d.comb += regs.bus.read_data.eq(AnySeq(16))
        m.submodules.stage = stage = self.make_stage()
        connect(m, decoder.bus, regs.bus)
        for link in (decoder.spi_frames, decoder.uart_frames):
            m.d.comb += [link.valid.eq(AnySeq(1)),
                         link.payload.payload.eq(AnySeq(len(link.payload.payload))),
                         link.payload.intact.eq(AnySeq(1))]
        for reply in (decoder.spi_replies, decoder.uart_replies):
            m.d.comb += reply.ready.eq(AnySeq(1))
        for port in (stage.positions_in.valid, stage.positions_out.ready):
            m.d.comb += port.eq(AnySeq(len(port)))
        for port in (stage.positions_in.payload.x, stage.positions_in.payload.y):
            m.d.comb += port.eq(0 if self.points_at_origin else AnySeq(len(port)))
        # As the system top wires them.
        m.d.comb += [
            stage.enable.eq(regs.cor_enable),
            stage.write_node.eq(regs.cor_node),
            stage.write_dx.eq(regs.cor_dx),
            stage.write_dy.eq(regs.cor_dy),
            stage.write_en.eq(regs.cor_write),
            regs.cor_write_ready.eq(~regs.cor_write & ~stage.write_pending
                                    if self.refuse_while_waiting else 1),
        ]

        reset = ResetSignal("sync")
        bus = regs.bus
        # The access being written is the one given on the clock before (RegisterBus).
        asked = (bus.write_en & bus.write_ok &
                 (regs._write_address == regmap["cor_write"].address) &
                 (regs._write_data == 1))
        owed = Signal()
        node = Signal.like(regs.cor_node)
        dx, dy = Signal(16), Signal(16)
        with m.If(asked):
            m.d.sync += [owed.eq(1), node.eq(regs.cor_node), dx.eq(regs.cor_dx),
                         dy.eq(regs.cor_dy)]
        with m.Elif(stage._ram_write):
            m.d.sync += owed.eq(0)
        waited = Signal(range(FieldCorrection.CLOCKS + 3))
        with m.If(reset | ~owed | stage._ram_write):
            m.d.sync += waited.eq(0)
        with m.Elif(waited != FieldCorrection.CLOCKS + 2):
            m.d.sync += waited.eq(waited + 1)
        m.d.comb += [
            Assert(~stage._ram_write |
                   (owed & (stage._ram_addr == node) & (stage._ram_data == Cat(dx, dy))),
                   "a table write stores what the registers held when cor_write was accepted"),
            Assert(waited <= FieldCorrection.CLOCKS,
                   "an accepted cor_write is made within CLOCKS + 1 clocks"),
            Assert(~(asked & owed), "no cor_write is accepted while one waits"),
        ]
        if self.helpers:
            # Helper invariants (proved too), so that a short induction is enough.
            held = (stage._held_node == node) & (stage._held_data == Cat(dx, dy))
            unchanged = (regs.cor_node == node) & (regs.cor_dx == dx) & (regs.cor_dy == dy)
            m.d.comb += [
                Assert(owed == (regs.cor_write | stage.write_pending),
                       "helper: owed while the strobe or the stage holds it"),
                Assert(~regs.cor_write | (unchanged & (waited == 0)),
                       "helper: the strobe sees the registers of its frame"),
                Assert(~stage.write_pending | (held & (stage._busy | stage._ram_write)),
                       "helper: a waiting write is held, and made when its point is done"),
                Assert(~(stage.write_pending & stage._busy) | (waited <= stage._step),
                       "helper: a waiting write started after its point"),
                Assert(~stage._busy | (stage._step <= 14), "helper: a point takes 15 steps"),
            ]

        changed = Signal()
        with m.If(stage.write_pending & bus.write_en & bus.write_ok &
                  (regs._write_address == regmap["cor_dx"].address)):
            m.d.sync += changed.eq(1)
        m.d.comb += [
            Cover(stage._ram_write & changed,
                  "a write made after cor_dx changed while it waited"),
            Cover(owed & bus.write_en & ~bus.write_ok &
                  (regs._write_address == regmap["cor_write"].address),
                  "a cor_write refused while one waits"),
        ]
        return m
