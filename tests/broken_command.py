"""Deliberately broken command paths, to show that the command proof catches each fault."""

from amaranth.hdl import Cat, Const, Module, Mux, Signal
from amaranth.lib import wiring

from galvoscan.gateware.host.command import CommandDecoder
from galvoscan.gateware.host.regmap import CHECK_BYTE
from galvoscan.gateware.host.spi_target import SPITarget


class TamperedDecoder(wiring.Component):
    """The real decoder with one link's frame stream tampered with (``_feed``); everything
    else passes through unchanged."""

    #: The stream ``_feed`` connects: ``"spi_frames"`` or ``"uart_frames"``.
    tampered = None

    def __init__(self):
        self.inner = CommandDecoder()
        super().__init__(self.inner.signature)

    def elaborate(self, platform):
        m = Module()
        m.submodules.inner = inner = self.inner
        for name in ("spi_frames", "uart_frames"):
            if name != self.tampered:
                wiring.connect(m, wiring.flipped(getattr(self, name)), getattr(inner, name))
        wiring.connect(m, inner.spi_replies, wiring.flipped(self.spi_replies))
        wiring.connect(m, inner.uart_replies, wiring.flipped(self.uart_replies))
        wiring.connect(m, inner.bus, wiring.flipped(self.bus))
        for name in ("errors", "accepted", "status_read", "write_refused"):
            m.d.comb += getattr(self, name).eq(getattr(inner, name))
        self._feed(m, getattr(self, self.tampered), getattr(inner, self.tampered))
        return m


class DecoderIgnoringCheckByte(TamperedDecoder):
    """The real decoder, fed SPI frames whose check byte has been replaced by 0x64."""

    tampered = "spi_frames"

    def _feed(self, m, outer, inner):
        m.d.comb += [
            inner.valid.eq(outer.valid),
            outer.ready.eq(inner.ready),
            inner.payload.bits.eq(outer.payload.bits),
            inner.payload.word.eq(Cat(Const(CHECK_BYTE, 8), outer.payload.word[8:])),
        ]


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


class DecoderDroppingUARTErrors(TamperedDecoder):
    """The real decoder, but a UART frame that is not 32 bits long is taken and dropped
    without being counted."""

    tampered = "uart_frames"

    def _feed(self, m, outer, inner):
        whole = outer.payload.bits == 32
        m.d.comb += [
            inner.valid.eq(outer.valid & whole),
            inner.payload.eq(outer.payload),
            outer.ready.eq(inner.ready | ~whole),
        ]


class DecoderAcceptingLongUARTFrames(TamperedDecoder):
    """The real decoder, but a UART frame that ran over (33 bits) is decoded as complete."""

    tampered = "uart_frames"

    def _feed(self, m, outer, inner):
        bits = outer.payload.bits
        m.d.comb += [
            inner.valid.eq(outer.valid),
            outer.ready.eq(inner.ready),
            inner.payload.word.eq(outer.payload.word),
            inner.payload.bits.eq(Mux(bits == 33, 32, bits)),
        ]


#: Each fault: the parts to swap in (and which of the links and reset the check needs), and
#: the property it must break. The broken designs are checked without the helper invariants
#: (a bounded check; over SPI one paced frame, from clock 64 on), so that the counterexample
#: is the bad write or the lost count itself.
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
