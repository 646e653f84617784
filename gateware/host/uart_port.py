"""Command frames over a UART: bytes gathered into frames, replies sent back as bytes."""

from amaranth.hdl import Cat, Module, Mux, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.fifo import SyncFIFOBuffered
from amaranth.lib.wiring import In, Out

from .frames import BROKEN, FRAME_BITS, CommandFrame
from .uart import UARTReceiver, UARTTransmitter


__all__ = ["UARTCommandPort", "REPLY_QUEUE_DEPTH"]


#: Replies the UART port queues (block RAM).
REPLY_QUEUE_DEPTH = 257


class UARTCommandPort(wiring.Component):
    """Frames of four bytes over 8N1 serial.

    Bytes are gathered four to a frame. A pause of more than ``gap_chars`` character times
    ends a frame early: the bytes gathered so far are handed on as a frame cut short (so the
    decoder counts it) and the next byte starts a new frame. A host that loses a byte therefore
    loses only that frame, as long as it pauses before the next. A byte with a bad stop bit
    spoils the frame it belongs to.

    Replies (four bytes each) are queued in block RAM, :data:`REPLY_QUEUE_DEPTH` deep (a queue
    that deep costs two RAM blocks and fewer logic cells than a four-deep one in flip-flops), or
    ``reply_depth`` deep; the decoder does not answer a read while the queue is full (a host
    that waits for each answer, as the client does, never meets that).

    Parameters
    ----------
    divisor : int
        System clocks per bit.
    reply_depth : int
        Replies queued (1: one being sent; the smallest boards).
    gap_chars : int
        Pause, in character times (10 bits), that ends a frame.

    Interface attributes
    --------------------
    rx : ``In(1, init=1)``, tx : ``Out(1, init=1)``
        The serial lines, idle high.
    frames : ``Out(stream.Signature(CommandFrame))``
        One event per frame or cut-short frame, to be taken within a character time.
    replies : ``In(stream.Signature(32))``
        Words to send, most significant byte first.
    """

    rx: In(1, init=1)
    tx: Out(1, init=1)
    frames: Out(stream.Signature(CommandFrame))
    replies: In(stream.Signature(32))

    def __init__(self, *, divisor, gap_chars=3, reply_depth=REPLY_QUEUE_DEPTH):
        if not isinstance(gap_chars, int) or gap_chars < 2:
            raise ValueError(f"gap_chars must be an integer of at least 2, not {gap_chars!r}")
        if not isinstance(reply_depth, int) or reply_depth < 1:
            raise ValueError(f"reply_depth must be a positive integer, not {reply_depth!r}")
        self.divisor = divisor
        self.gap_chars = gap_chars
        self.reply_depth = reply_depth
        super().__init__()

    def elaborate(self, platform):
        m = Module()
        m.submodules.receiver = receiver = UARTReceiver(divisor=self.divisor)
        m.submodules.transmitter = transmitter = UARTTransmitter(divisor=self.divisor)
        m.d.comb += [receiver.rx.eq(self.rx), self.tx.eq(transmitter.tx)]

        # --- bytes → frames -----------------------------------------------------------------
        # `quiet` restarts when a byte is received, in the middle of its stop bit, and the next
        # byte is received a character time after its start bit: counting one character more
        # than the pause makes the idle line itself, not idle plus a character, what ends a frame.
        gap = (self.gap_chars + 1) * 10 * self.divisor
        count = Signal(range(4))        # bytes gathered
        word = Signal(FRAME_BITS)
        broken = Signal()               # a byte of this frame had a bad stop bit
        quiet = Signal(range(gap + 1))  # clocks since the last byte or line error

        m.d.comb += receiver.bytes.ready.eq(1)
        with m.If(self.frames.ready):
            m.d.sync += self.frames.valid.eq(0)

        # The frame handed on is the gathering register itself (no copy: 32 logic cells):
        # it holds until the next byte, a character time later, and the decoder takes a UART
        # frame within two clocks.
        m.d.comb += self.frames.payload.word.eq(word)

        def hand_on(bits):
            m.d.sync += [
                self.frames.payload.bits.eq(bits),
                self.frames.valid.eq(1),
                count.eq(0),
                broken.eq(0),
            ]

        with m.If(receiver.bytes.valid):
            m.d.sync += [word.eq(Cat(receiver.bytes.payload, word)), quiet.eq(0)]
            with m.If(count == 3):
                hand_on(Mux(broken, BROKEN, FRAME_BITS))
            with m.Else():
                m.d.sync += count.eq(count + 1)
        with m.Elif(receiver.framing_error):
            m.d.sync += [broken.eq(1), quiet.eq(0)]
        with m.Elif(quiet != gap):
            m.d.sync += quiet.eq(quiet + 1)
        with m.Elif((count != 0) | broken):
            hand_on(Mux(broken, BROKEN, count * 8))

        # --- replies → bytes ----------------------------------------------------------------
        m.submodules.queue = queue = SyncFIFOBuffered(width=32, depth=self.reply_depth)
        m.d.comb += [
            queue.w_data.eq(self.replies.payload),
            queue.w_en.eq(self.replies.valid),
            self.replies.ready.eq(queue.w_rdy),
        ]
        byte_index = Signal(range(4), init=3)     # most significant byte first
        m.d.comb += [
            transmitter.bytes.valid.eq(queue.r_rdy),
            transmitter.bytes.payload.eq(queue.r_data.word_select(byte_index, 8)),
        ]
        with m.If(transmitter.bytes.valid & transmitter.bytes.ready):
            m.d.sync += byte_index.eq(byte_index - 1)
            with m.If(byte_index == 0):
                m.d.comb += queue.r_en.eq(1)
        return m
