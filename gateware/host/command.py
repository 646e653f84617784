"""Command decoder: checks each frame, turns it into a register write or read, and answers it."""

from amaranth.hdl import Const, Module, Mux, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out

from .frames import REFUSED, Answer, CommandFrame
from .registers import RegisterBus
from .regmap import BY_NAME


__all__ = ["CommandDecoder", "SEGMENT_ADDRESS", "FREE_ADDRESS"]


#: A write here queues a segment: the frame's data, x and y together.
SEGMENT_ADDRESS = BY_NAME["vec_op"].address
#: What the answer to a segment gives: the queue's free places after it.
FREE_ADDRESS = BY_NAME["fifo_free"].address


class CommandDecoder(wiring.Component):
    """Takes the frames of both links (:mod:`.frames`), one at a time, and answers every one.

    A frame is taken on one clock and copied; on the next it is decided, and on the one after
    the verdict is acted on:

    * not intact (cut short, run over, damaged: its CRC failed): refused, reason ``check``;
    * a read (address bit 7 set) of a register, with zero data: the register file reads it, and
      the answer gives the value;
    * a write whose ``seq`` is the one expected (:attr:`seq`): given to the register file,
      which takes it on the clock after or refuses it (reason ``register``). Taken, the next
      ``seq`` is expected, and the register is read back: the answer gives what it holds now
      (for ``vec_op``, the free places in the queue). A write of ``vec_op`` queues the
      frame's (data, x, y) together (:attr:`segment`, :attr:`segment_x`,
      :attr:`segment_y`);
    * a write with another ``seq``: refused, reason ``sequence``: a write lost on the line
      makes every later one refused, so none is ever taken out of order;
    * anything else: refused, reason ``register``.

    A refused frame changes nothing, adds one to :attr:`errors`, pulses :attr:`refused` (the
    system top latches a link fault on it while armed) and is answered with its reason and
    the ``seq`` expected. SPI goes first when both links' frames wait; the other waits (both
    transports hold a frame until it is taken). The next frame is taken on the clock after an
    answer is offered.

    Interface attributes
    --------------------
    spi_frames, uart_frames : ``In(stream.Signature(CommandFrame))``
    spi_replies, uart_replies : ``Out(stream.Signature(Answer))``
        Each frame's answer, offered for one clock to the link the frame came from, and held
        until the next frame is taken. The SPI target takes a copy for the host's next frame
        (one it cannot take then, a frame being already under way, is lost and counted in
        :attr:`errors`: a host that paces its frames as the client does never meets that).
        The UART port sends it from here: no frame is taken while ``uart_replies.ready`` is
        low (an answer going out), which is over long before a next frame can have come.
    bus : ``Out(RegisterBus())``
        To the register file.
    given : ``Out(1)``
        An access is given on :attr:`bus` this clock (the job player's writes wait).
    errors : ``Out(16)``
        Refused frames since reset; stops at 65535.
    refused : ``Out(1)``
        High for one clock for each refused frame.
    accepted : ``Out(1)``
        High for one clock for each frame taken (a read done, a write done).
    status_read : ``Out(1)``
        High for one clock when ``status`` is read (it clears the sticky flags): the clock the
        register file reads it, so the value read is the one before the clearing.
    seq : ``Out(8)``
        The ``seq`` the next write must carry (the ``link_seq`` register).
    segment : ``Out(1)``
        The write done this clock is the host's ``vec_op``: the queue takes
        (:attr:`segment_x`, :attr:`segment_y`) with it, not ``vec_x`` and ``vec_y``.
    segment_x, segment_y : ``Out(16)``
    """

    spi_frames: In(stream.Signature(CommandFrame))
    uart_frames: In(stream.Signature(CommandFrame))
    spi_replies: Out(stream.Signature(Answer))
    uart_replies: Out(stream.Signature(Answer))
    bus: Out(RegisterBus())
    given: Out(1)
    errors: Out(16)
    refused: Out(1)
    accepted: Out(1)
    status_read: Out(1)
    seq: Out(8)
    segment: Out(1)
    segment_x: Out(16)
    segment_y: Out(16)

    def elaborate(self, platform):
        m = Module()

        # --- take a frame -------------------------------------------------------------------
        frame = Signal(CommandFrame)
        from_spi = Signal()
        payload = frame.payload
        seq, address = payload[56:64], payload[48:56]
        data = payload[32:48]
        is_read = address[7]
        m.d.comb += [self.segment_x.eq(payload[16:32]), self.segment_y.eq(payload[0:16])]

        # --- answer -------------------------------------------------------------------------
        # The answer is the frame's own copy, its address and data replaced by the answer's
        # code and data once they are known (its tag is the frame's seq): offered for one
        # clock, from flip-flops, to the link the frame came from, and held until the next
        # frame is taken. The SPI target keeps a copy for the host's next frame; the UART port
        # sends it from here, so no frame is taken while it does (`uart_replies.ready` low),
        # which it has done long before the next frame can have come.
        answer = Signal(Answer)
        answer_valid = Signal()
        m.d.comb += answer.eq(payload[32:64])
        for link, spi in ((self.spi_replies, True), (self.uart_replies, False)):
            m.d.comb += [link.payload.eq(answer),
                         link.valid.eq(answer_valid & (from_spi if spi else ~from_spi))]
        lost = answer_valid & from_spi & ~self.spi_replies.ready

        verdict = Signal(2)         # why the frame taken is refused (REFUSED), or 0

        def offer(code, data):
            m.d.sync += [address.eq(code), payload[32:48].eq(data), answer_valid.eq(1)]
            m.next = "IDLE"

        def refuse(reason):
            m.d.comb += self.refused.eq(1)
            offer(0x80 | reason, self.seq)

        # The register file reads on the clock after an access is given and answers on the
        # next: an answer's data is on `read_data` two clocks after its read was given.
        with m.FSM():
            with m.State("IDLE"):
                m.d.sync += answer_valid.eq(0)
                # Not on the clock an answer is offered, nor while the UART port sends one.
                free = ~answer_valid & self.uart_replies.ready
                m.d.comb += [self.spi_frames.ready.eq(free),
                             self.uart_frames.ready.eq(free & ~self.spi_frames.valid)]
                with m.If(free & self.spi_frames.valid):
                    m.d.sync += [frame.eq(self.spi_frames.payload), from_spi.eq(1)]
                    m.next = "DECIDE"
                with m.Elif(free & self.uart_frames.valid):
                    m.d.sync += [frame.eq(self.uart_frames.payload), from_spi.eq(0)]
                    m.next = "DECIDE"
            with m.State("DECIDE"):
                # The access is given whatever is decided (a refused one is a read of no
                # consequence), and the verdict is kept for the next clock: neither the job
                # player's bus nor the answer then waits on the register file's address
                # decode (the longest path otherwise).
                m.d.comb += [self.bus.address.eq(address[:7]), self.bus.write_data.eq(data),
                             self.given.eq(1)]
                with m.If(~frame.intact):
                    m.d.sync += verdict.eq(REFUSED["check"])
                with m.Elif(is_read):
                    m.d.sync += verdict.eq(Mux(self.bus.read_ok & (data == 0), 0,
                                               REFUSED["register"]))
                with m.Else():
                    m.d.sync += verdict.eq(Mux(seq == self.seq, 0, REFUSED["sequence"]))
                m.next = "DECIDED"
            with m.State("DECIDED"):
                with m.If(verdict != 0):
                    refuse(verdict)
                with m.Elif(is_read):
                    # The register file reads now.
                    m.d.comb += self.status_read.eq(address[:7] == BY_NAME["status"].address)
                    m.next = "READ"
                with m.Else():
                    # The register file takes the write now, or refuses it; taken, the
                    # register is read back (a segment: the queue's free places).
                    is_segment = address[:7] == SEGMENT_ADDRESS
                    m.d.comb += [
                        self.bus.write_en.eq(1),
                        self.segment.eq(is_segment),
                        self.bus.address.eq(Mux(is_segment, FREE_ADDRESS, address[:7])),
                        self.given.eq(1),
                    ]
                    with m.If(self.bus.write_ok):
                        m.d.sync += self.seq.eq(self.seq + 1)
                        m.next = "FETCH"
                    with m.Else():
                        # Answered on the next clock: the answer then waits on no range check.
                        m.d.sync += verdict.eq(REFUSED["register"])
                        m.next = "REFUSE"
            with m.State("REFUSE"):
                refuse(verdict)
            with m.State("FETCH"):
                # The register file reads the write's register back now.
                m.next = "READ"
            with m.State("READ"):
                m.d.comb += self.accepted.eq(1)
                offer(address[:7], self.bus.read_data)

        with m.If((self.refused | lost) & (self.errors != 0xFFFF)):
            m.d.sync += self.errors.eq(self.errors + 1)
        return m
