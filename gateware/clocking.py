"""The system clock against the rates it must make: the one place a clock is checked.

The XY2-100 transmitter needs a whole, even number of system clocks per bit (each half of
``xy2_clk`` is a whole number of clocks); the UART needs a divisor within 2 % of its baud rate.
The system top, the board files, the bitstream build and the command line all ask
:func:`check_clocks`, so a clock is refused with the same message wherever it is given, and
before anything is built.
"""

from typing import NamedTuple

from .host.uart import uart_divisor
from .phy.xy2_100 import clocks_per_bit


__all__ = ["ClockPlan", "check_clocks", "XY2_100_BIT_RATE", "DEFAULT_BAUD"]


#: The XY2-100 bit rate: 2 Mbit/s, a 10 µs frame.
XY2_100_BIT_RATE = 2_000_000
#: The host serial port's default rate (8N1).
DEFAULT_BAUD = 115_200


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
