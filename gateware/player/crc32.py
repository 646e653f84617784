"""CRC-32 (IEEE 802.3, zlib's) of a byte stream, one bit per clock."""

from amaranth.hdl import Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out


__all__ = ["CRC32"]


#: The reflected polynomial: bits shift out LSB first.
POLYNOMIAL = 0xEDB88320


class CRC32(wiring.Component):
    """Zlib's CRC-32 of the bytes given since :attr:`clear`.

    A byte takes eight clocks, LSB first (some 40 cells, where a byte a clock would take
    about twice that); the flash reader gives one at most every sixteen.

    Interface attributes
    --------------------
    clear : ``In(1)``
        Start again (the CRC of no bytes: 0).
    data : ``In(8)``; strobe : ``In(1)``
        A byte, taken when ``strobe`` is high and :attr:`busy` is low.
    busy : ``Out(1)``
        A byte is being taken in.
    crc : ``Out(32)``
        The CRC of the bytes taken so far, once :attr:`busy` is low.
    """

    clear: In(1)
    data: In(8)
    strobe: In(1)
    busy: Out(1)
    crc: Out(32)

    def elaborate(self, platform):
        m = Module()
        state = Signal(32, init=0xFFFFFFFF)
        byte = Signal(8)
        bits = Signal(range(9))
        m.d.comb += [self.crc.eq(~state), self.busy.eq(bits != 0)]
        with m.If(bits != 0):
            feedback = state[0] ^ byte[0]
            m.d.sync += [
                state.eq((state >> 1) ^ Mux(feedback, POLYNOMIAL, 0)),
                byte.eq(byte >> 1),
                bits.eq(bits - 1),
            ]
        with m.Elif(self.strobe):
            m.d.sync += [byte.eq(self.data), bits.eq(8)]
        with m.If(self.clear):
            m.d.sync += [state.eq(0xFFFFFFFF), bits.eq(0)]
        return m
