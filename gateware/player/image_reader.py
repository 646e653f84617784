"""The job player's image reader: the flash's bytes into the image's 16-bit words, and into the
CRC-32 the player's check compares with the image's own."""

from amaranth.hdl import Module, Mux, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out

from .crc32 import CRC32


__all__ = ["ImageReader"]


class ImageReader(wiring.Component):
    """Words, low byte first, from the bytes of the flash reader; every byte also into a CRC-32.

    A byte is taken while :attr:`enable` is high and no word waits (the next word's bytes
    come once the last one is taken), and, while :attr:`wait_crc` is high, once the CRC has
    taken the last one.

    Parameters
    ----------
    crc_bits_per_clock : int
        The CRC core's (:class:`~.crc32.CRC32`): 1 on the board; the proof's 8 make its
        covers short.

    Interface attributes
    --------------------
    data : ``In(stream.Signature(8))``
        The flash reader's bytes.
    enable : ``In(1)``
        The player takes bytes now.
    wait_crc : ``In(1)``
        A byte waits for the CRC (the check; the playing does not read the CRC).
    zero_byte : ``In(1)``
        The CRC reads the byte being taken as zero (the image's CRC field).
    clear : ``In(1)``
        Start a read afresh: no byte of a word held, no word waiting.
    crc_clear : ``In(1)``
        Start the CRC afresh (a read from the image's start).
    words : ``Out(stream.Signature(16))``
        The image's words, each valid until taken.
    crc : ``Out(32)``; crc_busy : ``Out(1)``
        The CRC of the bytes taken since :attr:`crc_clear`, once ``crc_busy`` is low.

    Attributes
    ----------
    byte_high : Signal
        The next byte is a word's high byte (the player's proof names it).
    crc_core : :class:`~.crc32.CRC32`
    """

    def __init__(self, *, crc_bits_per_clock=1):
        self.crc_core = CRC32(bits_per_clock=crc_bits_per_clock)
        self.byte_high = Signal(name="byte_high")
        super().__init__({
            "data": In(stream.Signature(8)),
            "enable": In(1), "wait_crc": In(1), "zero_byte": In(1),
            "clear": In(1), "crc_clear": In(1),
            "words": Out(stream.Signature(16)),
            "crc": Out(32), "crc_busy": Out(1),
        })

    def elaborate(self, platform):
        m = Module()
        m.submodules.crc = crc = self.crc_core
        word, word_valid, byte_high = self.words.payload, self.words.valid, self.byte_high
        take_byte = Signal()
        m.d.comb += [
            take_byte.eq(self.enable & ~word_valid & ~(crc.busy & self.wait_crc)),
            self.data.ready.eq(take_byte),
            crc.data.eq(Mux(self.zero_byte, 0, self.data.payload)),
            crc.strobe.eq(self.data.valid & take_byte),
            crc.clear.eq(self.crc_clear),
            self.crc.eq(crc.crc),
            self.crc_busy.eq(crc.busy),
        ]
        with m.If(self.data.valid & take_byte):
            m.d.sync += byte_high.eq(~byte_high)
            with m.If(byte_high):
                m.d.sync += [word[8:].eq(self.data.payload), word_valid.eq(1)]
            with m.Else():
                m.d.sync += word[:8].eq(self.data.payload)
        # (After the above: a word taken, or a read started afresh, wins.)
        with m.If(self.words.valid & self.words.ready):
            m.d.sync += word_valid.eq(0)
        with m.If(self.clear):
            m.d.sync += [byte_high.eq(0), word_valid.eq(0)]
        return m
