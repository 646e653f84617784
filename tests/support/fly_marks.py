"""Marking on the fly, read off a simulated board's records by the tests' own decoders: the
frames a laser pulse fell on (the XY2-100 wires), and the register writes the host sent on
its link (the bytes the board received, COBS-decoded by the tests' codec), so that a test can
say when the count was zeroed and move each mark back by the belt's travel since."""

from galvoscan.gateware.host.regmap import BY_NAME, READ_FLAG
from galvoscan.sim.xy2_receiver import frame_of_each_pulse

from link_codec import cobs_decode, crc16


__all__ = ["pulsed_frames", "host_frames", "writes"]


def pulsed_frames(board):
    """``(clock, x, y)`` of each XY2-100 frame a laser pulse fell on, in time order."""
    frames = board.frames
    placed = frame_of_each_pulse(board.sync_rises, board.pulses, len(frames))
    return sorted({k: frames[k] for k, _ in placed}.values())


def host_frames(bytes_in):
    """``(clock, address, data, read)`` of each command frame the board received whole (its
    CRC good), ``clock`` the one its closing zero byte's stop bit ended on."""
    found, packet = [], b""
    for cycle, byte in bytes_in:
        if byte:
            packet += bytes([byte])
            continue
        frame = cobs_decode(packet) if packet else None
        packet = b""
        if frame and len(frame) == 10 and crc16(frame) == 0:
            found.append((cycle, frame[1] & ~READ_FLAG & 0xFF, frame[2] << 8 | frame[3],
                          bool(frame[1] & READ_FLAG)))
    return found


def writes(bytes_in, name=None):
    """``(clock, value)`` of each write to register ``name`` (its 16 bits as sent), in order;
    ``name`` None: ``(clock, name)`` of every write."""
    names = {reg.address: reg.name for reg in BY_NAME.values()}
    every = [(cycle, address, data) for cycle, address, data, read in host_frames(bytes_in)
             if not read]
    if name is None:
        return [(cycle, names.get(address, hex(address))) for cycle, address, _ in every]
    address = BY_NAME[name].address
    return [(cycle, data) for cycle, found, data in every if found == address]
