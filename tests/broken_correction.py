"""Deliberately broken correction stages, to show that the proof catches each fault."""

from amaranth.hdl import Module
from amaranth.lib import wiring

from galvoscan.gateware.field.correction import FieldCorrection


class WritesMidPoint(FieldCorrection):
    """Writes the table whenever asked, even while a point's corners are being read."""

    def _may_write(self, busy):
        return 1


class OverwritesOutput(FieldCorrection):
    """Takes a new point while the last one still waits to be taken."""

    def _may_take(self, busy, out_free):
        return ~busy


class LosesWrites(wiring.Component):
    """Drops a write asked for while a point is being made."""

    def __init__(self, table):
        self.inner = FieldCorrection(table)
        self._busy = self.inner._busy
        self._ram_write = self.inner._ram_write
        super().__init__(self.inner.signature)

    def elaborate(self, platform):
        m = Module()
        m.submodules.inner = inner = self.inner
        wiring.connect(m, wiring.flipped(self.positions_in), inner.positions_in)
        wiring.connect(m, inner.positions_out, wiring.flipped(self.positions_out))
        for name in ("enable", "write_node", "write_dx", "write_dy"):
            m.d.comb += getattr(inner, name).eq(getattr(self, name))
        m.d.comb += [
            inner.write_en.eq(self.write_en & ~inner._busy),
            self.write_pending.eq(inner.write_pending),
            self.clipped.eq(inner.clipped),
        ]
        return m


#: Each fault and the property that catches it first. (A lost write shows first as a write
#: owed that the stage no longer keeps pending: the helper that lets the induction bound the
#: wait.)
CORRECTION_FAULTS = {
    WritesMidPoint: "no table write while a point is made",
    OverwritesOutput: "a point is taken only when the output is free",
    LosesWrites: "helper: a write is owed while one is pending",
}
