"""Marking on the fly: a point the belt's offset moves is never wrapped, and a point held at
the field's edge is never fired."""

from amaranth.asserts import AnyConst, AnySeq
from amaranth.hdl import (Assert, Assume, ClockDomain, Cover, Elaboratable, Module, Mux,
                          ResetSignal, Signal, signed)

from ..gateware.points import FIELD_MAX


__all__ = ["FlyOffsetSpec", "ClippedOnWiresSpec"]


class FlyOffsetSpec(Elaboratable):
    """The fly offset stage, for every point, offset and handshake (all free on every clock).
    Proved: each axis of the point out is the point in moved by its offset, held within
    ``0 … FIELD_MAX`` (the sum taken in the spec's own 20 bits: nothing wraps); the point is
    flagged clipped exactly when either axis was held; the handshake passes through."""

    def __init__(self, stage):
        self.stage = stage

    def elaborate(self, platform):
        m = Module()
        m.domains.sync = ClockDomain()
        m.submodules.dut = dut = self.stage
        m.d.comb += [
            ResetSignal("sync").eq(AnySeq(1)),
            dut.positions_in.payload.eq(AnySeq(len(dut.positions_in.payload.as_value()))),
            dut.positions_in.valid.eq(AnySeq(1)),
            dut.positions_out.ready.eq(AnySeq(1)),
            dut.offset_x.eq(AnySeq(len(dut.offset_x))),
            dut.offset_y.eq(AnySeq(len(dut.offset_y))),
        ]
        held_any = []
        for axis in ("x", "y"):
            total = Signal(signed(20), name=f"total_{axis}")
            m.d.comb += total.eq(dut.positions_in.payload[axis].as_unsigned() +
                                 getattr(dut, f"offset_{axis}").as_signed())
            held = (total < 0) | (total > FIELD_MAX)
            held_any.append(held)
            want = Mux(total < 0, 0, Mux(total > FIELD_MAX, FIELD_MAX, total))
            m.d.comb += Assert(dut.positions_out.payload[axis] == want,
                               "a moved point is held within the field, never wrapped")
        m.d.comb += [
            Assert(dut.clipped == (held_any[0] | held_any[1]),
                   "a point is flagged clipped exactly when it was held at the edge"),
            Assert((dut.positions_out.valid == dut.positions_in.valid) &
                   (dut.positions_in.ready == dut.positions_out.ready),
                   "the handshake passes through"),
            Cover(dut.clipped & (dut.positions_out.payload.x == FIELD_MAX)),
            Cover(~dut.clipped & (dut.positions_out.payload.y == 0)),
        ]
        return m


class ClippedOnWiresSpec(Elaboratable):
    """The gate that keeps the laser off while a clipped point is on the wires, for every
    sequence of points entering, clipped or not, taken by the PHY, and of marking (all free,
    the reset too), with the one rule of the pipeline it sits in: a stage between holds one
    point at most, so a point enters it only while it is empty or its point is being taken.

    The spec follows the points itself: the flag of the point held between, and of the point
    the PHY took last (none: not clipped, after a reset). Proved: ``marking_out`` is
    ``marking_in`` exactly while the point on the wires was not clipped: a clipped point is
    never fired, and nothing else is held back."""

    def __init__(self, gate, *, helpers=True):
        self.gate = gate
        self.helpers = helpers

    def elaborate(self, platform):
        m = Module()
        m.domains.sync = ClockDomain()
        m.submodules.dut = dut = self.gate
        reset = Signal()
        m.d.comb += [ResetSignal("sync").eq(reset), reset.eq(AnySeq(1))]
        for name in ("entering", "clipped", "taken", "marking_in"):
            m.d.comb += getattr(dut, name).eq(AnySeq(1))

        wire = Signal()
        if dut.held:
            full, held = Signal(), Signal()
            # The pipeline's rule: one point between at most.
            m.d.comb += Assume(~dut.entering | ~full | dut.taken)
            # The PHY takes only a point there is.
            m.d.comb += Assume(~dut.taken | full)
            with m.If(dut.taken):
                m.d.sync += [wire.eq(held), full.eq(0)]
            with m.If(dut.entering):
                m.d.sync += [held.eq(dut.clipped), full.eq(1)]
            if self.helpers:
                # Helper (proved too): the gate holds the spec's point.
                m.d.comb += Assert(~full | (dut.held_clipped == held), "helper: the point held")
        else:
            m.d.comb += Assume(dut.taken == dut.entering)
            with m.If(dut.taken):
                m.d.sync += wire.eq(dut.clipped)
        if self.helpers:
            # Helper (proved too): the gate's flag is the spec's. (The broken gates' checks
            # leave the helpers out, so that their counterexamples break the property itself.)
            m.d.comb += Assert(dut.on_wires == wire, "helper: the point on the wires")
        m.d.comb += [
            Assert(dut.marking_out == (dut.marking_in & ~wire),
                   "marking passes exactly while the point on the wires was not clipped"),
            Cover(dut.marking_in & ~dut.marking_out),
            Cover(dut.marking_out),
        ]
        return m
