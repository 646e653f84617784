"""The system clock against the rates it must make: the one place a clock is checked.

The XY2-100 transmitter needs a whole, even number of system clocks per bit (each half of
``xy2_clk`` is a whole number of clocks); the UART needs a divisor within 2 % of its baud rate.
The system top, the board files, the bitstream build and the command line all ask
:func:`check_clocks`, so a clock is refused with the same message wherever it is given, and
before anything is built.
"""

from typing import NamedTuple

from .limits import FRAME_US
from .host.uart import uart_divisor
from .phy.xy2_100 import FRAME_BITS, clocks_per_bit


__all__ = ["ClockPlan", "check_clocks", "XY2_100_BIT_RATE", "DEFAULT_BAUD", "FTDI_BAUDS",
           "default_baud"]


#: The XY2-100 bit rate: 2 Mbit/s, a 10 µs frame.
XY2_100_BIT_RATE = 2_000_000
assert FRAME_BITS * 1_000_000 == FRAME_US * XY2_100_BIT_RATE
#: The host serial port's default rate (8N1). 1 Mbaud carries 25 000 frames/s, 8 300 vector
#: segments/s: enough to keep the queue fed with 1 mm segments at several m/s (115 200 baud
#: carries 960). The boards' FT2232H makes it exactly (3 MHz / 3), and a 12 MHz clock divides
#: it exactly (12 clocks a bit); 3 Mbaud needs a 24 MHz or faster clock (8 clocks a bit).
DEFAULT_BAUD = 1_000_000
#: Rates the FT2232H makes exactly, for the command line's choices.
FTDI_BAUDS = (115_200, 1_000_000, 3_000_000)


def default_baud(clk_freq):
    """:data:`DEFAULT_BAUD`, or for a clock too slow to carry it (a simulation's few MHz) the
    fastest of :data:`FTDI_BAUDS` below it that the clock does carry."""
    for baud in sorted((b for b in FTDI_BAUDS if b <= DEFAULT_BAUD), reverse=True):
        try:
            uart_divisor(clk_freq, baud)
        except ValueError:
            continue
        return baud
    return DEFAULT_BAUD         # none: check_clocks says why


class ClockPlan(NamedTuple):
    """What a system clock gives the cores that count it."""
    clk_freq: float
    clocks_per_bit: int     # system clocks per XY2 bit (even, at least 2)
    uart_divisor: int       # system clocks per UART bit


def check_clocks(clk_freq, bit_rate=XY2_100_BIT_RATE, baud=DEFAULT_BAUD):
    """Check a system clock against the XY2 bit rate and the UART baud rate.

    Parameters
    ----------
    clk_freq : int or float
        System clock, Hz.
    bit_rate : int or float
        XY2 bit rate, Hz (2 MHz: XY2-100; 4 MHz: XY2-200).
    baud : int
        UART rate.

    Returns
    -------
    :class:`ClockPlan`

    Raises
    ------
    ValueError
        If ``clk_freq / bit_rate`` is not an even integer of at least 2, or the UART divisor
        is under 8 or more than 2 % off.
    """
    return ClockPlan(clk_freq=clk_freq, clocks_per_bit=clocks_per_bit(clk_freq, bit_rate),
                     uart_divisor=uart_divisor(clk_freq, baud))
