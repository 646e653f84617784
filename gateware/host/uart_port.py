"""Command frames over a UART: COBS-framed bytes gathered into frames, answers sent back as
six bytes each."""

from amaranth.hdl import Array, Cat, Const, Module, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out

from .crc import SerialCRC16
from .frames import ANSWER_BYTES, COMMAND_BYTES, PAYLOAD_BITS, Answer, CommandFrame
from .uart import UARTReceiver, UARTTransmitter


__all__ = ["UARTCommandPort", "MAX_COBS_CODE"]


#: The largest COBS code byte a command frame has (ten bytes, none zero: code 11).
MAX_COBS_CODE = COMMAND_BYTES + 1



class UARTCommandPort(wiring.Component):
    """Command frames over 8N1 serial, each COBS-encoded and ended by a zero byte.

    Received bytes are COBS-decoded as they come: a code byte says how many bytes follow
    before the next zero of the frame. The decoded bytes' CRC is worked out a bit a clock
    (eight clocks a byte, well within a character time), and the first
    :data:`~.frames.PAYLOAD_BITS` bits are kept. A zero byte ends the frame: it is handed on,
    intact if it decoded to exactly :data:`~.frames.COMMAND_BYTES` bytes, no code byte
    promised more than came, no byte had a bad stop bit, and the CRC held. A zero byte with
    nothing before it (a host's flush) is no frame. After a lost or extra byte, the frame it
    fell in is refused and the next starts at the next zero byte: the link finds its step
    again by itself.

    Each answer (the decoder's, a CRC added a bit a clock) is sent as its six bytes, back to
    back: answers come only when asked for, so the host knows how many to read, and after a
    damaged one it waits for the line to go quiet and asks again (the CRC tells a misaligned
    answer from a good one). There is no queue: an answer takes six character times and the
    next frame at least twelve to arrive, so one answer is always out before the next is made
    (one that finds an answer still going out is refused, ``replies.ready`` low, and the
    decoder counts it).

    Parameters
    ----------
    divisor : int
        System clocks per bit.
    kept_bytes : int
        Bytes of a frame kept and handed on (8: all before the CRC; 4: ``seq``, address and
        data, for a build without vector mode, which never uses a segment's end point; the
        rest is handed on as zeros, and checked all the same).

    Interface attributes
    --------------------
    rx : ``In(1, init=1)``, tx : ``Out(1, init=1)``
        The serial lines, idle high.
    frames : ``Out(stream.Signature(CommandFrame))``
        One event per frame, held until taken (within a character time).
    replies : ``In(stream.Signature(Answer))``
        Answers to send: taken while none is going out (``ready``), and read from the
        payload, which its sender holds until ``ready`` is high again.
    """

    rx: In(1, init=1)
    tx: Out(1, init=1)
    frames: Out(stream.Signature(CommandFrame))
    replies: In(stream.Signature(Answer))

    def __init__(self, *, divisor, kept_bytes=PAYLOAD_BITS // 8):
        if kept_bytes not in (4, PAYLOAD_BITS // 8):
            raise ValueError(f"kept_bytes must be 4 or {PAYLOAD_BITS // 8}, not {kept_bytes!r}")
        self.divisor = divisor
        self.kept_bytes = kept_bytes
        super().__init__()

    def elaborate(self, platform):
        m = Module()
        m.submodules.receiver = receiver = UARTReceiver(divisor=self.divisor)
        m.submodules.transmitter = transmitter = UARTTransmitter(divisor=self.divisor)
        m.d.comb += [receiver.rx.eq(self.rx), self.tx.eq(transmitter.tx)]
        self._receive(m, receiver)
        self._send(m, transmitter)
        return m

    def _receive(self, m, receiver):
        """Bytes → COBS-decoded frames."""
        m.submodules.check = check = SerialCRC16()
        word = Signal(8 * self.kept_bytes)
        count = Signal(range(COMMAND_BYTES + 2))    # bytes decoded (saturates past a frame)
        remaining = Signal(range(MAX_COBS_CODE))    # bytes before the next code byte
        started = Signal()                          # a byte of this frame has come
        broken = Signal()                           # a bad stop bit or a code past a frame's
        # A decoded byte, fed to the CRC a bit a clock, top first: the receiver's byte (which
        # it holds until the next one is in, a character time away), or a zero.
        feeding = Signal(range(9))                  # its bits still to feed
        feed_zero = Signal()

        intact = Signal()                           # the frame handed on was whole
        m.d.comb += [
            receiver.bytes.ready.eq(1),
            self.frames.payload.payload.eq(word << (PAYLOAD_BITS - len(word))),
            self.frames.payload.intact.eq(intact),
        ]
        with m.If(self.frames.ready):
            m.d.sync += self.frames.valid.eq(0)

        with m.If(feeding != 0):
            index = (feeding - 1)[:3]
            m.d.comb += [check.enable.eq(1),
                         check.bit.eq(receiver.bytes.payload.bit_select(index, 1) & ~feed_zero)]
            m.d.sync += feeding.eq(feeding - 1)

        def decoded(byte, zero):
            with m.If(count < self.kept_bytes):
                m.d.sync += word.eq(Cat(byte, word[:-8]))
            with m.If(count != COMMAND_BYTES + 1):
                m.d.sync += count.eq(count + 1)
            m.d.sync += [feeding.eq(8), feed_zero.eq(zero)]

        byte = receiver.bytes.payload
        with m.If(receiver.bytes.valid):
            with m.If(byte == 0):
                # The frame's end: hand it on (the word holds until the next frame's first
                # byte, a character time away), and start the next.
                with m.If(started | broken):
                    m.d.sync += [self.frames.valid.eq(1), intact.eq(
                        (count == COMMAND_BYTES) & (remaining == 0) & ~broken &
                        (check.crc == 0))]
                m.d.sync += [started.eq(0), remaining.eq(0), broken.eq(0), count.eq(0)]
            with m.Elif(broken):
                pass                    # (the rest of a broken frame, to its zero byte)
            with m.Elif(remaining == 0):
                # A code byte: a zero of the frame before it (not before the first), then
                # code - 1 bytes.
                with m.If(~started):
                    m.d.comb += check.clear.eq(1)
                with m.Else():
                    decoded(Const(0, 8), 1)
                m.d.sync += started.eq(1)
                with m.If(byte > MAX_COBS_CODE):
                    m.d.sync += broken.eq(1)        # (more bytes than a frame has)
                with m.Else():
                    m.d.sync += remaining.eq(byte - 1)
            with m.Else():
                decoded(byte, 0)
                m.d.sync += remaining.eq(remaining - 1)
        with m.Elif(receiver.framing_error):
            m.d.sync += broken.eq(1)

    def _send(self, m, transmitter):
        """Answers → six bytes, back to back, the CRC worked out as the first four go."""
        m.submodules.answer_check = check = SerialCRC16()
        answer = self.replies.payload           # held by the decoder while it goes out
        position = Signal(range(ANSWER_BYTES))
        fed = Signal(range(9))                  # bits of this byte fed to the CRC
        # The bytes that go out: the answer's four, then the CRC's two (read from the CRC
        # register itself, which holds still while they go).
        out_bytes = Array([answer.as_value().word_select(Answer.size // 8 - 1 - i, 8)
                           for i in range(Answer.size // 8)] + [check.crc[8:], check.crc[:8]])
        byte = out_bytes[position]
        sent = transmitter.bytes.valid & transmitter.bytes.ready

        with m.FSM():
            with m.State("IDLE"):
                m.d.comb += self.replies.ready.eq(1)
                with m.If(self.replies.valid):
                    m.d.comb += check.clear.eq(1)
                    m.d.sync += [position.eq(0), fed.eq(0)]
                    m.next = "SEND"
            with m.State("SEND"):
                # An answer byte goes to the CRC, top bit first, then out; a CRC byte goes out.
                with m.If((position < Answer.size // 8) & (fed != 8)):
                    index = (7 - fed)[:3]
                    m.d.comb += [check.enable.eq(1), check.bit.eq(byte.bit_select(index, 1))]
                    m.d.sync += fed.eq(fed + 1)
                with m.Else():
                    m.d.comb += [transmitter.bytes.valid.eq(1),
                                 transmitter.bytes.payload.eq(byte)]
                    with m.If(sent):
                        m.d.sync += [position.eq(position + 1), fed.eq(0)]
                        with m.If(position == ANSWER_BYTES - 1):
                            m.next = "IDLE"
