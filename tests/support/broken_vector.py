"""Deliberately broken pixel lines, to show that the pixel-line proofs catch each fault: the
real sequencer (its interpolator free, as proved) with its queue's commands tampered with on
the way in."""

from amaranth.hdl import Module
from amaranth.lib import wiring

from galvoscan.formal.vector import FreeDDASequencer
from galvoscan.gateware.sources.vector import OP_JUMP, OP_MARK


#: Each fault: what it does, the harness that catches it, and the property it breaks.
VECTOR_FAULTS = {
    "gate_ignored": ("a pixel line is stepped as a plain mark: every point lit, its bits "
                     "ignored", "dark_lines", "the laser stays off"),
    "op_and_pixels_swapped": ("vec_op's bit 0 and bit 8 taken for each other: a pixel word "
                              "is a plain mark", "words", "the laser stays off"),
    "bits_inverted": ("a pixel word's bits reach the line inverted", "dark_lines",
                      "the laser stays off"),
}


class TamperedSequencer(wiring.Component):
    def __init__(self, kind):
        if kind not in VECTOR_FAULTS:
            raise ValueError(f"unknown fault {kind!r}")
        self.kind = kind
        self.inner = FreeDDASequencer()
        super().__init__(self.inner.signature)

    def elaborate(self, platform):
        m = Module()
        m.submodules.inner = inner = self.inner
        outer_command, command = self.commands.payload, inner.commands.payload
        m.d.comb += [
            inner.commands.valid.eq(self.commands.valid),
            self.commands.ready.eq(inner.commands.ready),
            command.eq(outer_command),
            self.points.valid.eq(inner.points.valid),
            self.points.payload.eq(inner.points.payload),
            inner.points.ready.eq(self.points.ready),
        ]
        for name in ("frame_strobe", "pulse_ahead", "run", "pitch", "pulses_per_point",
                     "jump_delay", "mark_delay", "polygon_delay", "polygon_scaled"):
            m.d.comb += getattr(inner, name).eq(getattr(self, name))
        for name in ("laser", "underrun", "stall", "busy"):
            m.d.comb += getattr(self, name).eq(getattr(inner, name))
        is_line = outer_command.pixels & (outer_command.op == OP_MARK)
        is_word = outer_command.pixels & (outer_command.op == OP_JUMP)
        if self.kind == "gate_ignored":
            with m.If(is_line):
                m.d.comb += command.pixels.eq(0)
        elif self.kind == "op_and_pixels_swapped":
            m.d.comb += [command.op.eq(outer_command.pixels),
                         command.pixels.eq(outer_command.op)]
        elif self.kind == "bits_inverted":
            with m.If(is_word):
                m.d.comb += [command.x.eq(~outer_command.x), command.y.eq(~outer_command.y)]
        return m
