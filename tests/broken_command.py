"""Deliberately broken command paths, to show that the command proof catches each fault."""

from amaranth.hdl import Cat, Const, Module, Mux
from amaranth.lib import wiring

from galvoscan.gateware.host.command import CommandDecoder
from galvoscan.gateware.host.regmap import CHECK_BYTE
from galvoscan.gateware.host.spi_target import SPITarget


class DecoderIgnoringCheckByte(wiring.Component):
    """The real decoder, fed SPI frames whose check byte has been replaced by 0x64."""

    def __init__(self):
        self.inner = CommandDecoder()
        super().__init__(self.inner.signature)

    def elaborate(self, platform):
        m = Module()
        m.submodules.inner = inner = self.inner
        wiring.connect(m, wiring.flipped(self.uart_frames), inner.uart_frames)
        wiring.connect(m, inner.spi_replies, wiring.flipped(self.spi_replies))
        wiring.connect(m, inner.uart_replies, wiring.flipped(self.uart_replies))
        wiring.connect(m, inner.bus, wiring.flipped(self.bus))
        m.d.comb += [
            inner.spi_frames.valid.eq(self.spi_frames.valid),
            self.spi_frames.ready.eq(inner.spi_frames.ready),
            inner.spi_frames.payload.bits.eq(self.spi_frames.payload.bits),
            inner.spi_frames.payload.word.eq(
                Cat(Const(CHECK_BYTE, 8), self.spi_frames.payload.word[8:])),
            self.errors.eq(inner.errors),
            self.accepted.eq(inner.accepted),
            self.status_read.eq(inner.status_read),
        ]
        return m


class TargetPassingShortFrames(wiring.Component):
    """The real SPI target, but a frame cut short after 31 bits is reported as complete."""

    def __init__(self):
        self.inner = SPITarget()
        super().__init__(self.inner.signature)
        # The proof's helper invariants look at the frame state of the target.
        self._selected, self._bits, self._shift = \
            self.inner._selected, self.inner._bits, self.inner._shift

    def elaborate(self, platform):
        m = Module()
        m.submodules.inner = inner = self.inner
        wiring.connect(m, wiring.flipped(self.replies), inner.replies)
        bits = inner.frames.payload.bits
        m.d.comb += [
            inner.sck.eq(self.sck), inner.cs_n.eq(self.cs_n), inner.copi.eq(self.copi),
            self.cipo.eq(inner.cipo),
            self.frames.valid.eq(inner.frames.valid),
            inner.frames.ready.eq(self.frames.ready),
            self.frames.payload.word.eq(inner.frames.payload.word),
            self.frames.payload.bits.eq(Mux(bits == 31, 32, bits)),
        ]
        return m


#: Each fault: the parts to swap in, and the property it must break.
BROKEN_COMMAND_PATHS = {
    "decoder_ignores_check_byte": (
        {"make_decoder": DecoderIgnoringCheckByte},
        "a register is written only by a complete frame with check byte 0x64"),
    # The target misreports what was clocked in: the proof's statement of exactly that fails.
    "target_passes_short_frames": (
        {"make_spi": TargetPassingShortFrames},
        "helper: frame event carries the frame"),
}
