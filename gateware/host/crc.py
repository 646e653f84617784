"""CRC-16/CCITT, one bit a clock: the host link's frame check (:mod:`.frames`)."""

from amaranth.hdl import Cat, Const, Module, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .frames import CRC_INIT, CRC_POLY


__all__ = ["SerialCRC16"]


class SerialCRC16(wiring.Component):
    """A CRC-16/CCITT register (polynomial 0x1021, initial value 0xFFFF), most significant
    bit first.

    Fed a frame's bits and then its CRC's, it holds zero exactly when the CRC held: what a
    receiver checks. Fed a message's bits, it holds the CRC to send after them (shifted out
    most significant bit first with ``shift``).

    Interface attributes
    --------------------
    clear : ``In(1)``
        Start again at the initial value (on the next clock; over ``enable``).
    enable : ``In(1)``
        Take ``bit`` this clock.
    bit : ``In(1)``
    shift : ``In(1)``
        Shift the register left by one, zero in (to send the CRC, top bit first).
    crc : ``Out(16)``
        The register.
    """

    clear: In(1)
    enable: In(1)
    bit: In(1)
    shift: In(1)
    crc: Out(16, init=CRC_INIT)

    def elaborate(self, platform):
        m = Module()
        feedback = self.crc[15] ^ self.bit
        poly = Const(CRC_POLY, 16)
        with m.If(self.clear):
            m.d.sync += self.crc.eq(CRC_INIT)
        with m.Elif(self.enable):
            m.d.sync += self.crc.eq(Cat(Const(0, 1), self.crc[:15]) ^
                                    (poly & feedback.replicate(16)))
        with m.Elif(self.shift):
            m.d.sync += self.crc.eq(Cat(Const(0, 1), self.crc[:15]))
        return m
