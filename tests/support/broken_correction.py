"""Deliberately broken correction stages, to show that the proof catches each fault."""

from amaranth.hdl import Module
from amaranth.lib import wiring

from galvoscan.gateware.field.correction import FieldCorrection


class WritesMidPoint(FieldCorrection):
    """Writes the table whenever asked, even while a point's corners are being read."""

    def _may_write(self, busy):
        return 1


class WritesLateValues(FieldCorrection):
    """A waiting write stores what the write port shows when it is made, not what it showed
    when the write was asked for (a frame from the other link can change it meanwhile)."""

    def _write_value(self, pending, held, asked_now):
        return asked_now


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
        self._ram_addr = self.inner._ram_addr
        self._ram_data = self.inner._ram_data
        self._step = self.inner._step
        self._held_node, self._held_data = self.inner._held_node, self.inner._held_data
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


#: Each fault and the property its bounded check (without helper invariants) breaks.
CORRECTION_FAULTS = {
    WritesMidPoint: "no table write while a point is made",
    WritesLateValues: "a table write stores the node and offsets asked for",
    OverwritesOutput: "a point is taken only when the output is free",
    # The dropped write is never made; or a later one is, storing other values than it asked.
    LosesWrites: ("a requested write is made within CLOCKS clocks",
                  "a table write stores the node and offsets asked for"),
}

#: Faults about a write that waits for a point: a point is made in 15 clocks, so none shows
#: before clock 16, and their bounded checks skip the first 13 (which only cost solver time).
WAITING_FAULTS = {WritesLateValues, LosesWrites}
