"""The fly offset applied: each point moved by where the belt has carried the part, before the
field correction (RTC5/RTC6 add it after wobble and before the correction table), and held in
the field rather than wrapped.

A point the offset pushes past the field's edge is not marked: the mirrors stop at the edge
(the position is held at 0 or 65,535 on that axis) and :attr:`FlyOffset.clipped` marks the
point, so that the top keeps the laser off while it is on the wires, and counts it.
"""

from amaranth.hdl import Module, Mux, Signal, signed
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out

from ..points import FIELD_MAX, FieldPoint
from .scale import OFFSET_BITS


__all__ = ["FlyOffset", "ClippedOnWires"]


class FlyOffset(wiring.Component):
    """``position + offset`` on each axis, combinationally (no clock of latency: the point is
    on its way to the correction stage, which has a frame's budget), held within
    ``0 … FIELD_MAX``.

    Interface attributes
    --------------------
    positions_in : ``In(stream.Signature(FieldPoint))``
    positions_out : ``Out(stream.Signature(FieldPoint))``
        The same handshake, the payload moved.
    offset_x, offset_y : ``In(signed(OFFSET_BITS))``
        Galvo units (:class:`~.scale.FlyScale`'s).
    clipped : ``Out(1)``
        The point on ``positions_out`` now was held at the field's edge on either axis.
    """

    positions_in: In(stream.Signature(FieldPoint))
    positions_out: Out(stream.Signature(FieldPoint))
    offset_x: In(signed(OFFSET_BITS))
    offset_y: In(signed(OFFSET_BITS))
    clipped: Out(1)

    def elaborate(self, platform):
        m = Module()
        clips = []
        for axis in ("x", "y"):
            # 16 bits unsigned + 18 signed: 19 signed bits hold every sum.
            moved = Signal(signed(OFFSET_BITS + 1), name=f"moved_{axis}")
            m.d.comb += moved.eq(self.positions_in.payload[axis] + getattr(self, f"offset_{axis}"))
            # Below the field: the sign bit. Past it: positive with a bit above the field's 16.
            # (Read off the sum's bits rather than compared: the sum is at the end of a long
            # combinational path, from the source select through the scale's multiplier.)
            low = moved[-1]
            high = ~moved[-1] & moved[16:-1].any()
            m.d.comb += self.positions_out.payload[axis].eq(self._held(moved, low, high))
            clips.append(low | high)
        m.d.comb += [
            self.positions_out.valid.eq(self.positions_in.valid),
            self.positions_in.ready.eq(self.positions_out.ready),
            self.clipped.eq(self._flag(*clips)),
        ]
        return m

    def _held(self, moved, low, high):
        """The axis's position: the sum held at the field's edge."""
        return Mux(low, 0, Mux(high, FIELD_MAX, moved[:16]))

    def _flag(self, clipped_x, clipped_y):
        """The point's flag: either axis held."""
        return clipped_x | clipped_y


class ClippedOnWires(wiring.Component):
    """Follows each point's :attr:`FlyOffset.clipped` flag to the wires, and keeps the laser
    off while a clipped point is on them.

    A point leaves the fly stage (``entering``) into the correction stage, which holds one
    point at most and hands it to the PHY (``taken``) at a frame's start, or with no such stage
    straight into the PHY (``entering`` and ``taken`` on the same clock). The PHY sends the
    point it took from the next clock until it takes the next one: :attr:`on_wires` is that
    point's flag, and :attr:`marking_out` is ``marking_in`` while it is low.

    Parameters
    ----------
    held : bool
        A stage between holds the point (the correction stage); False: the PHY takes the
        point as it leaves the fly stage.

    Interface attributes
    --------------------
    entering, clipped : ``In(1)``
        A point leaves the fly stage now; it was held at the field's edge.
    taken : ``In(1)``
        The PHY takes a point now.
    marking_in : ``In(1)``
    marking_out : ``Out(1)``
    on_wires : ``Out(1)``
        The point on the wires now was held at the field's edge.
    """

    entering: In(1)
    clipped: In(1)
    taken: In(1)
    marking_in: In(1)
    marking_out: Out(1)
    on_wires: Out(1)

    def __init__(self, *, held):
        self.held = bool(held)
        super().__init__()
        #: The flag of the point the stage between holds (with ``held``).
        self.held_clipped = Signal()

    def elaborate(self, platform):
        m = Module()
        if self.held:
            with m.If(self.entering):
                m.d.sync += self.held_clipped.eq(self.clipped)
            next_on_wires = self.held_clipped
        else:
            next_on_wires = self.clipped
        with m.If(self._moves_on()):
            m.d.sync += self.on_wires.eq(next_on_wires)
        m.d.comb += self.marking_out.eq(self.marking_in & ~self._gate())
        return m

    def _moves_on(self):
        """When the point on the wires changes: the PHY takes the next."""
        return self.taken

    def _gate(self):
        """What keeps the laser off: the point on the wires clipped."""
        return self.on_wires
