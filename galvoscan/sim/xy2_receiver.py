"""A scan head's view of the XY2-100 bus: bits sampled on the falling clock edge, made into frames.

Used by ``galvoscan sim`` to turn the simulated wires into positions, exactly as a scan head
would read them, with every frame's parity and control bits checked.
"""

import bisect
from dataclasses import dataclass


__all__ = ["XY2Frame", "XY2Receiver", "XY2ProtocolError", "frame_of_each_pulse"]


class XY2ProtocolError(ValueError):
    """The wires broke the XY2-100 protocol."""


@dataclass(frozen=True)
class XY2Frame:
    """One decoded frame: the position on each axis, in galvo units."""
    x: int
    y: int


class XY2Receiver:
    """Assembles frames from samples taken on each falling edge of ``xy2_clk``.

    A frame is the 20 bits from a rise of SYNC to the bit where SYNC is low (the parity bit).
    Bits before the first SYNC rise are ignored.

    Parameters
    ----------
    control_bits : int
        The control bits every frame must carry (``0b001`` for 16-bit positions).
    """

    FRAME_BITS = 20

    def __init__(self, *, control_bits=0b001):
        self.control_bits = control_bits
        self._words = None  # (x, y) bits so far in this frame, or None before the first frame
        self._count = 0
        self._last_sync = 0

    def sample(self, sync, x, y):
        """Take one falling-edge sample; return an :class:`XY2Frame` when one is complete."""
        if sync and not self._last_sync:
            if self._words is not None and self._count:
                raise XY2ProtocolError(f"SYNC rose after {self._count} bits, mid-frame")
            self._words, self._count = (0, 0), 0
        self._last_sync = sync
        if self._words is None:
            return None
        if not sync and self._count == 0:
            raise XY2ProtocolError("a clock with SYNC low between frames: frames must be "
                                   "back to back")
        word_x, word_y = self._words
        self._words = ((word_x << 1) | x, (word_y << 1) | y)
        self._count += 1
        if sync:
            if self._count >= self.FRAME_BITS:
                raise XY2ProtocolError("SYNC high for 20 bits: the parity bit is missing")
            return None
        if self._count != self.FRAME_BITS:
            raise XY2ProtocolError(f"SYNC fell after {self._count - 1} bits, not 19")
        self._count = 0
        return XY2Frame(self._check(self._words[0], "X"), self._check(self._words[1], "Y"))

    def _check(self, word, axis):
        if bin(word).count("1") % 2:
            raise XY2ProtocolError(f"{axis} frame {word:05x} has odd parity")
        if word >> 17 != self.control_bits:
            raise XY2ProtocolError(
                f"{axis} frame {word:05x} has control bits {word >> 17:03b}, "
                f"not {self.control_bits:03b}")
        return (word >> 1) & 0xFFFF


def frame_of_each_pulse(sync_rises, pulses, frames):
    """``[(frame, clock)]``: the frame whose position each laser pulse fell on, of ``frames``
    complete frames, from the clocks of the SYNC rises and of the pulses.

    Frame k is in force from the SYNC rise that starts frame k + 1 (the PHY takes the next
    point as it starts a frame); a pulse on that very clock still falls on frame k - 1.
    Pulses before the first frame or after the last complete one are left out."""
    placed = []
    for cycle in pulses:
        k = bisect.bisect_left(sync_rises, cycle) - 2
        if 0 <= k < frames:
            placed.append((k, cycle))
    return placed
