"""Deliberately broken command paths, to show that the command proofs catch each fault."""

from amaranth.hdl import Module, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from galvoscan.gateware.host.command import CommandDecoder
from galvoscan.gateware.host.frames import COMMAND_BITS
from galvoscan.gateware.host.progress import ProgressFeed
from galvoscan.gateware.host.spi_target import SPITarget


class TamperedDecoder(wiring.Component):
    """The real decoder with its frames tampered with on the way in (``_feed``) or its
    segment outputs on the way out (``_segment``); everything else passes through."""

    def __init__(self):
        self.inner = CommandDecoder()
        super().__init__(self.inner.signature)

    def elaborate(self, platform):
        m = Module()
        m.submodules.inner = inner = self.inner
        for name in ("spi_frames", "uart_frames"):
            outer, to = getattr(self, name), getattr(inner, name)
            m.d.comb += [to.valid.eq(outer.valid), outer.ready.eq(to.ready)]
            self._feed(m, outer.payload, to.payload)
        wiring.connect(m, inner.spi_replies, wiring.flipped(self.spi_replies))
        wiring.connect(m, inner.uart_replies, wiring.flipped(self.uart_replies))
        wiring.connect(m, inner.bus, wiring.flipped(self.bus))
        for name in ("given", "errors", "refused", "accepted", "status_read", "seq"):
            m.d.comb += getattr(self, name).eq(getattr(inner, name))
        self._segment(m)
        return m

    def _feed(self, m, outer, inner):
        m.d.comb += inner.eq(outer)

    def _segment(self, m):
        m.d.comb += [self.segment.eq(self.inner.segment),
                     self.segment_x.eq(self.inner.segment_x),
                     self.segment_y.eq(self.inner.segment_y)]


class DecoderIgnoringCheck(TamperedDecoder):
    """Every frame taken as intact: the CRC's verdict ignored."""

    def _feed(self, m, outer, inner):
        m.d.comb += [inner.payload.eq(outer.payload), inner.intact.eq(1)]


class DecoderIgnoringSequence(TamperedDecoder):
    """Every frame's seq taken as the one expected: a write after a lost one is done."""

    def _feed(self, m, outer, inner):
        m.d.comb += [inner.eq(outer), inner.payload[56:64].eq(self.inner.seq)]


class DecoderQueueingOldEndPoint(TamperedDecoder):
    """A segment's x and y from a register written by an earlier frame: the queue takes the
    operation with the old end point (as three register writes did)."""

    def _segment(self, m):
        old_x, old_y = Signal(16), Signal(16)
        with m.If(self.inner.segment):
            m.d.sync += [old_x.eq(self.inner.segment_x), old_y.eq(self.inner.segment_y)]
        m.d.comb += [self.segment.eq(self.inner.segment), self.segment_x.eq(old_x),
                     self.segment_y.eq(old_y)]


class FeedOnRefusedSegments(ProgressFeed):
    """The watchdog fed by a segment frame whether or not the queue took it."""

    def elaborate(self, platform):
        m = Module()
        m.d.sync += self.alive.eq(self.segment | self.keepalive | self.player)
        return m


class FeedOnEveryFrame(wiring.Component):
    """The watchdog fed by every frame the decoder takes, reads among them (the chatter that
    held an armed board while the host polled its status)."""

    segment: In(1)
    pushed: In(1)
    keepalive: In(1)
    player: In(1)
    accepted: In(1)
    alive: Out(1)

    def elaborate(self, platform):
        m = Module()
        m.d.sync += self.alive.eq((self.segment & self.pushed) | self.keepalive | self.player |
                                  self.accepted)
        return m


class TargetIgnoringLength(SPITarget):
    """The real SPI target, but any frame whose CRC holds is intact, whatever its length: a
    frame clocked on past its 80 bits with COPI low (a host that sends a longer transfer) keeps
    a CRC of zero, and the board would take it."""

    def elaborate(self, platform):
        m = super().elaborate(platform)
        m.d.comb += self.frames.payload.intact.eq(self._check.crc == 0)
        return m


class TargetIgnoringCRC(SPITarget):
    """The real SPI target, but any 80-bit frame is intact."""

    def elaborate(self, platform):
        m = super().elaborate(platform)
        m.d.comb += self.frames.payload.intact.eq(self._bits == COMMAND_BITS)
        return m


class TargetKeepingFramesThroughReset(SPITarget):
    """The real SPI target, but its frame state survives a reset: the bits after a reset
    mid-frame complete the bits before it."""

    def __init__(self):
        super().__init__()
        self._selected = Signal(reset_less=True)
        self._bits = Signal.like(self._bits, reset_less=True)
        self._shift = Signal.like(self._shift, reset_less=True)


#: Each fault of the decoder's side: the parts to swap into the command path's harness, and
#: the properties it must break (a bounded check a few clocks deep, without reset).
BROKEN_COMMAND_PATHS = {
    "decoder_ignores_check": (
        {"make_decoder": DecoderIgnoringCheck},
        ("a register is written only by an intact write frame with the expected seq",
         "a frame that is not intact is refused")),
    "decoder_ignores_sequence": (
        {"make_decoder": DecoderIgnoringSequence},
        "a register is written only by an intact write frame with the expected seq"),
    "queue_takes_old_end_point": (
        {"make_decoder": DecoderQueueingOldEndPoint},
        "a segment is queued with its frame's end point"),
    "feed_on_refused_segments": (
        {"make_feed": FeedOnRefusedSegments},
        "the watchdog is fed only by a segment queued or a keepalive"),
    "feed_on_every_frame": (
        {"make_feed": FeedOnEveryFrame},
        "the watchdog is fed only by a segment queued or a keepalive"),
}

#: Each fault of the SPI target: the target to swap in and the properties it must break
#: (a bounded check of one paced frame, any one bit flipped).
BROKEN_SPI_TARGETS = {
    "target_ignores_length": (
        TargetIgnoringLength,
        "an SPI frame is intact only with 80 bits and a CRC that holds"),
    "target_ignores_crc": (
        TargetIgnoringCRC,
        "an SPI frame is intact only with 80 bits and a CRC that holds"),
    "target_keeps_frames_through_reset": (
        TargetKeepingFramesThroughReset,
        ("an SPI frame is intact only with 80 bits and a CRC that holds",
         "an SPI frame event carries the frame's first 64 bits",
         "an SPI frame with 80 bits and a CRC that holds is intact")),
}

#: The solver each SPI target's bounded check is searched with, where it is not the proofs'
#: own: the frame whose CRC does not hold takes Yices 164 s to find and z3 18 s.
SPI_TARGET_SOLVERS = {"target_ignores_crc": "z3"}
