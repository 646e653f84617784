"""I/O inside a job: the queue's waits and outputs, between the vector queue and the vector
sequencer (SCANLAB RTC5/6's list commands ``wait_for_input``-style waits, ``write_io_port``,
``wait_for_encoder``, ``set_fly_x`` and ``fly_return``, in the queue's own words).

A queued command with ``io`` set (``vec_op`` bit 9) is an **I/O word**
(:data:`~.vector.IOWord`). It moves nothing. It waits at the head of the queue until every
segment before it is marked (the sequencer idle: the laser is off), then:

* ``WAIT_INPUT``: waits for input ``index`` (after a two-flip-flop synchroniser) to be at
  ``level`` (with ``edge``: to come to it, from a moment it is not, counted from the word's
  start: a part already under the sensor is not taken twice); ``vec_x`` ms at most (0: no
  limit). A wait that runs out **times out**: latched (``timed_out``) until the queue is
  flushed, it holds the queue for good, and the system top stops the job as a laser fault
  does (the job player sees a fault; the host reads it in the ``io`` register).
* ``SET_OUTPUT``: sets output ``index`` to ``level``, for ``vec_x`` frames (10 µs) and then
  back (0: until another word changes it). Outputs keep their level through a flush (a PLC
  may still be reading them) and go low only on a soft reset.
* ``WAIT_COUNT_UP`` / ``WAIT_COUNT_DOWN``: waits for encoder ``index`` (0 X, 1 Y) to reach
  ``vec_y:vec_x`` (signed 32 bits) or more / or less (builds with marking on the fly).
* ``FLY_START``: clears both encoders' counts and turns the fly offset on; ``FLY_END`` turns
  it off (builds with marking on the fly).

Any other word is passed to the sequencer as it is, as soon as it is at the head of the queue:
the stage adds no clock to a segment. Since the sequencer's busy includes a command waiting
for it, and an I/O word is never shown to it, its busy is its own work only.

A pixel line is followed by its pixel words: one followed by an I/O word instead waits for
them as for an empty queue (the host puts a jump between them).
"""

from amaranth.hdl import Cat, Module, Mux, Signal, signed
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out

from ..fields import IOKind, IOState
from .vector import IOVectorCommand, PixelVectorCommand, io_word


__all__ = ["QueueIO", "IO_INPUTS", "IO_OUTPUTS"]


#: Inputs (``io_in``) and outputs (``io_out``) a build with I/O in the queue has.
IO_INPUTS = IO_OUTPUTS = 2


