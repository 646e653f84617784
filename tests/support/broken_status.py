"""Deliberately broken status receivers, to show that the head status proof catches each
fault: the real receiver with one of its checks changed."""

from galvoscan.gateware.phy.xy2_100 import FRAME_BITS
from galvoscan.gateware.phy.xy2_status import XY2StatusReceiver


#: Each fault: what it does, and the property it breaks.
STATUS_FAULTS = {
    "parity_unchecked": ("a frame with odd parity is taken",
                         "a frame is taken exactly when its code is 001 and its parity even"),
    "code_unchecked": ("a frame with any code is taken",
                       "a frame is taken exactly when its code is 001 and its parity even"),
    "data_shifted": ("the status word is taken a bit off (the parity bit in, D15 out)",
                     "a frame taken gives its 16 data bits"),
}
# A receiver that keeps a lost head's last word is left out: its counterexample needs a good
# frame and then a refused one, 160 clocks, and the bounded check did not reach it in 15
# minutes. tests/gateware/phy/test_xy2_status.py checks a head gone missing reads 0, against
# a head model of its own.


class BrokenReceiver(XY2StatusReceiver):
    """The receiver at 4 clocks a bit with ``fault``; a head missing after one refused frame,
    so that a bounded check from reset reaches it (a good frame, then a bad one)."""

    def __init__(self, fault):
        if fault not in STATUS_FAULTS:
            raise ValueError(f"unknown fault {fault!r}")
        self.fault = fault
        super().__init__(clocks_per_bit=4, missing_frames=1)

    def _taken(self, word):
        if self.fault == "parity_unchecked":
            return word[FRAME_BITS - 3:] == 0b001
        if self.fault == "code_unchecked":
            return ~word.xor()
        return super()._taken(word)

    def _data(self, word):
        if self.fault == "data_shifted":
            return word[0:16]
        return super()._data(word)
