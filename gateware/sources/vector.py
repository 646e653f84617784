"""Vector marking: queued jump / mark segments, stepped at a pitch, each point held for a whole
number of laser pulses (after Wan et al. 2018).

Two halves:

* the **point generator** turns commands into points: a jump gives its end point (laser off);
  a mark gives, if the laser was off, the current point first, then the :class:`LineDDA`'s
  points up to the end point (laser on). Points wait in a one-point slot; the DDA works out
  the next segment while the slot's point is being held.
* the **pacer** hands points to the PHY at frame boundaries. A marked point is held until
  exactly ``pulses_per_point`` laser pulses have fallen on it, then the next one follows in
  the pulse gap (Wan et al. 2018: t = N·T − 10 µs before the next pulse, the frame's
  transmission time; here the pacer counts the laser's PRR clock ahead by the two frames a
  point takes to reach the head, through ``pulse_ahead``). A jump's point is held
  ``jump_delay`` µs (whole frames, at least one) with the laser off. The line speed is
  ``pitch × PRR / pulses_per_point``.

With the RTC's scanner delays (``delays=True``; SCANLAB RTC5/6), a mark's end point is held
longer: ``polygon_delay`` with the laser on when another mark follows, ``mark_delay`` with the
laser off when a jump follows; both in whole frames, rounded up, none for 0. A zero-length mark after a jump (a dot)
has no end point of its own, so no mark delay. The laser delays act on :attr:`laser` further on
(:class:`~.laser_delays.LaserDelays`).

This needs at most one pulse per frame: the PRR must not exceed the frame rate (100 kHz at
XY2-100), as Wan et al. say. Above it a point would get more pulses than asked.

The pacer's decision for a frame, :attr:`laser`, applies from the moment that frame has been
sent; the system top delays it by two frames to the laser's ``marking`` input.
"""

from amaranth.hdl import Cat, Module, Mux, Signal
from amaranth.lib import data, stream, wiring
from amaranth.lib.wiring import In, Out

from ..fields import IOKind, VectorOp
from ..points import FIELD_CENTRE, OffsetPoint
from .dda import DIRECTION_BITS, Direction, LineDDA


__all__ = ["VectorSequencer", "DirectedVectorSequencer", "VectorCommand",
           "DelayedVectorCommand", "VecOpWord", "PixelVecOpWord", "PixelVectorCommand",
           "IOVecOpWord", "IOVectorCommand", "IOWord", "io_word",
           "PIXELS_PER_WORD", "command_layout", "OP_JUMP", "OP_MARK"]


#: ``op`` of a jump (move with the laser off) and of a mark (step a line with the laser on).
OP_JUMP, OP_MARK = VectorOp.JUMP, VectorOp.MARK

#: One queued segment: where to go, and how.
VectorCommand = data.StructLayout({"op": VectorOp, "x": 16, "y": 16})
#: The same with a mark's scaled corner hold in frames (``vec_op`` bits 7:1). The queue's block
#: RAMs are 8 bits wide, so its 33 bits already take 40: the field costs no RAM.
DelayedVectorCommand = data.StructLayout({"op": VectorOp, "x": 16, "y": 16, "corner_frames": 7})
#: The ``vec_op`` register's word: the op, and (builds with the RTC delays) the corner hold.
VecOpWord = data.StructLayout({"op": VectorOp, "corner_frames": 7})
#: The same in a build with pixel lines (bit 8, ``pixels``): a mark with it is a **pixel
#: line**, whose points are marked or not by the pixel bits that follow it in the queue; a
#: jump with it is a **pixel word**, 32 of those bits (``x`` the first 16, bit 0 first, ``y``
#: the next), which moves nothing.
PixelVecOpWord = data.StructLayout({"op": VectorOp, "corner_frames": 7, "pixels": 1})
#: A queued command of a build with pixel lines (which has the RTC delays).
PixelVectorCommand = data.StructLayout({"op": VectorOp, "x": 16, "y": 16, "corner_frames": 7,
                                        "pixels": 1})
