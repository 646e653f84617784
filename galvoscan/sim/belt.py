"""The conveyor under the simulated board: a belt whose encoder the board's fly inputs read.

The belt moves at ``counts_per_s`` (signed: its direction) and its encoder's count is advanced
by that rate each machine period (``SimulatedBoard.machine_period_s``), in whole femtoseconds
and integers so that both backends count alike; the A and B lines are the count's place in a
quadrature turn (A leads B going forward). So the rate must stay within one count a period
(100,000 counts a second at 10 µs), as a real encoder's lines must stay within the receiver's
rate. A glitch turns both lines over at once for some periods: a decoder sees two illegal steps
and no move.
"""

from ..gateware.fly.encoder import QUADRATURE_CYCLE


__all__ = ["FEMTO", "advance", "lines"]


#: Femtoseconds a second: the belt's integration step is the machine period in fs.
FEMTO = 10 ** 15


def advance(count, fraction, counts_per_s, period_fs):
    """The count and its fraction (in counts × 10^-15) a period on."""
    fraction += counts_per_s * period_fs
    count += fraction // FEMTO
    return count, fraction % FEMTO


def lines(count, inverted=False):
    """``(a, b)`` for ``count``; both turned over while ``inverted`` (a glitch)."""
    a, b = QUADRATURE_CYCLE[count % 4]
    return (1 - a, 1 - b) if inverted else (a, b)
