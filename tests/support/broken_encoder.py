"""Deliberately broken quadrature decoders, to show that the encoder proof catches each
fault: the real decoder with one of its steps changed."""

from amaranth.hdl import Const, Signal, signed

from galvoscan.gateware.fly.encoder import QuadratureDecoder


#: Each fault: what it does, and the property it breaks.
ENCODER_FAULTS = {
    "two_edges_counted": ("both lines changing is counted as a step forward",
                          "the count follows the lines edge by edge and never wraps"),
    "wraps": ("the count wraps at its ends instead of stopping there",
              "the count follows the lines edge by edge and never wraps"),
    "direction_swapped": ("one of the four edges counted the wrong way",
                          "the count follows the lines edge by edge and never wraps"),
    "illegal_not_counted": ("illegal transitions go uncounted",
                            "a two-edge step is counted as illegal and moves nothing"),
    "previous_reset": ("the last sample is reset with the rest: a phantom edge after a reset",
                       "the decoder compares each sample with the last"),
}


class BrokenDecoder(QuadratureDecoder):
    """The decoder with ``fault``; 3 bits of count, so that a bounded check from reset reaches
    the count's ends (the real decoder's proof is by induction, at 32 bits)."""

    def __init__(self, fault, *, count_bits=3):
        if fault not in ENCODER_FAULTS:
            raise ValueError(f"unknown fault {fault!r}")
        self.fault = fault
        super().__init__(count_bits=count_bits)
        if fault == "previous_reset":
            self.previous = Signal(2)

    def _steps(self, m):
        forward, backward, illegal = super()._steps(m)
        if self.fault == "two_edges_counted":
            counted = Signal()
            m.d.comb += counted.eq(forward | illegal)
            return counted, backward, illegal
        if self.fault == "direction_swapped":
            up, down = Signal(), Signal()
            odd = self.previous == 0b11
            m.d.comb += [up.eq((forward & ~odd) | (backward & odd)),
                         down.eq((backward & ~odd) | (forward & odd))]
            return up, down, illegal
        if self.fault == "illegal_not_counted":
            return forward, backward, Const(0, 1)
        return forward, backward, illegal

    def _limits(self):
        if self.fault == "wraps":
            # Ends the count never equals (one past each): it runs over them.
            bits = len(self.count)
            return (Const(2 ** (bits - 1), signed(bits + 1)),
                    Const(-2 ** (bits - 1) - 1, signed(bits + 1)))
        return super()._limits()
