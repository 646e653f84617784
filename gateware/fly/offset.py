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


__all__ = ["FlyOffset"]


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
            low, high = moved < 0, moved > FIELD_MAX
            m.d.comb += self.positions_out.payload[axis].eq(
                Mux(low, 0, Mux(high, FIELD_MAX, moved[:16])))
            clips.append(low | high)
        m.d.comb += [
            self.positions_out.valid.eq(self.positions_in.valid),
            self.positions_in.ready.eq(self.positions_out.ready),
            self.clipped.eq(clips[0] | clips[1]),
        ]
        return m
