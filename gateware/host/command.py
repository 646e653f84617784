"""Command decoder: checks each frame and turns it into a register write or a read reply."""

from amaranth.hdl import Cat, Const, Module, Mux, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out

from .frames import FRAME_BITS, CommandFrame
from .registers import RegisterBus
from .regmap import BY_NAME, CHECK_BYTE


__all__ = ["CommandDecoder"]


class CommandDecoder(wiring.Component):
    """The instruction decoder of Dai & Tang 2020, for two transports.

    A frame is ``address[31:24] data[23:8] check[7:0]``. It is accepted only if it is complete
    (32 bits), its check byte is 0x64, and then

    * for a write (address bit 7 clear): the register exists, is writable and the value is in
      its range; the register is written, on the clock after the frame is taken (the register
      file checks on one clock and writes on the next: see :class:`~.registers.RegisterBus`);
    * for a read (address bit 7 set): the register exists and the data field is zero; the
      answer ``address, value, 0x64`` is offered on the transport the request came from three
      clocks after the frame is taken (the register file reads on the clock after, and answers
      on the clock after that).

    Anything else changes nothing and adds one to :attr:`errors`, as does a read whose answer
    cannot be queued. One frame is taken per clock; SPI goes first when both arrive together.
    What a frame did (:attr:`accepted`, :attr:`write_refused`, the count in :attr:`errors`)
    is known on the clock after it is taken.

    Interface attributes
    --------------------
    spi_frames, uart_frames : ``In(stream.Signature(CommandFrame))``
    spi_replies : ``Out(stream.Signature(32))``
        Held until taken; a read over SPI is refused while one waits.
    uart_replies : ``Out(stream.Signature(32))``
        Offered for one clock, into the UART port's queue: a read over the UART is refused
        while the queue has no room (``ready`` low), so when its answer comes there is room.
    bus : ``Out(RegisterBus())``
        To the register file.
    errors : ``Out(16)``
        Rejected frames since reset; stops at 65535.
    accepted : ``Out(1)``
        High for one clock for each accepted frame, the clock after it is taken (the
        watchdog's sign of life).
    status_read : ``Out(1)``
        High for one clock when ``status`` is read (it clears the sticky flags): the clock the
        register file reads it, so the value read is the one before the clearing.
    write_refused : ``Out(1)``
        High for one clock when a well-formed write frame is refused by the register file,
        the clock after it is taken.
    """

    spi_frames: In(stream.Signature(CommandFrame))
    uart_frames: In(stream.Signature(CommandFrame))
    spi_replies: Out(stream.Signature(32))
    uart_replies: Out(stream.Signature(32))
    bus: Out(RegisterBus())
    errors: Out(16)
    accepted: Out(1)
    status_read: Out(1)
    write_refused: Out(1)

    def elaborate(self, platform):
        m = Module()

        from_spi = self.spi_frames.valid
        m.d.comb += [
            self.spi_frames.ready.eq(1),
            self.uart_frames.ready.eq(~from_spi),
        ]
        valid = self.spi_frames.valid | self.uart_frames.valid
        frame = CommandFrame(Mux(from_spi, self.spi_frames.payload, self.uart_frames.payload))

        address = frame.word[24:32]
        data = frame.word[8:24]
        complete = (frame.bits == FRAME_BITS) & (frame.word[0:8] == CHECK_BYTE)
        is_read = address[7]
        m.d.comb += [
            self.bus.address.eq(address[0:7]),
            self.bus.write_data.eq(data),
        ]

        with m.If(self.spi_replies.ready):
            m.d.sync += self.spi_replies.valid.eq(0)
        # A read in flight: the register file reads it on the clock after the frame (`fetch`)
        # and the value comes on the next (`answer`); its link's reply is not free until the
        # answer is sent.
        fetch, fetch_spi, fetch_address = Signal(), Signal(), Signal(7)
        answer, answer_spi, answer_address = Signal(), Signal(), Signal(7)
        in_flight_spi = (fetch & fetch_spi) | (answer & answer_spi)
        in_flight_uart = (fetch & ~fetch_spi) | (answer & ~answer_spi)
        # The SPI target takes its reply as the host's next frame starts: it waits here until
        # then. The UART port queues its replies: one with room when the read is taken still
        # has room when the answer comes (nothing else fills the queue), so the answer is
        # offered for that one clock only, straight from the register file.
        reply_free = Mux(from_spi,
                         (~self.spi_replies.valid | self.spi_replies.ready) & ~in_flight_spi,
                         self.uart_replies.ready & ~in_flight_uart)

        read_taken = valid & complete & is_read & self.bus.read_ok & (data == 0) & reply_free
        # A well-formed write, given to the register file now and done (or refused) on the
        # next clock; a frame neither that nor a read taken is rejected, counted on the next.
        write_given = Signal()
        rejected = Signal()
        m.d.sync += [
            write_given.eq(valid & complete & ~is_read),
            rejected.eq(valid & ~(complete & ~is_read) & ~read_taken),
            fetch.eq(read_taken),
            fetch_spi.eq(from_spi),
            fetch_address.eq(address[0:7]),
            answer.eq(fetch),
            answer_spi.eq(fetch_spi),
            answer_address.eq(fetch_address),
        ]
        write_done = write_given & self.bus.write_ok
        refused = write_given & ~self.bus.write_ok
        m.d.comb += [
            self.bus.write_en.eq(write_given),
            self.accepted.eq(write_done | fetch),
            self.write_refused.eq(refused),
            self.status_read.eq(fetch & (fetch_address == BY_NAME["status"].address)),
        ]

        reply_word = Cat(Const(CHECK_BYTE, 8), self.bus.read_data, answer_address, Const(0, 1))
        with m.If(answer & answer_spi):
            m.d.sync += [self.spi_replies.payload.eq(reply_word), self.spi_replies.valid.eq(1)]
        m.d.comb += [
            self.uart_replies.payload.eq(reply_word),
            self.uart_replies.valid.eq(answer & ~answer_spi),
        ]

        # `rejected` and `refused` are about the same frame: one count a clock at most.
        with m.If((rejected | refused) & (self.errors != 0xFFFF)):
            m.d.sync += self.errors.eq(self.errors + 1)
        return m
