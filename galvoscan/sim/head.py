"""The scan head's answer on its STATUS line, as the simulated board's head sends it: a frame
of XY2-100's own format in step with the controller's (three control bits ``001``, the 16
bits of its status word, even parity), changed with each rising CLOCK edge, the first bit
with the edge on which SYNC is first seen high; the word is the one the head holds as the frame
begins. Written from the protocol, not from the
gateware's receiver, which the tests check against it."""

from ..gateware.phy.xy2_100 import FRAME_BITS


__all__ = ["HEALTHY_HEAD", "status_frame_bits"]


#: A head with nothing to report: bit 0 set, PosAck X and Y, Temp OK, Power OK (RTC5/RTC6's
#: get_head_status bits 0, 3, 4, 6, 7).
HEALTHY_HEAD = 0b1101_1001


def status_frame_bits(word, *, code=0b001):
    """The ``FRAME_BITS`` levels a head sends for status ``word``, first bit first."""
    if not 0 <= word <= 0xFFFF:
        raise ValueError(f"a head's status word is 16 bits, not {word!r}")
    bits = [int(c) for c in f"{code:03b}{word:016b}"]
    bits.append(sum(bits) % 2)
    assert len(bits) == FRAME_BITS
    return bits
