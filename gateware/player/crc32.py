"""CRC-32 (IEEE 802.3, zlib's) of a byte stream, a few bits per clock."""

from amaranth.hdl import Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out


__all__ = ["CRC32"]


#: The reflected polynomial: bits shift out LSB first.
POLYNOMIAL = 0xEDB88320


class CRC32(wiring.Component):
    """Zlib's CRC-32 of the bytes given since :attr:`clear`.

    A byte takes ``8 / bits_per_clock`` clocks, LSB first: one bit a clock is some 40 cells,
    and the flash reader gives a byte at most every sixteen clocks.

    Parameters
    ----------
    bits_per_clock : int
        1, 2, 4 or 8 (a byte a clock: about twice the logic; the player's proof takes it,
        so that its covers are short).

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

    def __init__(self, *, bits_per_clock=1):
        if bits_per_clock not in (1, 2, 4, 8):
            raise ValueError(f"bits_per_clock must be 1, 2, 4 or 8, not {bits_per_clock!r}")
        self.bits_per_clock = bits_per_clock
        super().__init__()
        #: The shift register (the CRC's complement), for the player's proof.
        self._state = Signal(32, init=0xFFFFFFFF, name="crc_state")

    def elaborate(self, platform):
        m = Module()
        state = self._state
        n = self.bits_per_clock
        byte = Signal(8)
        steps = Signal(range(8 // n + 1))
        m.d.comb += [self.crc.eq(~state), self.busy.eq(steps != 0)]

        def advance(value, bits):
            for k in range(n):
                value = (value >> 1) ^ Mux(value[0] ^ bits[k], POLYNOMIAL, 0)
            return value

        with m.If(steps != 0):
            m.d.sync += [state.eq(advance(state, byte)), byte.eq(byte >> n),
                         steps.eq(steps - 1)]
        with m.Elif(self.strobe):
            m.d.sync += [byte.eq(self.data), steps.eq(8 // n)]
        with m.If(self.clear):
            m.d.sync += [state.eq(0xFFFFFFFF), steps.eq(0)]
        return m
