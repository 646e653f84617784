"""The start input: a foot switch, a PLC's output or the board's button, debounced."""

from amaranth.hdl import Module, Signal
from amaranth.lib import wiring
from amaranth.lib.cdc import FFSynchronizer
from amaranth.lib.wiring import In, Out


__all__ = ["StartInput", "DEFAULT_DEBOUNCE_MS", "debounce_ticks"]


#: Debounce of the start input, ms (RTC6 lets it be set from 0 to 1023 ms; a foot switch's
#: contacts bounce for a few ms).
DEFAULT_DEBOUNCE_MS = 10


def debounce_ticks(debounce_ms, tick_us):
    """Ticks of ``tick_us`` in a debounce of ``debounce_ms`` (checked: 1 … 1023 ms)."""
    if not isinstance(debounce_ms, int) or isinstance(debounce_ms, bool) or \
            not 1 <= debounce_ms <= 1023:
        raise ValueError(f"the start input's debounce must be a whole number of ms from 1 to "
                         f"1023, not {debounce_ms!r}")
    return int(debounce_ms * 1000 // tick_us)


class StartInput(wiring.Component):
    """A press of an active-low start input, once it has held steady for the debounce time.

    The pins are pulled up (an open input reads released) and each goes through its own
    synchroniser; the input is pressed while any of them is low. A change counts only once it
    has lasted ``debounce_ms``, so contact bounce and glitches start nothing.

    Parameters
    ----------
    inputs : int
        Start pins (a foot switch and the board's button: 2).
    debounce_ms : int
        Time a change must last, ms (1 … 1023).
    tick_us : int
        µs between :attr:`tick` pulses (an XY2-100 frame: 10).

    Interface attributes
    --------------------
    start_n : ``In(inputs, init=all ones)``
        The pins, 0 = pressed.
    tick : ``In(1)``
        One clock every ``tick_us``.
    pressed : ``Out(1)``
        High for one clock when a press has lasted ``debounce_ms``.
    held : ``Out(1)``
        The debounced level: pressed.
    """

    def __init__(self, *, inputs=2, debounce_ms=DEFAULT_DEBOUNCE_MS, tick_us=10):
        if not isinstance(inputs, int) or not 1 <= inputs <= 4:
            raise ValueError(f"inputs must be 1 to 4 pins, not {inputs!r}")
        self.debounce_ticks = debounce_ticks(debounce_ms, tick_us)
        super().__init__({"start_n": In(inputs, init=2 ** inputs - 1), "tick": In(1),
                          "pressed": Out(1), "held": Out(1)})

    def elaborate(self, platform):
        m = Module()
        pins = Signal(len(self.start_n), init=2 ** len(self.start_n) - 1)
        m.submodules.sync = FFSynchronizer(self.start_n, pins, init=2 ** len(self.start_n) - 1)
        level = Signal()
        m.d.comb += level.eq(~pins.all())
        steady = Signal(range(self.debounce_ticks + 1))
        with m.If(level == self.held):
            m.d.sync += steady.eq(0)
        with m.Elif(self.tick):
            with m.If(steady == self.debounce_ticks - 1):
                m.d.sync += [self.held.eq(level), steady.eq(0),
                             self.pressed.eq(level)]
            with m.Else():
                m.d.sync += steady.eq(steady + 1)
        with m.If(self.pressed):
            m.d.sync += self.pressed.eq(0)
        return m
