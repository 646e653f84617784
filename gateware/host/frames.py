"""The host link's frames, as both transports (SPI, UART) carry them.

A **command frame** is ten bytes, most significant first::

    seq | address | data[15:8] | data[7:0] | x[15:8] | x[7:0] | y[15:8] | y[7:0] | crc[15:8] | crc[7:0]

* ``seq``: a write's sequence number. The board takes a write only if it carries the number
  it expects (``link_seq``), and then expects the next (modulo 256): a write lost on the line
  makes every later one refused, never taken out of order. A read may carry any number; its
  answer gives it back (a tag, for the host to match answers to requests).
* ``address``: bit 7 set asks for a read.
* ``data``: the value to write (zero in a read).
* ``x``, ``y``: a segment's end point, in a write of ``vec_op`` (which queues the segment
  ``data`` says at (x, y): the three are taken together from one checked frame, never one
  without the others). Zero in every other frame.
* ``crc``: CRC-16/CCITT (polynomial 0x1021, initial value 0xFFFF, no reflection, no final
  XOR; Python's :func:`binascii.crc_hqx` with 0xFFFF) over the eight bytes before it.

An **answer** is six bytes, one for every frame the board receives::

    tag | code | data[15:8] | data[7:0] | crc[15:8] | crc[7:0]

* a frame taken: ``tag`` is its ``seq``, ``code`` its address (bit 7 clear), ``data`` for a
  read the register's value, for a write what the register holds after it (for ``vec_op``,
  the free places left in the vector queue);
* a frame refused: ``code`` is ``0x80 | reason`` (:data:`REFUSED`), ``tag`` the frame's first
  byte as received, ``data`` the sequence number the board expects next.

Over SPI a frame is what is clocked between ``cs_n`` falling and rising; its answer comes out
on CIPO during the next frame. Over the UART each frame is COBS-encoded (Cheshire & Baker's
Consistent Overhead Byte Stuffing) and ends with a zero byte, which no encoded byte is: after a
lost or extra byte the receiver finds the next frame at the next zero, and only the frame the
fault fell in is lost (and answered as refused). Answers go back as their six bytes: the host
asked for each, so it knows how many to read; after one that fails its CRC it waits for the
line to go quiet, drops what came, and asks again.
"""

from amaranth.lib import data


__all__ = ["CommandFrame", "Answer", "COMMAND_BYTES", "PAYLOAD_BITS", "ANSWER_BYTES",
           "COMMAND_BITS", "CRC_POLY", "CRC_INIT", "REFUSED", "crc16"]


#: Bytes in a command frame, with its CRC.
COMMAND_BYTES = 10
#: Bits in a command frame.
COMMAND_BITS = COMMAND_BYTES * 8
#: Bits of a command frame before its CRC (what a transport hands the decoder).
PAYLOAD_BITS = COMMAND_BITS - 16
#: Bytes in an answer, with its CRC.
ANSWER_BYTES = 6

#: CRC-16/CCITT: the polynomial (x^16 + x^12 + x^5 + 1) and the initial value.
CRC_POLY = 0x1021
CRC_INIT = 0xFFFF

#: Why a frame was refused, in an answer's ``code`` (with bit 7 set).
REFUSED = {
    "check": 1,         # not a whole frame, or its CRC fails (cut short, run over, damaged)
    "sequence": 2,      # a write whose seq is not the one expected
    "register": 3,      # the register file refused it (unknown address, read-only, out of range,
                        # the queue full) or a read's data was not zero
}

#: What a transport hands the decoder for each frame it received: the eight bytes before
#: the CRC (``seq`` in the top byte), and whether the frame was whole and its CRC held.
CommandFrame = data.StructLayout({"payload": PAYLOAD_BITS, "intact": 1})

#: An answer before its CRC, as the decoder gives it to the transport (``tag`` in the top
#: byte); the transport adds the CRC.
Answer = data.StructLayout({"data": 16, "code": 8, "tag": 8})


def crc16(data, crc=CRC_INIT):
    """CRC-16/CCITT of ``data`` (bytes), bit by bit as the gateware computes it: the
    elaboration-time reference for tables and tests of the gateware (the host uses
    :func:`binascii.crc_hqx`, a separate implementation)."""
    for byte in data:
        for i in range(7, -1, -1):
            feedback = ((crc >> 15) ^ (byte >> i)) & 1
            crc = ((crc << 1) & 0xFFFF) ^ (CRC_POLY if feedback else 0)
    return crc