#: The ``vec_op`` word of a build with I/O in the queue (bit 9, ``io``): with ``io`` set, the
#: word's bits 8:0 are an :data:`IOWord`, and ``vec_x``, ``vec_y`` its arguments.
IOVecOpWord = data.StructLayout({"op": VectorOp, "corner_frames": 7, "pixels": 1, "io": 1})
#: A queued command of a build with I/O in the queue (which has pixel lines).
IOVectorCommand = data.StructLayout({"op": VectorOp, "x": 16, "y": 16, "corner_frames": 7,
                                     "pixels": 1, "io": 1})
#: Bits 8:0 of an I/O word: what it does (:class:`~..fields.IOKind`), on which input, output
#: or encoder (``index``), and at which level; ``edge``: a wait for an input to come to the
#: level, not to be at it.
IOWord = data.StructLayout({"kind": IOKind, "index": 1, "level": 1, "edge": 1, "_": 3})
#: Pixels one pixel word carries.
PIXELS_PER_WORD = 32


def io_word(command):
    """The :data:`IOWord` view of a queued :data:`IOVectorCommand`: an I/O word's bits 8:0
    are the op, corner-hold and pixels fields of a segment's."""
    return IOWord(Cat(command.op, command.corner_frames, command.pixels))



def command_layout(*, delays, pixel_lines=False, queue_io=False):
    """The layout of a queued command in a build with (or without) the delays, pixel
    lines (which need the delays) and I/O in the queue (which needs pixel lines)."""
    if pixel_lines and not delays:
        raise ValueError("pixel lines come with vector mode's delays")
    if queue_io and not pixel_lines:
        raise ValueError("I/O in the queue comes with pixel lines (their vec_op word)")
    if queue_io:
        return IOVectorCommand
    return PixelVectorCommand if pixel_lines else DelayedVectorCommand if delays else \
        VectorCommand


