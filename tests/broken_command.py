"""Deliberately broken command paths, to show that the command proof catches each fault."""

from amaranth.hdl import Cat, Const, Module, Mux, Signal
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


class TargetKeepingFramesThroughReset(SPITarget):
    """The real SPI target, but its frame state survives a reset: the bits after a reset
    mid-frame complete the bits before it."""

    def __init__(self):
        super().__init__()
        self._selected = Signal(reset_less=True)
        self._bits = Signal.like(self._bits, reset_less=True)
        self._shift = Signal.like(self._shift, reset_less=True)


class DecoderDroppingUARTErrors(wiring.Component):
    """The real decoder, but a UART frame that is not 32 bits long is taken and dropped
    without being counted."""

    def __init__(self):
        self.inner = CommandDecoder()
        super().__init__(self.inner.signature)

    def elaborate(self, platform):
        m = Module()
        m.submodules.inner = inner = self.inner
        wiring.connect(m, wiring.flipped(self.spi_frames), inner.spi_frames)
        wiring.connect(m, inner.spi_replies, wiring.flipped(self.spi_replies))
        wiring.connect(m, inner.uart_replies, wiring.flipped(self.uart_replies))
        wiring.connect(m, inner.bus, wiring.flipped(self.bus))
        whole = self.uart_frames.payload.bits == 32
        m.d.comb += [
            inner.uart_frames.valid.eq(self.uart_frames.valid & whole),
            inner.uart_frames.payload.eq(self.uart_frames.payload),
            self.uart_frames.ready.eq(inner.uart_frames.ready | ~whole),
            self.errors.eq(inner.errors),
            self.accepted.eq(inner.accepted),
            self.status_read.eq(inner.status_read),
            self.write_refused.eq(inner.write_refused),
        ]
        return m


class DecoderAcceptingLongUARTFrames(wiring.Component):
    """The real decoder, but a UART frame that ran over (33 bits) is decoded as complete."""

    def __init__(self):
        self.inner = CommandDecoder()
        super().__init__(self.inner.signature)

    def elaborate(self, platform):
        m = Module()
        m.submodules.inner = inner = self.inner
        wiring.connect(m, wiring.flipped(self.spi_frames), inner.spi_frames)
        wiring.connect(m, inner.spi_replies, wiring.flipped(self.spi_replies))
        wiring.connect(m, inner.uart_replies, wiring.flipped(self.uart_replies))
        wiring.connect(m, inner.bus, wiring.flipped(self.bus))
        bits = self.uart_frames.payload.bits
        m.d.comb += [
            inner.uart_frames.valid.eq(self.uart_frames.valid),
            self.uart_frames.ready.eq(inner.uart_frames.ready),
            inner.uart_frames.payload.word.eq(self.uart_frames.payload.word),
            inner.uart_frames.payload.bits.eq(Mux(bits == 33, 32, bits)),
            self.errors.eq(inner.errors),
            self.accepted.eq(inner.accepted),
            self.status_read.eq(inner.status_read),
            self.write_refused.eq(inner.write_refused),
        ]
        return m


#: Each fault: the parts to swap in (and which of the links and reset the check needs), and
#: the property it must break. The broken designs are checked without the helper invariants
#: (a bounded check, from clock 66 on), so that the counterexample is the bad write or the
#: lost count itself.
BROKEN_COMMAND_PATHS = {
    "decoder_ignores_check_byte": (
        {"make_decoder": DecoderIgnoringCheckByte, "uart_live": False, "reset_free": False},
        ("a register is written only by a complete frame with check byte 0x64",
         "only a complete frame with check byte 0x64 is accepted")),
    "target_passes_short_frames": (
        {"make_spi": TargetPassingShortFrames, "uart_live": False, "reset_free": False},
        "a register is written only by a complete frame with check byte 0x64"),
    "target_keeps_frames_through_reset": (
        {"make_spi": TargetKeepingFramesThroughReset, "uart_live": False},
        # The frame that straddles the reset: written, or taken as a frame the spec never saw.
        ("a register is written only by a complete frame with check byte 0x64",
         "only a complete frame with check byte 0x64 is accepted",
         "every rejected frame is counted, and nothing else")),
    "decoder_drops_uart_errors": (
        {"make_decoder": DecoderDroppingUARTErrors},
        "every rejected frame is counted, and nothing else"),
    "decoder_accepts_long_uart_frames": (
        {"make_decoder": DecoderAcceptingLongUARTFrames},
        ("a register is written only by a complete frame with check byte 0x64",
         "only a complete frame with check byte 0x64 is accepted")),
}
