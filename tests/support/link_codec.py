"""Test-side codec of the host link's frames, written from the frame format
(docs/reference/host-link.md) independently of the gateware and of the host client: its own
CRC-16/CCITT (a table, not the gateware's bit loop nor binascii's) and its own COBS."""

__all__ = ["crc16", "command", "answer", "parse_answer", "cobs_encode", "cobs_decode",
           "REASON"]


def _table():
    table = []
    for byte in range(256):
        crc = byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) if crc & 0x8000 else crc << 1
        table.append(crc & 0xFFFF)
    return table


_TABLE = _table()

#: The refusal reasons an answer's code carries (bit 7 set).
REASON = {"check": 1, "sequence": 2, "register": 3}

#: Bits a command frame takes on the serial line: ten bytes, COBS's code byte and the zero that
#: ends it, 10 bits each (8N1).
FRAME_LINE_BITS = (10 + 1 + 1) * 10


def crc16(data, crc=0xFFFF):
    for byte in data:
        crc = ((crc << 8) & 0xFFFF) ^ _TABLE[(crc >> 8) ^ byte]
    return crc


def command(seq, address, data=0, x=0, y=0, *, read=False):
    """A command frame's ten bytes."""
    body = bytes([seq, address | (0x80 if read else 0), data >> 8, data & 0xFF, x >> 8,
                  x & 0xFF, y >> 8, y & 0xFF])
    return body + crc16(body).to_bytes(2, "big")


def answer(tag, code, data):
    body = bytes([tag, code, data >> 8, data & 0xFF])
    return body + crc16(body).to_bytes(2, "big")


def parse_answer(packet):
    """``(tag, code, data)`` of an answer whose CRC holds, else None."""
    if len(packet) != 6 or crc16(packet) != 0:
        return None
    return packet[0], packet[1], (packet[2] << 8) | packet[3]


def cobs_encode(data):
    out, group = bytearray(), bytearray()
    for byte in data:
        if byte == 0:
            out += bytes([len(group) + 1]) + group
            group = bytearray()
        else:
            group.append(byte)
            if len(group) == 254:
                out += bytes([255]) + group
                group = bytearray()
    out += bytes([len(group) + 1]) + group
    return bytes(out)


def cobs_decode(data):
    """The bytes COBS-encoded in ``data`` (no zero byte in it), or None if it is no
    encoding."""
    out, i = bytearray(), 0
    while i < len(data):
        code = data[i]
        if code == 0 or i + code > len(data):
            return None
        out += data[i + 1:i + code]
        i += code
        if code < 255 and i < len(data):
            out.append(0)
    return bytes(out)
