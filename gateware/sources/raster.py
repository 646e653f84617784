"""Raster fill: line by line over a rectangle, Dai & Tang 2020's baseline (raster mode).

One point per 10 µs frame: along a line the position moves ``step`` galvo units a frame (the
line speed) and ends exactly on the rectangle's edge; the next line starts ``spacing`` further
across. Serpentine by default (every other line runs back), or every line in the same
direction with a jump back. After the last line (the last multiple of ``spacing`` within the
height) the fill starts again from the first: cleaning repeats passes. The turn-arounds are
left to the mirrors; the laser stays on through them unless ``turn_gate`` asks for it to be off
for that many frames at the start of every line but the first.

The same sequence, frame by frame, is :func:`galvoscan.analysis.patterns.raster_frames`.
"""

from amaranth.hdl import Cat, Module, Mux, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out

from ..points import FIELD_MAX, OffsetPoint


__all__ = ["RasterSequencer"]


class RasterSequencer(wiring.Component):
    """Line-by-line fill of a rectangle.

    Interface attributes
    --------------------
    frame_strobe : ``In(1)``
        The PHY's frame strobe.
    run : ``In(1)``
        Fill while high; while low the mirrors hold, the laser is off, and the next start
        begins again at the first line.
    x, y : ``In(16)``
        Lower-left corner, galvo units.
    width, height : ``In(16)``
        Size, galvo units (positions past 65535 are clamped).
    spacing : ``In(16)``
        Line spacing, galvo units (0 is taken as 1).
    step : ``In(16)``
        Galvo units along a line per frame (0 is taken as 1).
    along_y : ``In(1)``
        Lines run along Y (else along X).
    one_way : ``In(1)``
        Every line in the same direction (else serpentine).
    turn_gate : ``In(16)``
        Frames with the laser off at the start of each line after the first.
    points : ``Out(stream.Signature(OffsetPoint))``
        One point per frame, offsets from the field centre.
    laser : ``Out(1)``
        Laser wanted during the frame decided at the last strobe.
    """

    frame_strobe: In(1)
    run: In(1)
    x: In(16)
    y: In(16)
    width: In(16)
    height: In(16)
    spacing: In(16)
    step: In(16)
    along_y: In(1)
    one_way: In(1)
    turn_gate: In(16)
    points: Out(stream.Signature(OffsetPoint))
    laser: Out(1)

    def elaborate(self, platform):
        m = Module()

        along_length = Mux(self.along_y, self.height, self.width)
        across_length = Mux(self.along_y, self.width, self.height)
        step = Mux(self.step == 0, 1, self.step)
        spacing = Mux(self.spacing == 0, 1, self.spacing)

        started = Signal()            # a point has been put out since run rose
        along = Signal(17)            # distance from the start of the line
        across = Signal(17)           # distance of this line from the first
        backwards = Signal()          # this line runs from the far end
        line_frames = Signal(16)      # frames since this line started
        # The first line since run rose, or since reset (never gated): a raster that runs
        # straight out of reset starts on its first line too.
        first_line = Signal(init=1)

        with m.If(self.points.ready):
            m.d.sync += self.points.valid.eq(0)

        def clamp(value):
            # A 17-bit sum: past the field's edge exactly when its top bit is set.
            return Mux(value[16], FIELD_MAX, value[:16])

        with m.If(~self.run):
            m.d.sync += [started.eq(0), along.eq(0), across.eq(0), backwards.eq(0),
                         line_frames.eq(0), first_line.eq(1), self.laser.eq(0)]
        with m.Elif(self.frame_strobe):
            # `along` never passes the line's length, nor `across` the rectangle's other side
            # (both are brought back below), so both fit 16 bits, and so do their differences.
            position_along = Mux(backwards, along_length - along[:16], along[:16])[:16]
            pos_x = clamp(self.x + Mux(self.along_y, across[:16], position_along))
            pos_y = clamp(self.y + Mux(self.along_y, position_along, across[:16]))
            gated = ~first_line & (line_frames < self.turn_gate)
            m.d.sync += [
                self.points.valid.eq(1),
                self.points.payload.x.eq(Cat(pos_x[:15], ~pos_x[15])),
                self.points.payload.y.eq(Cat(pos_y[:15], ~pos_y[15])),
                self.laser.eq(~gated),
                started.eq(1),
                line_frames.eq(line_frames + (line_frames != 0xFFFF)),
            ]
            # Then move on: along the line, or to the next line, or back to the first.
            with m.If(along >= along_length):
                next_across = across + spacing
                m.d.sync += [along.eq(0), line_frames.eq(0), first_line.eq(0)]
                with m.If(next_across > across_length):
                    m.d.sync += [across.eq(0), backwards.eq(0)]
                with m.Else():
                    m.d.sync += [across.eq(next_across), backwards.eq(~backwards & ~self.one_way)]
            with m.Else():
                next_along = along + step
                m.d.sync += along.eq(Mux(next_along > along_length, along_length, next_along))
        return m
