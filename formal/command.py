"""The command path from the SPI pins to a register write, as properties (Dai & Tang 2020's
frame; galvoscan's bad-input rules, README "How it is checked")."""

from amaranth.asserts import AnySeq
from amaranth.hdl import Assert, Cat, ClockDomain, Cover, Elaboratable, Module, Signal
from amaranth.lib.wiring import connect

from ..gateware.host.command import CommandDecoder
from ..gateware.host.frames import FRAME_BITS
from ..gateware.host.registers import RegisterFile
from ..gateware.host.regmap import CHECK_BYTE
from ..gateware.host.spi_target import SPITarget


__all__ = ["CommandPathSpec"]


class CommandPathSpec(Elaboratable):
    """No register write without a complete 32-bit frame with check byte 0x64.

    The SPI pins are free on every clock (any SCK rate, glitches, ``cs_n`` released anywhere).
    The spec reads the pins as the design must: through two flip-flops. For every clock it
    proves that a register write happens only on the clock after ``cs_n`` rose at the end of a
    frame of exactly 32 SCK rising edges whose last byte is 0x64 and whose address bit 7 is clear,
    and that it writes that frame's address and data. A frame with more or fewer bits (``cs_n``
    released mid-frame) therefore never writes.

    A frame may last for ever, so k-induction alone cannot relate the spec's view of the frame
    to the SPI target's; helper invariants (also proved) say that the two agree.

    Parameters
    ----------
    make_spi, make_decoder : callables
        Build the SPI target and the decoder under proof (the tests pass broken ones).
    """

    def __init__(self, *, make_spi=SPITarget, make_decoder=CommandDecoder):
        self.make_spi = make_spi
        self.make_decoder = make_decoder

    def elaborate(self, platform):
        m = Module()
        m.domains.sync = ClockDomain(reset_less=True)
        m.submodules.spi = spi = self.make_spi()
        m.submodules.decoder = decoder = self.make_decoder()
        m.submodules.registers = registers = RegisterFile()
        connect(m, spi.frames, decoder.spi_frames)
        connect(m, decoder.spi_replies, spi.replies)
        connect(m, decoder.bus, registers.bus)
        m.d.comb += [
            decoder.uart_frames.valid.eq(0),
            decoder.uart_replies.ready.eq(1),
            spi.sck.eq(AnySeq(1)),
            spi.cs_n.eq(AnySeq(1)),
            spi.copi.eq(AnySeq(1)),
        ]

        # The pins two clocks ago, as the design sees them after its synchronisers.
        def delayed(pin, init):
            stages = [Signal(init=init, name=f"{pin.name}_d{i}") for i in (1, 2)]
            m.d.sync += [stages[0].eq(pin), stages[1].eq(stages[0])]
            return stages[1]
        sck, cs_n, copi = delayed(spi.sck, 0), delayed(spi.cs_n, 1), delayed(spi.copi, 0)
        sck_q = Signal()
        m.d.sync += sck_q.eq(sck)

        # The frame, from cs_n falling to cs_n rising.
        selected = Signal()
        bits = Signal(range(FRAME_BITS + 2))
        shift = Signal(FRAME_BITS)
        with m.If(~cs_n & ~selected):
            m.d.sync += [selected.eq(1), bits.eq(0), shift.eq(0)]
        with m.Elif(~cs_n & selected & sck & ~sck_q):
            m.d.sync += shift.eq(Cat(copi, shift))
            with m.If(bits != FRAME_BITS + 1):
                m.d.sync += bits.eq(bits + 1)
        with m.Elif(cs_n & selected):
            m.d.sync += selected.eq(0)

        # The frame that ended on the last clock.
        ended = Signal()
        word = Signal(FRAME_BITS)
        word_bits = Signal.like(bits)
        m.d.sync += ended.eq(cs_n & selected)
        with m.If(cs_n & selected):
            m.d.sync += [word.eq(shift), word_bits.eq(bits)]

        write = registers.bus.write_en & registers.bus.write_ok
        m.d.comb += Assert(~write | (ended & (word_bits == FRAME_BITS) &
                                     (word[0:8] == CHECK_BYTE) & ~word[31] &
                                     (registers.bus.address == word[24:31]) &
                                     (registers.bus.write_data == word[8:24])),
                           "a register is written only by a complete frame with check byte 0x64")

        # Helper invariants: the SPI target's frame is the spec's frame.
        m.d.comb += [
            Assert(spi._selected == selected, "helper: target selected"),
            Assert(spi._bits == bits, "helper: target bit count"),
            Assert(~selected | (spi._shift == shift), "helper: target bits"),
            Assert(spi.frames.valid == ended, "helper: one frame event per frame"),
            Assert(~ended | ((spi.frames.payload.word == word) &
                             (spi.frames.payload.bits == word_bits)),
                   "helper: frame event carries the frame"),
        ]

        m.d.comb += [
            Cover(write, "a register is written"),
            Cover(ended & (word_bits == FRAME_BITS - 1) & (word[0:8] == CHECK_BYTE),
                  "a frame with a good check byte cut short by cs_n"),
            Cover(decoder.spi_replies.valid, "a read is answered"),
        ]
        return m