class QueueIO(wiring.Component):
    """The queue's I/O words, done between the vector queue and the vector sequencer.

    Parameters
    ----------
    frame_us : int
        µs a frame lasts (10 at XY2-100): the frame strobe times the waits and the pulses.
    encoders : bool
        The build marks on the fly: the count waits and the fly words act. Without it they are
        done at once (they do nothing; the host sends none to such a board).

    Interface attributes
    --------------------
    commands_in : ``In(stream.Signature(IOVectorCommand))``
        The vector queue's commands.
    commands_out : ``Out(stream.Signature(PixelVectorCommand))``
        To the sequencer: every command that is no I/O word.
    sequencer_busy : ``In(1)``
        The sequencer is marking (its ``busy``).
    frame_strobe : ``In(1)``
        The PHY's frame strobe: a tick each frame.
    flush : ``In(1)``
        ``vec_flush`` (or a soft reset): a held word is dropped, a time-out cleared; the
        outputs keep their level.
    io_in : ``In(2)``
        The input pins (a part sensor …), 1 = high; synchronised here.
    io_out : ``Out(2)``
        The output pins.
    count_x, count_y : ``In(signed(32))``, with ``encoders``
        The encoders' counts.
    fly_clear : ``Out(1)``, with ``encoders``
        One clock: clear the encoders' counts (``FLY_START``).
    fly_on : ``Out(1)``, with ``encoders``
        The queue has turned the fly offset on (``FLY_START`` … ``FLY_END``; low after a
        flush).
    holding : ``Out(1)``
        An I/O word is at the head of the queue (the sequencer sees the queue empty: that is
        no underrun).
    timed_out : ``Out(1)``
        Latched until a flush: a wait for an input ran out of time.
    state : ``Out(IOState)``
        The ``io`` register.
    """

    def __init__(self, *, frame_us=10, encoders=False):
        if not isinstance(frame_us, int) or frame_us <= 0 or 1000 % frame_us:
            raise ValueError(f"frame_us must be a whole number of µs that divides 1000, not "
                             f"{frame_us!r}")
        self.frame_us = frame_us
        self.encoders = bool(encoders)
        members = {
            "commands_in": In(stream.Signature(IOVectorCommand)),
            "commands_out": Out(stream.Signature(PixelVectorCommand)),
            "sequencer_busy": In(1), "frame_strobe": In(1), "flush": In(1),
            "io_in": In(IO_INPUTS), "io_out": Out(IO_OUTPUTS),
            "holding": Out(1), "timed_out": Out(1), "state": Out(IOState),
        }
        if self.encoders:
            members.update({"count_x": In(signed(32)), "count_y": In(signed(32)),
                            "fly_clear": Out(1), "fly_on": Out(1)})
        super().__init__(members)
        # State the proof's helper invariants name (galvoscan.formal.queue_io).
        self._in_wait_input = Signal(name="in_wait_input")  # waiting for an input
        self._in_count = Signal(name="in_count")            # waiting for a count
        self._seen_away = Signal(name="seen_away")          # the input was away from the level
        self._limited = Signal(name="limited")              # the wait has a time limit

    def elaborate(self, platform):
        m = Module()
        command = self.commands_in.payload
        word = io_word(command)
        is_io = self.commands_in.valid & command.io

        # Every other command straight through.
        m.d.comb += [
            self.commands_out.payload.eq(command.as_value()[:PixelVectorCommand.size]),
            self.commands_out.valid.eq(self._to_sequencer(self.commands_in.valid, command.io)),
            self.holding.eq(is_io),
        ]
        pop = Signal()          # the I/O word at the head is done
        m.d.comb += self.commands_in.ready.eq(Mux(command.io, pop, self.commands_out.ready))

        # The inputs through two flip-flops.
        inputs_meta, inputs = Signal(IO_INPUTS), Signal(IO_INPUTS)
        m.d.sync += [inputs_meta.eq(self.io_in), inputs.eq(inputs_meta)]

        # The outputs, and each one's pulse: frames left before it goes back (0: held).
        outputs = Signal(IO_OUTPUTS)
        pulse_left = [Signal(16, name=f"pulse_left_{k}") for k in range(IO_OUTPUTS)]
        for k, left in enumerate(pulse_left):
            with m.If(self.frame_strobe & (left != 0)):
                m.d.sync += left.eq(left - 1)
                with m.If(left == 1):
                    m.d.sync += outputs[k].eq(~outputs[k])
        m.d.comb += self.io_out.eq(outputs)

        # A wait for an input: ms left (and frames into the ms), whether the input was seen
        # away from the level (an edge wait).
        frames_per_ms = 1000 // self.frame_us
        ms_left = Signal(16)
        limited = self._limited
        frames = Signal(range(frames_per_ms))
        seen_away = self._seen_away
        timed_out = self.timed_out
        fly_on = Signal()
        if self.encoders:
            m.d.comb += self.fly_on.eq(fly_on)
        target = Signal(signed(32))
        count = Signal(signed(32))
        if self.encoders:
            m.d.sync += count.eq(Mux(word.index, self.count_y, self.count_x))
        # The count's comparisons a clock behind it: no 32-bit compare in one clock's path
        # with the multiplexer (the count moves at most a step a clock; a wait ends a clock
        # later).
        at_or_above, at_or_below = Signal(), Signal()
        m.d.sync += [at_or_above.eq(count >= target), at_or_below.eq(count <= target)]

        input_now = inputs.bit_select(word.index, 1)
        with m.FSM() as fsm:
            with m.State("PASS"):
                # (Not while the queue is flushed: the word is gone with it.)
                with m.If(is_io & self._idle() & ~self.flush):
                    with m.Switch(word.kind):
                        with m.Case(IOKind.WAIT_INPUT):
                            m.d.sync += [ms_left.eq(command.x), limited.eq(command.x != 0),
                                         frames.eq(0), seen_away.eq(~word.edge)]
                            m.next = "WAIT_INPUT"
                        with m.Case(IOKind.SET_OUTPUT):
                            m.d.comb += pop.eq(1)
                            for k in range(IO_OUTPUTS):
                                with m.If(word.index == k):
                                    m.d.sync += [outputs[k].eq(word.level),
                                                 pulse_left[k].eq(command.x)]
                        with m.Case(IOKind.WAIT_COUNT_UP, IOKind.WAIT_COUNT_DOWN):
                            if self.encoders:
                                m.d.sync += target.eq(Cat(command.x, command.y))
                                m.next = "SETTLE"
                            else:
                                m.d.comb += pop.eq(1)
                        with m.Case(IOKind.FLY_START):
                            m.d.comb += pop.eq(1)
                            if self.encoders:
                                m.d.comb += self.fly_clear.eq(1)
                                m.d.sync += fly_on.eq(1)
                        with m.Case(IOKind.FLY_END):
                            m.d.comb += pop.eq(1)
                            m.d.sync += fly_on.eq(0)
                        with m.Default():
                            m.d.comb += pop.eq(1)
            with m.State("WAIT_INPUT"):
                with m.If(input_now != word.level):
                    m.d.sync += seen_away.eq(1)
                with m.If(~is_io):
                    m.next = "PASS"                         # (its word gone: a reset)
                with m.Elif(self._held(timed_out)):
                    pass                                    # held until a flush
                with m.Elif(self._reached(input_now, word.level, seen_away)):
                    m.d.comb += pop.eq(1)
                    m.next = "PASS"
                with m.Elif(self.frame_strobe & limited):
                    with m.If(frames == frames_per_ms - 1):
                        m.d.sync += [frames.eq(0), ms_left.eq(ms_left - 1)]
                        with m.If(ms_left == 1):
                            m.d.sync += timed_out.eq(1)
                    with m.Else():
                        m.d.sync += frames.eq(frames + 1)
                with m.If(self.flush):
                    m.next = "PASS"
            with m.State("SETTLE"):
                # (A clock for the new target to reach the comparisons' flip-flops.)
                m.next = "WAIT_COUNT"
                with m.If(self.flush):
                    m.next = "PASS"
            with m.State("WAIT_COUNT"):
                with m.If(~is_io):
                    m.next = "PASS"
                with m.Elif(Mux(word.kind == IOKind.WAIT_COUNT_UP, at_or_above, at_or_below)):
                    m.d.comb += pop.eq(1)
                    m.next = "PASS"
                with m.If(self.flush):
                    m.next = "PASS"

        with m.If(self.flush):
            m.d.sync += [timed_out.eq(0), fly_on.eq(0)]
        m.d.comb += [self._in_wait_input.eq(fsm.ongoing("WAIT_INPUT")),
                     self._in_count.eq(fsm.ongoing("SETTLE") | fsm.ongoing("WAIT_COUNT"))]

        m.d.comb += [
            self.state.inputs.eq(inputs),
            self.state.outputs.eq(outputs),
            self.state.waiting.eq(is_io),
            self.state.timed_out.eq(timed_out),
        ]
        return m

    # (The rules the proof checks, as methods: the broken designs change one each.)
    def _to_sequencer(self, valid, io):
        """A command is shown to the sequencer: any but an I/O word."""
        return valid & ~io

    def _idle(self):
        """An I/O word may start: every segment before it is marked."""
        return ~self.sequencer_busy

    def _reached(self, input_now, level, seen_away):
        """A wait for an input ends: at the level (an edge wait: having been away)."""
        return seen_away & (input_now == level)

    def _held(self, timed_out):
        """A wait that timed out holds the queue."""
        return timed_out

