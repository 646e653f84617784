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
      its range; the register is written;
    * for a read (address bit 7 set): the register exists and the data field is zero; the
      answer ``address, value, 0x64`` is sent back on the transport the request came from
      (two clocks after the frame: the register file answers a clock after the address).

    Anything else changes nothing and adds one to :attr:`errors`, as does a read whose answer
    cannot be queued. One frame is decoded per clock; SPI goes first when both arrive together.

    Interface attributes
    --------------------
    spi_frames, uart_frames : ``In(stream.Signature(CommandFrame))``
    spi_replies, uart_replies : ``Out(stream.Signature(32))``
    bus : ``Out(RegisterBus())``
        To the register file.
    errors : ``Out(16)``
        Rejected frames since reset; stops at 65535.
    accepted : ``Out(1)``
        High for one clock for each accepted frame (the watchdog's sign of life).
    status_read : ``Out(1)``
        High for one clock when ``status`` is read (it clears the sticky flags).
    write_refused : ``Out(1)``
        High for one clock when a well-formed write frame is refused by the register file
        (``bus.address`` tells which register).
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

        replies = (self.spi_replies, self.uart_replies)
        for reply in replies:
            with m.If(reply.ready):
                m.d.sync += reply.valid.eq(0)
        # A read's answer comes off the register bus a clock after its address: the read is
        # fetching (`fetch`) on that clock, and its link's reply is not free until it is sent.
        fetch = Signal()
        fetch_spi = Signal()
        fetch_address = Signal(7)
        reply_free = Mux(from_spi,
                         (~self.spi_replies.valid | self.spi_replies.ready) & ~(fetch & fetch_spi),
                         (~self.uart_replies.valid | self.uart_replies.ready) &
                         ~(fetch & ~fetch_spi))

        write_ok = complete & ~is_read & self.bus.write_ok
        read_ok = complete & is_read & self.bus.read_ok & (data == 0) & reply_free
        m.d.comb += [
            self.bus.write_en.eq(valid & write_ok),
            self.accepted.eq(valid & (write_ok | read_ok)),
            self.write_refused.eq(valid & complete & ~is_read & ~self.bus.write_ok),
            self.status_read.eq(valid & read_ok &
                                (address[0:7] == BY_NAME["status"].address)),
        ]

        m.d.sync += [
            fetch.eq(valid & read_ok),
            fetch_spi.eq(from_spi),
            fetch_address.eq(address[0:7]),
        ]
        with m.If(fetch):
            answer = Cat(Const(CHECK_BYTE, 8), self.bus.read_data, fetch_address, Const(0, 1))
            for index, reply in enumerate(replies):
                with m.If(fetch_spi if index == 0 else ~fetch_spi):
                    m.d.sync += [reply.payload.eq(answer), reply.valid.eq(1)]

        with m.If(valid & ~(write_ok | read_ok) & (self.errors != 0xFFFF)):
            m.d.sync += self.errors.eq(self.errors + 1)
        return m