class VectorSequencer(wiring.Component):
    """Vector marking from a queue of segments.

    Interface attributes
    --------------------
    commands : ``In(stream.Signature(VectorCommand))``
        The queue (a FIFO in the system top).
    frame_strobe : ``In(1)``
        The PHY's frame strobe (its position is taken on that clock).
    pulse_ahead : ``In(1)``
        The laser's PRR rising edges, two frames and one clock early.
    run : ``In(1)``
        Hand points on while high; while low the mirrors hold and the laser is off (the queue
        and the position are kept).
    pitch : ``In(16)``
        Galvo units between marked points.
    pulses_per_point : ``In(8)``
        Laser pulses each marked point gets (0 is taken as 1).
    jump_delay : ``In(16)``
        µs a jump's end point is held with the laser off (whole frames, at least one).
    mark_delay, polygon_delay : ``In(12)``, when ``delays``
        µs a mark's end point is held before a jump (laser off) or another mark (laser on).
    polygon_scaled : ``In(1)``, when ``delays``
        Hold each corner for the frames sent with the mark that leaves it instead.
    points : ``Out(stream.Signature(OffsetPoint))``
        To the scale stage: offsets from the field centre (position − 32768).
    laser : ``Out(1)``
        Laser wanted during the frame decided at the last strobe.
    underrun : ``Out(1)``
        One clock when a marked point's pulses are done and the queue has run empty (the
        mirrors hold with the laser off until more segments come).
    busy : ``Out(1)``
        Segments are queued, being stepped, or a point is still being held.
    stall : ``Out(1)``
        One clock when a marked point's pulses are done and the next segment is still being
        set up (the mirrors hold with the laser off for a frame). Set-up takes 140 clocks,
        so at 12 MHz and XY2-100 (120 clocks a frame) only a one-point segment after another
        one-point segment can stall.

    Parameters
    ----------
    frame_us : int
        µs a frame lasts (10 at XY2-100).
    delays : bool
        Build the mark and polygon delays.
    pixel_lines : bool
        Build pixel lines (needs ``delays``): a mark queued with ``pixels`` set is stepped as
        any mark, at the pitch, each point held for ``pulses_per_point`` pulses, but each
        point's laser is the next bit of the pixel words queued after it (bit 0 of the first
        word for its first point), so the mirrors sweep the line at one speed and every dark
        pixel gets the same pulses. A bit can only keep the laser off: a point is lit only if
        its line would light it without the bits. Where the words run out (the queue's next
        command is no pixel word) the rest of the line is stepped dark; where the queue is
        empty the line waits for them (a stall). A pixel word anywhere else is dropped.
    """

    def __init__(self, *, frame_us=10, delays=False, pixel_lines=False):
        self.frame_us = frame_us
        self.delays = delays
        self.pixel_lines = pixel_lines
        members = {
            "commands": In(stream.Signature(command_layout(delays=delays,
                                                           pixel_lines=pixel_lines))),
            "frame_strobe": In(1), "pulse_ahead": In(1), "run": In(1),
            "pitch": In(16), "pulses_per_point": In(8), "jump_delay": In(16),
            "points": Out(stream.Signature(OffsetPoint)),
            "laser": Out(1), "underrun": Out(1), "stall": Out(1), "busy": Out(1),
        }
        if delays:
            members.update({"mark_delay": In(12), "polygon_delay": In(12),
                            "polygon_scaled": In(1)})
        if self.with_direction:
            members["direction"] = Out(Direction, init={"ux": 1 << DIRECTION_BITS})
        super().__init__(members)
        # State the pixel-line proof's helper invariants name (galvoscan.formal.vector).
        # (Named as the locals they stand for: a build without pixel lines is the same
        # netlist, name for name, as before them.)
        self._slot_valid = Signal(name="slot_valid")            # a point waits in the slot
        self._slot_mark = Signal(name="slot_mark")              # a marked point (mark or line)
        self._slot_gate = Signal(init=1, name="slot_gate")      # its bit (1 off a pixel line)
        self._holding_mark = Signal(name="holding_mark")        # a marked point is held
        self._held_gate = Signal(name="held_gate")              # the point held is lit
        self._pixel_line = Signal(name="pixel_line")            # stepping a pixel line
        self._pixel_bits = Signal(PIXELS_PER_WORD, name="pixel_bits")
        self._stepping = Signal(name="stepping")                # stepping a line (pixel builds)

    def _line_dda(self):
        """The line interpolator (the pixel-line proof puts a free one in its place)."""
        return LineDDA(direction=self.with_direction)

    #: Hand each point's line direction on (:class:`DirectedVectorSequencer`).
    with_direction = False

    def elaborate(self, platform):
        m = Module()
        m.submodules.dda = dda = self._line_dda()
        m.d.comb += dda.pitch.eq(self.pitch)

        # --- point generator ----------------------------------------------------------------
        cur_x = Signal(16, init=FIELD_CENTRE)      # where the last command ended
        cur_y = Signal(16, init=FIELD_CENTRE)
        pen_down = Signal()                        # the last point handed on was marked
        slot_valid = self._slot_valid
        slot_x = Signal(16)
        slot_y = Signal(16)
        slot_mark = self._slot_mark
        slot_end = Signal()                        # the slot's point ends a mark segment
        slot_gate = self._slot_gate                # the slot's pixel bit (1 off a pixel line)
        corner_frames = Signal(7)                         # the corner hold (frames) of the last mark
        taken = Signal()                           # the pacer takes the slot this clock

        with m.If(taken):
            m.d.sync += slot_valid.eq(0)

        segment_valid = Signal()
        # A segment ends where the sequencer stands once it has been queued (no copy).
        m.d.comb += [dda.segment.valid.eq(segment_valid),
                     dda.segment.payload.x1.eq(cur_x), dda.segment.payload.y1.eq(cur_y)]
        with m.If(dda.segment.ready):
            m.d.sync += segment_valid.eq(0)

        # A slot the pacer takes is free from the next clock, not this one: the pacer's
        # once-a-frame decision then ends at the slot's flip-flop instead of running on into
        # the DDA's handshake and the queue's read enable (the design's longest path). The
        # pacer takes at most one point a frame, so the clock this costs is never seen.
        slot_free = ~slot_valid
        command = self.commands.payload
        fetching = Signal()

        # Pixel lines: the bits of the line being stepped, and whether a point may be made.
        if self.pixel_lines:
            pixel_line = self._pixel_line
            start_pending = Signal()    # its first point (the pen was up) is still to be made
            pixel_bits = self._pixel_bits
            bits_left = Signal(range(PIXELS_PER_WORD + 1))
            is_word = Signal()          # the queue's next command is a pixel word
            bit_ready = Signal()        # a point may be made: off a line, or its bit known
            gate_bit = Signal()         # the bit of the next point made
            take_bit = Signal()         # a point is made this clock: its bit is used
            m.d.comb += [
                is_word.eq(self.commands.valid & command.pixels & (command.op == OP_JUMP)),
                # A bit in hand; or none will come (the next command is no pixel word: the
                # rest of the line is dark). With the queue empty the point waits.
                bit_ready.eq(~pixel_line | (bits_left != 0) |
                             (self.commands.valid & ~is_word)),
                gate_bit.eq(~pixel_line | ((bits_left != 0) & pixel_bits[0])),
            ]
            with m.If(take_bit & pixel_line & (bits_left != 0)):
                m.d.sync += [pixel_bits.eq(pixel_bits >> 1), bits_left.eq(bits_left - 1)]

        with m.FSM():
            with m.State("FETCH"):
                m.d.comb += fetching.eq(~segment_valid & ~dda.busy)
                take = self.commands.valid & slot_free & ~segment_valid & ~dda.busy
                if self.pixel_lines:
                    with m.If(take & is_word):
                        # A word past the end of its line (or of none): dropped.
                        m.d.comb += self.commands.ready.eq(1)
                    taking = m.Elif(take)
                else:
                    taking = m.If(take)
                with taking:
                    with m.If(command.op == OP_JUMP):
                        m.d.comb += self.commands.ready.eq(1)
                        m.d.sync += [
                            slot_valid.eq(1), slot_x.eq(command.x), slot_y.eq(command.y),
                            slot_mark.eq(0),
                            pen_down.eq(0), cur_x.eq(command.x), cur_y.eq(command.y),
                        ]
                        if self.pixel_lines:
                            m.d.sync += [slot_gate.eq(1), pixel_line.eq(0)]
                    with m.Else():
                        m.d.comb += self.commands.ready.eq(1)
                        if self.delays:
                            m.d.sync += corner_frames.eq(command.corner_frames)
                        # The line from where we are; its start is marked first if the laser
                        # was off.
                        m.d.sync += [
                            dda.segment.payload.x0.eq(cur_x), dda.segment.payload.y0.eq(cur_y),
                            segment_valid.eq(1),
                            cur_x.eq(command.x), cur_y.eq(command.y),
                            pen_down.eq(1),
                        ]
                        if self.pixel_lines:
                            # A pixel line's first point waits for its bit, in STEP.
                            m.d.sync += [pixel_line.eq(command.pixels), bits_left.eq(0)]
                            with m.If(~pen_down & command.pixels):
                                m.d.sync += start_pending.eq(1)
                            with m.Elif(~pen_down):
                                m.d.sync += [slot_valid.eq(1), slot_x.eq(cur_x),
                                             slot_y.eq(cur_y), slot_mark.eq(1), slot_end.eq(0),
                                             slot_gate.eq(1)]
                        else:
                            with m.If(~pen_down):
                                m.d.sync += [slot_valid.eq(1), slot_x.eq(cur_x),
                                             slot_y.eq(cur_y), slot_mark.eq(1), slot_end.eq(0)]
                        m.next = "STEP"
            with m.State("STEP"):
                if self.pixel_lines:
                    m.d.comb += self._stepping.eq(1)
                    # The line's next pixel word, when its last bit has been used.
                    with m.If(pixel_line & (bits_left == 0) & is_word):
                        m.d.comb += self.commands.ready.eq(1)
                        m.d.sync += [pixel_bits.eq(Cat(command.x, command.y)),
                                     bits_left.eq(PIXELS_PER_WORD)]
                    m.d.comb += dda.points.ready.eq(slot_free & ~start_pending & bit_ready)
                    with m.If(start_pending & slot_free & bit_ready):
                        m.d.comb += take_bit.eq(1)
                        m.d.sync += [slot_valid.eq(1), slot_x.eq(dda.segment.payload.x0),
                                     slot_y.eq(dda.segment.payload.y0), slot_mark.eq(1),
                                     slot_end.eq(0), slot_gate.eq(gate_bit),
                                     start_pending.eq(0)]
                    with m.Elif(dda.points.valid & slot_free & ~start_pending & bit_ready):
                        m.d.comb += take_bit.eq(1)
                        m.d.sync += [slot_valid.eq(1), slot_x.eq(dda.points.payload.x),
                                     slot_y.eq(dda.points.payload.y), slot_mark.eq(1),
                                     slot_end.eq(dda.last), slot_gate.eq(gate_bit)]
                    with m.Elif(~segment_valid & ~dda.busy & ~start_pending):
                        m.next = "FETCH"
                else:
                    m.d.comb += dda.points.ready.eq(slot_free)
                    with m.If(dda.points.valid & slot_free):
                        m.d.sync += [slot_valid.eq(1), slot_x.eq(dda.points.payload.x),
                                     slot_y.eq(dda.points.payload.y), slot_mark.eq(1),
                                     slot_end.eq(dda.last)]
                    with m.Elif(~segment_valid & ~dda.busy):
                        m.next = "FETCH"

        # --- pacer --------------------------------------------------------------------------
        holding_mark = self._holding_mark
        waiting = Signal()          # a point is held for a time: a jump's, or a mark's end
        held_end = Signal()         # the marked point held ends a mark segment
        held_gate = self._held_gate
        pulses = Signal(8)          # early PRR edges since the held point was handed on
        waited = Signal(17)         # µs of whole frames the wait has lasted by the next strobe
        pulses_now = Signal(8)
        m.d.comb += pulses_now.eq(pulses + (self.pulse_ahead & (pulses != 0xFF)))
        # The pulses a point needs, from a flip-flop: a new pulses_per_point counts from the
        # clock after it is written.
        need = Signal(8, init=1)
        m.d.sync += need.eq(self.pulses_per_point | (self.pulses_per_point == 0))
        # `pulses >= need` and `pulses >= need - 1`, worked out a clock ahead from the count's
        # next value, so that the frame strobe's decision (into the point handed on) waits on
        # no comparator: that was the full build's longest path.
        reached = Signal()
        short = Signal(init=1)
        m.d.sync += [reached.eq(pulses_now >= need), short.eq(pulses_now >= need - 1)]
        # What the current wait lasts, in µs: a jump's, or (delays) a mark end's.
        wait_us = Signal(16)
        m.d.comb += wait_us.eq(self.jump_delay)

        with m.If(self.points.ready):
            m.d.sync += self.points.valid.eq(0)
        if self.with_direction:
            # Each point keeps the direction the DDA had when it took the point.
            slot_direction = Signal(Direction)
            with m.If(~slot_valid):
                m.d.sync += slot_direction.eq(dda.direction)
            with m.If(taken):
                m.d.sync += self.direction.eq(slot_direction)
        m.d.comb += self.busy.eq(self.commands.valid | ~fetching | slot_valid | holding_mark |
                                 waiting)

        # A held mark end goes on to a polygon wait (another mark next) or a mark-delay wait
        # (a jump next); neither for a 0 delay or a 0 corner hold.
        to_polygon = Signal()
        to_mark_delay = Signal()
        if self.delays:
            WAIT_JUMP, WAIT_MARK, WAIT_POLYGON = range(3)
            wait_kind = Signal(2)
            # A scaled corner's hold comes with its mark, in frames, worked out by the host
            # (which knows the angle): no multiplier here.
            polygon_us = Mux(self.polygon_scaled, corner_frames * self.frame_us, self.polygon_delay)
            with m.Switch(wait_kind):
                with m.Case(WAIT_MARK):
                    m.d.comb += wait_us.eq(self.mark_delay)
                with m.Case(WAIT_POLYGON):
                    m.d.comb += wait_us.eq(polygon_us)
            at_end = holding_mark & held_end & slot_valid
            m.d.comb += [
                to_polygon.eq(at_end & slot_mark & Mux(self.polygon_scaled, corner_frames != 0,
                                                       self.polygon_delay != 0)),
                to_mark_delay.eq(at_end & ~slot_mark & (self.mark_delay != 0)),
            ]

        m.d.sync += pulses.eq(pulses_now)
        # `waited >= wait_us` from a flip-flop too: `waited` changes only on frame strobes,
        # and the wait's length only with the registers or on a strobe, a frame or more before
        # the next strobe asks.
        waited_enough = Signal()
        m.d.sync += waited_enough.eq(waited >= wait_us)
        with m.If(self.frame_strobe):
            # pulses_now >= need, with the late-arriving pulse_ahead kept off the adder and the
            # comparator (a long path otherwise): the count so far reaches it, or falls one
            # short and a pulse is coming now.
            enough = reached | (self.pulse_ahead & short)
            done = (~holding_mark | enough) & \
                   (~waiting | waited_enough)
            with m.If(~self.run):
                m.d.sync += [self.laser.eq(0), holding_mark.eq(0), waiting.eq(0)]
            with m.Elif(done & (to_polygon | to_mark_delay)):
                # The mirrors catch up with the end point: the laser stays on into a corner,
                # goes off before a jump.
                # (A pixel line's dark end point keeps it off into the corner too.)
                m.d.sync += [waiting.eq(1), holding_mark.eq(0), waited.eq(self.frame_us),
                             self.laser.eq(to_polygon & held_gate if self.pixel_lines
                                           else to_polygon)]
                if self.delays:
                    m.d.sync += wait_kind.eq(Mux(to_polygon, WAIT_POLYGON, WAIT_MARK))
            with m.Elif(done & slot_valid):
                m.d.comb += taken.eq(1)
                m.d.sync += [
                    self.points.valid.eq(1),
                    # Offset binary to an offset from the centre: flip the top bit.
                    self.points.payload.x.eq(Cat(slot_x[:15], ~slot_x[15])),
                    self.points.payload.y.eq(Cat(slot_y[:15], ~slot_y[15])),
                    # A pixel bit can only keep a marked point dark.
                    self.laser.eq(slot_mark & slot_gate if self.pixel_lines else slot_mark),
                    holding_mark.eq(slot_mark),
                    held_end.eq(slot_end),
                    waiting.eq(~slot_mark),
                    pulses.eq(0),
                    reached.eq(0),                  # 0 >= need (need is at least 1)
                    short.eq(need == 1),            # 0 >= need - 1
                    waited.eq(self.frame_us),
                ]
                if self.delays:
                    m.d.sync += wait_kind.eq(WAIT_JUMP)
                if self.pixel_lines:
                    m.d.sync += held_gate.eq(slot_gate)
            with m.Elif(done):
                # Nothing to go on with: hold here with the laser off.
                # (A pixel line waiting for its next word is waiting on the queue too.)
                queue_empty = ((fetching | ~bit_ready) if self.pixel_lines else fetching) & \
                    ~self.commands.valid
                m.d.comb += [self.underrun.eq(holding_mark & queue_empty),
                             self.stall.eq(holding_mark & ~queue_empty)]
                m.d.sync += [self.laser.eq(0), holding_mark.eq(0), waiting.eq(0)]
            with m.Else():
                m.d.sync += waited.eq(waited + Mux(waited[-1], 0, self.frame_us))
        return m


class DirectedVectorSequencer(VectorSequencer):
    """A :class:`VectorSequencer` that hands on the direction of each point's line too.

    Interface attributes
    --------------------
    direction : ``Out(Direction)``
        The direction of the line the point on :attr:`points` lies on, held with the point (see
        :class:`~.dda.LineDDA`): a mark's first point, and a line no longer than the pitch,
        carry the direction of the last line longer than the pitch.

    Working the direction out makes a segment's set-up 166 clocks rather than 140.
    """

    with_direction = True
