"""The vector queue: the segments written to ``vec_op`` (by the host or the job player),
waiting in block RAM for the vector sequencer.

A write of ``vec_op`` queues one command, ``(op, x, y)``: the register file refuses the write
while the queue is full (:attr:`~VectorQueue.ready` low), and counts the refusal. A host's
segment carries its end point in the very frame that queues it (one checked frame: never an
old ``vec_x`` or ``vec_y``); the player's come from the ``vec_x`` and ``vec_y`` registers.
"""

from amaranth.hdl import Module, Mux, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.fifo import SyncFIFOBuffered
from amaranth.lib.wiring import In, Out, connect

from .vector import IOVecOpWord, PixelVecOpWord, VecOpWord, command_layout


__all__ = ["VectorQueue"]


class VectorQueue(wiring.Component):
    """Queue of vector commands between the register file and the vector sequencer.

    Reset it (``ResetInserter``) to flush what it holds.

    Parameters
    ----------
    depth : int
        Segments it holds.
    delays : bool
        The build has vector mode's RTC delays: ``vec_op`` is a :data:`VecOpWord` (op and
        corner hold) and the commands :data:`DelayedVectorCommand`; else ``vec_op`` is the op
        alone and the commands :data:`VectorCommand`.
    pixel_lines : bool
        The build has pixel lines (and the delays): ``vec_op`` is a :data:`PixelVecOpWord`,
        the commands :data:`PixelVectorCommand`.
    queue_io : bool
        The build has I/O in the queue (and pixel lines): ``vec_op`` is an
        :data:`IOVecOpWord`, the commands :data:`IOVectorCommand`.

    Interface attributes
    --------------------
    vec_op : ``In(IOVecOpWord)`` with I/O, ``In(PixelVecOpWord)`` with pixel lines, ``In(VecOpWord)`` with delays, else ``In(1)``
        The ``vec_op`` register, the value being pushed while :attr:`push` is high.
    push : ``In(1)``
        A write of ``vec_op`` the register file took (only while :attr:`ready`).
    segment : ``In(1)``; segment_x, segment_y : ``In(16)``
        The command decoder's: the write is a host segment, and its end point, galvo units.
    vec_x, vec_y : ``In(16)``
        The registers: the end point of a write that is no host segment (the player's).
    ready : ``Out(1)``
        Room for one more command (the register file's ``vec_op_ready``).
    free : ``Out(16)``
        Commands it has room for (the ``fifo_free`` register).
    empty : ``Out(1)``
        It holds no command.
    commands : ``Out(stream.Signature(command layout))``
        The queued commands, to the vector sequencer.
    """

    def __init__(self, *, depth, delays=False, pixel_lines=False, queue_io=False):
        if not isinstance(depth, int) or isinstance(depth, bool) or not 2 <= depth < 1 << 16:
            raise ValueError(f"depth must be a whole number from 2 to 65535, not {depth!r}")
        self.depth = depth
        self.delays = bool(delays)
        self.pixel_lines = bool(pixel_lines)
        self.queue_io = bool(queue_io)
        self.layout = command_layout(delays=self.delays, pixel_lines=self.pixel_lines,
                                     queue_io=self.queue_io)
        word = IOVecOpWord if self.queue_io else PixelVecOpWord if self.pixel_lines else \
            VecOpWord if self.delays else 1
        super().__init__({
            "vec_op": In(word),
            "push": In(1),
            "segment": In(1), "segment_x": In(16), "segment_y": In(16),
            "vec_x": In(16), "vec_y": In(16),
            "ready": Out(1), "free": Out(16), "empty": Out(1),
            "commands": Out(stream.Signature(self.layout)),
        })

    def elaborate(self, platform):
        m = Module()
        m.submodules.fifo = fifo = SyncFIFOBuffered(width=self.layout.size, depth=self.depth)
        command = Signal(self.layout)
        if self.delays:
            m.d.comb += command.corner_frames.eq(self.vec_op.corner_frames)
            op = self.vec_op.op
        if self.pixel_lines:
            m.d.comb += command.pixels.eq(self.vec_op.pixels)
        if self.queue_io:
            m.d.comb += command.io.eq(self.vec_op.io)
        if not self.delays:
            op = self.vec_op
        m.d.comb += [
            command.op.eq(op),
            command.x.eq(Mux(self.segment, self.segment_x, self.vec_x)),
            command.y.eq(Mux(self.segment, self.segment_y, self.vec_y)),
            fifo.w_stream.payload.eq(command),
            fifo.w_stream.valid.eq(self.push),
            self.ready.eq(fifo.w_stream.ready),
            self.free.eq(self.depth - fifo.level),
            self.empty.eq(fifo.level == 0),
        ]
        connect(m, fifo.r_stream, wiring.flipped(self.commands))
        return m
