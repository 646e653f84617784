"""I/O in the queue: an I/O word never reaches the sequencer, starts only once every segment
before it is marked, a wait for an input ends only at its level, a timed-out wait holds the
queue until a flush, and the outputs change only as the queue's words say."""

from amaranth.asserts import AnySeq
from amaranth.hdl import (Assert, Assume, ClockDomain, Cover, Elaboratable, Module,
                          ResetSignal, Signal)

from ..gateware.fields import IOKind
from ..gateware.sources.vector import PixelVectorCommand, io_word


__all__ = ["QueueIOSpec"]


class QueueIOSpec(Elaboratable):
    """The queue's I/O stage, for every sequence of commands (held at the queue's head until
    taken, as a FIFO's read port holds them, or dropped by a flush), of the sequencer's busy,
    the frame strobe, the inputs, the flush and the reset (all free).

    The spec keeps its own synchroniser of the inputs and its own record of the word at the
    head: whether the sequencer has been seen idle with it there, and whether its input has
    been away from the level since. Proved:

    * every command but an I/O word reaches the sequencer unchanged, with its handshake; an
      I/O word never does;
    * an I/O word is taken only once the sequencer has been idle with it at the head;
    * a wait for an input is taken only with the input at its level (an edge wait: having
      been away from it since the word started);
    * a wait that timed out is never taken, and stays timed out, until a flush or a reset;
      one with no limit (0 ms) never times out;
    * an output changes only on a set-output word (to its level), at a frame strobe (a
      pulse's end) or at a reset.
    """

    def __init__(self, stage, *, helpers=True):
        self.stage = stage
        self.helpers = helpers

    def elaborate(self, platform):
        m = Module()
        m.domains.sync = ClockDomain()
        m.submodules.dut = dut = self.stage
        reset = Signal()
        m.d.comb += [ResetSignal("sync").eq(reset), reset.eq(AnySeq(1))]
        command_in = dut.commands_in
        m.d.comb += [
            command_in.valid.eq(AnySeq(1)),
            command_in.payload.eq(AnySeq(len(command_in.payload.as_value()))),
            dut.commands_out.ready.eq(AnySeq(1)),
            dut.sequencer_busy.eq(AnySeq(1)),
            dut.frame_strobe.eq(AnySeq(1)),
            dut.flush.eq(AnySeq(1)),
            dut.io_in.eq(AnySeq(len(dut.io_in))),
        ]
        if dut.encoders:
            m.d.comb += [dut.count_x.eq(AnySeq(32)), dut.count_y.eq(AnySeq(32))]
        command = command_in.payload
        word = io_word(command)
        taken = command_in.valid & command_in.ready
        io_taken = taken & command.io

        # The queue's head: once shown, held until taken, unless flushed (or reset).
        shown = Signal()
        shown_payload = Signal.like(command.as_value())
        m.d.sync += [shown.eq(command_in.valid & ~command_in.ready & ~dut.flush),
                     shown_payload.eq(command.as_value())]
        # (A flush or a reset empties the queue on the clock after it.)
        m.d.comb += Assume(~shown | (command_in.valid & (command.as_value() == shown_payload)))

        # The spec's synchroniser.
        meta, inputs = Signal(len(dut.io_in)), Signal(len(dut.io_in))
        m.d.sync += [meta.eq(dut.io_in), inputs.eq(meta)]
        input_now = inputs.bit_select(word.index, 1)

        # The word at the head: the sequencer seen idle with it there; its input seen away.
        idle_seen, away_seen = Signal(), Signal()
        at_head = command_in.valid & command.io
        started = at_head & (idle_seen | ~dut.sequencer_busy)
        m.d.sync += [idle_seen.eq(started & ~taken & ~dut.flush),
                     away_seen.eq(started & ~taken & ~dut.flush &
                                  (away_seen | (input_now != word.level)))]


        out = dut.commands_out
        m.d.comb += [
            Assert(out.valid == (command_in.valid & ~command.io),
                   "every command but an I/O word reaches the sequencer; an I/O word never"),
            Assert(out.payload.as_value() == command.as_value()[:PixelVectorCommand.size],
                   "a command reaches the sequencer unchanged"),
            Assert(command.io | (command_in.ready == out.ready),
                   "a command reaches the sequencer unchanged"),
            Assert(~io_taken | started,
                   "an I/O word is taken only once the sequencer is idle with it at the head"),
            Assert(~io_taken | (word.kind != IOKind.WAIT_INPUT) |
                   ((input_now == word.level) & (~word.edge | away_seen)),
                   "a wait for an input ends only at its level (an edge: once away)"),
        ]

        # Timed out: never taken, and latched, until a flush or a reset.
        was_timed_out = Signal()
        m.d.sync += was_timed_out.eq(dut.timed_out & ~dut.flush & ~reset)
        m.d.comb += [
            Assert(~was_timed_out | ~io_taken | (word.kind != IOKind.WAIT_INPUT),
                   "a wait that timed out holds the queue until a flush"),
            Assert(~was_timed_out | reset | dut.timed_out,
                   "a wait that timed out holds the queue until a flush"),
        ]
        # A wait with no limit never times out (the word's limit is at the head while it waits).
        unlimited = Signal()
        m.d.comb += unlimited.eq(at_head & idle_seen & (word.kind == IOKind.WAIT_INPUT) &
                                 (command.x == 0))
        rose = Signal()
        m.d.comb += rose.eq(dut.timed_out & ~was_timed_out)
        m.d.comb += Assert(~(rose & unlimited & ~reset),
                           "a wait with no limit never times out")

        # The outputs: only a set-output word, a frame strobe (a pulse's end) or a reset.
        outputs_q = Signal(len(dut.io_out))
        set_k, set_level, set_now = Signal(), Signal(), Signal()
        strobe_q, reset_q = Signal(), Signal()
        m.d.sync += [outputs_q.eq(dut.io_out), set_k.eq(word.index), set_level.eq(word.level),
                     set_now.eq(io_taken & (word.kind == IOKind.SET_OUTPUT)),
                     strobe_q.eq(dut.frame_strobe), reset_q.eq(reset)]
        changed = Signal(len(dut.io_out))
        m.d.comb += changed.eq(dut.io_out ^ outputs_q)
        for k in range(len(dut.io_out)):
            by_word = set_now & (set_k == k)
            m.d.comb += [
                Assert(~changed[k] | by_word | strobe_q | reset_q,
                       "an output changes only by a set-output word, a pulse's end or a reset"),
                Assert(~by_word | reset_q | (dut.io_out[k] == set_level),
                       "a set-output word gives its output its level"),
            ]

        if self.helpers:
            # Helpers (proved too): the stage's record of a wait is the spec's.
            waiting_input, counting = dut._in_wait_input, dut._in_count
            m.d.comb += [
                Assert(waiting_input == (at_head & idle_seen & (word.kind == IOKind.WAIT_INPUT)),
                       "helper: a wait for an input is the word at the head's"),
                Assert(counting == (at_head & idle_seen &
                                    ((word.kind == IOKind.WAIT_COUNT_UP) |
                                     (word.kind == IOKind.WAIT_COUNT_DOWN))),
                       "helper: a wait for a count is the word at the head's"),
                Assert(~waiting_input | ~dut._seen_away | ~word.edge | away_seen,
                       "helper: the input seen away"),
                Assert(~waiting_input | (dut._limited == (command.x != 0)),
                       "helper: the limit"),
                Assert(~dut.timed_out | waiting_input, "helper: a time-out is a wait's"),
            ]

        m.d.comb += [
            Cover(io_taken & (word.kind == IOKind.WAIT_INPUT) & word.edge),
            Cover(rose),
            Cover(set_now & strobe_q & (dut.io_out != outputs_q)),
            Cover(out.valid & out.ready & command.pixels),
        ]
        return m
