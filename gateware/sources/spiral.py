"""Spiral sequencer: walks the two angle ROMs at different cycle lengths (Dai & Tang 2020)."""

from amaranth.hdl import Module, Mux, Signal, signed
from amaranth.lib import stream, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from ..points import OffsetPoint
from .spiral_interp import DIVIDE_CLOCKS, MAX_INTERPOLATED_DWELL, AxisInterpolator
from .spiral_table import SpiralTable


__all__ = ["SpiralSequencer", "PARK_FRAMES"]


#: Frames the head holds the park position after power-up before the first point: that point
#: is due at the end of the first frame and goes out at the end of the second.
PARK_FRAMES = 2


class SpiralSequencer(wiring.Component):
    """Precessing spiral from two ROMs.

    X walks ``ROM_X[x_first … x_last]`` and Y walks ``ROM_Y[y_first … y_last]``, one step per
    point, each wrapping to its first address after its last. With the paper's ranges (0-127 and
    1-126) the two cycles differ in length, the phase between X and Y drifts, and the ellipse the
    spot draws precesses until it fills the field; the pattern repeats after lcm(128, 126) = 8064
    points.

    Each point is offered once, right after the frame strobe on which its predecessor's dwell
    ended, and is then shown for ``dwell`` frames: the PHY repeats the last position on frames
    when nothing new is offered. Register inputs are sampled when a point is issued, so a change
    takes effect at a point boundary.

    Built with ``interpolation=True`` and with ``interpolate`` high when a point is issued, that
    point's frames after its first are offered too, each part of the way to the next point
    (:class:`~.spiral_interp.AxisInterpolator`: frame ``k`` of ``d`` shows
    ``p + sign(q - p) × floor(|q - p| × k / d)``): the same points at the same times, joined by
    straight steps instead of held and jumped between. A point held longer than
    :data:`~.spiral_interp.MAX_INTERPOLATED_DWELL` frames is held.

    Parameters
    ----------
    table : :class:`SpiralTable`
        The angle tables, placed in two ROMs (block RAM on iCE40).
    interpolation : bool
        Build the linear interpolation and its ``interpolate`` input.

    Interface attributes
    --------------------
    frame_strobe : ``In(1)``
        The PHY's frame strobe: one pulse per 10 µs frame.
    run : ``In(1)``
        Issue points while high. While low the last point stays on the galvos, and the next
        start begins the pattern again from ``x_first``/``y_first``.
    dwell : ``In(16)``
        Frames each point is held, 1 … 65535 (×10 µs at 2 Mbit/s). 0 is taken as 1.
    x_first, x_last, y_first, y_last : ``In(range(points))``
        ROM address ranges walked by each axis, inclusive. An address past ``*_last`` (after
        the range is changed) wraps to ``*_first``.
    interpolate : ``In(1)``, with ``interpolation``
        1 = linear interpolation between points, 0 = each point held.
    points : ``Out(stream.Signature(OffsetPoint))``
        Spiral points, signed offsets from the field centre.
    """

    class Signature(wiring.Signature):
        """Signature of a spiral sequencer whose ROMs hold ``points`` samples per axis."""

        def __init__(self, *, points, interpolation=False):
            if not isinstance(points, int) or points < 2:
                raise TypeError(f"points must be an integer of at least 2, not {points!r}")
            self.rom_points = points
            members = {
                "frame_strobe": In(1),
                "run":          In(1),
                "dwell":        In(16),
                "x_first":      In(range(points)),
                "x_last":       In(range(points)),
                "y_first":      In(range(points)),
                "y_last":       In(range(points)),
            }
            if interpolation:
                members["interpolate"] = In(1)
            members["points"] = Out(stream.Signature(OffsetPoint))
            super().__init__(members)

    def __init__(self, table, *, interpolation=False):
        if not isinstance(table, SpiralTable):
            raise TypeError(f"table must be a SpiralTable, not {table!r}")
        self.table = table
        self.interpolation = bool(interpolation)
        super().__init__(self.Signature(points=table.points, interpolation=self.interpolation))

    def elaborate(self, platform):
        m = Module()

        depth = self.table.points
        m.submodules.rom_x = rom_x = Memory(shape=signed(16), depth=depth, init=self.table.x)
        m.submodules.rom_y = rom_y = Memory(shape=signed(16), depth=depth, init=self.table.y)
        read_x = rom_x.read_port()
        read_y = rom_y.read_port()

        addr_x = Signal(range(depth))
        addr_y = Signal(range(depth))
        m.d.comb += [read_x.addr.eq(addr_x), read_y.addr.eq(addr_y)]

        # A table point taken (not an interpolated frame between two of them).
        between = Signal()
        issued = self.points.valid & self.points.ready & ~between

        # After reset, and whenever `run` is low, the walk starts again from the first
        # addresses, so every start replays the pattern from its beginning.
        restart = Signal(init=1)
        with m.If(~self.run):
            m.d.sync += restart.eq(1)
        with m.Elif(restart):
            m.d.sync += [
                restart.eq(0),
                addr_x.eq(self.x_first),
                addr_y.eq(self.y_first),
            ]
        with m.Elif(issued):
            m.d.sync += [
                addr_x.eq(Mux(addr_x >= self.x_last, self.x_first, addr_x + 1)),
                addr_y.eq(Mux(addr_y >= self.y_last, self.y_first, addr_y + 1)),
            ]

        # The ROMs answer one clock after the address changes; `fetched` is low on that clock.
        fetched = Signal()
        m.d.sync += fetched.eq(~restart & ~issued)

        # Frame strobes still to pass before the next point is due.
        # The first point after a start waits for a frame strobe too, like every other one: a
        # point always arrives just after a frame boundary, a whole frame before it is sent.
        frames_left = Signal(16)
        dwell = Mux(self.dwell == 0, 1, self.dwell)
        with m.If(restart):
            m.d.sync += frames_left.eq(1)
        with m.Elif(issued):
            m.d.sync += frames_left.eq(dwell)
        with m.Elif(self.frame_strobe & (frames_left != 0)):
            m.d.sync += frames_left.eq(frames_left - 1)

        table_due = fetched & (frames_left == 0)
        if self.interpolation:
            self._elaborate_interpolation(m, read_x, read_y, restart, issued, fetched,
                                          frames_left, dwell, table_due, between)
        else:
            m.d.comb += [
                self.points.payload.x.eq(read_x.data),
                self.points.payload.y.eq(read_y.data),
                self.points.valid.eq(self.run & ~restart & table_due),
            ]

        return m

    def _elaborate_interpolation(self, m, read_x, read_y, restart, issued, fetched, frames_left,
                                 dwell, table_due, between):
        """Interpolated frames between table points (``between`` high while one is offered).

        Every point comes from the interpolators' position registers (no multiplexer in front
        of the output, and no load from the ROMs): the last step from a point lands on the next
        one, on the clock that point is due; it is offered on the next clock. A held point (or
        the first after a start) is one step of its whole way, made when the next is due."""
        m.submodules.interp_x = interp_x = AxisInterpolator()
        m.submodules.interp_y = interp_y = AxisInterpolator()

        # The next table point is due, and the way to it divided (after a start the division
        # may still run when the first frame strobe comes).
        dividing_due = Signal()
        divide_left = Signal(range(DIVIDE_CLOCKS + 1))
        due = Signal()
        m.d.comb += due.eq(table_due & ~dividing_due & (divide_left == 0) & ~restart)
        arrived = Signal()
        m.d.sync += arrived.eq(due & ~issued)
        m.d.comb += self.points.valid.eq(self.run & ~restart & ((due & arrived) | between))

        # The point's setting and dwell, held from its issue until the next point arrives (the
        # Bresenham steps need the same d all along). Longer dwells are held, not interpolated:
        # their way is divided by 1 and made in the one step onto the next point.
        interpolating = Signal()
        point_frames = Signal(8)
        # The next point is read from the ROMs two clocks after an issue or a start (`fetched`
        # low, then high): then the division starts, and takes a quotient bit a clock.
        start = dividing_due & fetched & ~issued
        with m.If(restart):
            m.d.sync += [interpolating.eq(0), point_frames.eq(1), dividing_due.eq(1)]
        with m.Elif(issued):
            interpolate = self.interpolate & (dwell <= MAX_INTERPOLATED_DWELL)
            m.d.sync += [
                interpolating.eq(interpolate),
                point_frames.eq(Mux(interpolate, dwell[:8], 1)),
                dividing_due.eq(1),
            ]
        with m.Elif(fetched):
            m.d.sync += dividing_due.eq(0)
        with m.If(start):
            m.d.sync += divide_left.eq(DIVIDE_CLOCKS)
        with m.Elif(divide_left != 0):
            m.d.sync += divide_left.eq(divide_left - 1)

        # At a frame strobe with more frames of this point to come, the next one moves on; and
        # when the next table point is due, the last step lands on it.
        between_step = self.frame_strobe & interpolating & (frames_left > 1) & ~restart
        with m.If(restart | (self.points.valid & self.points.ready)):
            m.d.sync += between.eq(0)
        with m.Elif(between_step):
            m.d.sync += between.eq(1)

        for interp, read, axis in ((interp_x, read_x, "x"), (interp_y, read_y, "y")):
            m.d.comb += [
                interp.start.eq(start),
                interp.q.eq(read.data),
                interp.divide.eq(divide_left != 0),
                interp.frames.eq(point_frames),
                interp.step.eq(between_step | (due & ~arrived)),
                getattr(self.points.payload, axis).eq(interp.position),
            ]
