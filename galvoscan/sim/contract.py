"""The simulated board's contract: what both of its backends (Amaranth's simulator,
:mod:`.board_engine`; the compiled model, :mod:`.compiled`) provide to
:class:`~.board.SimulatedBoard`, so that each depends on this module and neither on the other.

An engine is built with the board (``engine(board, record_samples=..., record_pins=...)``),
takes what the host queued on the board as it goes onto the pins, and appends to the board's
records what the pins did, waking at the instants named here, so that both backends keep the
same records to the clock.
"""

from typing import Protocol


__all__ = ["BACKENDS", "Engine", "LASER_PINS", "MACHINE_PERIOD_S", "SPI_IDLE_S", "PIN_FIELDS",
           "pack_pins"]


#: The simulated board's backends: ``auto`` is the compiled one where it can be built.
BACKENDS = ("auto", "compiled", "python")

# The laser pins recorded at every change, in this order.
LASER_PINS = ("laser_enable", "laser_mo", "laser_am", "laser_prr", "laser_latch", "laser_guide")

#: How often the machine's interlock and alarm pins are set from the board's attributes.
MACHINE_PERIOD_S = 10e-6

#: How often an idle SPI host looks for a transfer to send.
SPI_IDLE_S = 5e-6

#: The pins ``record_pins`` records, as ``(name, first bit, width)`` of the packed value
#: (``laser_alarm`` 0 wide on a build without alarms).
PIN_FIELDS = (("laser_mo", 0, 1), ("laser_am", 1, 1), ("laser_prr", 2, 1),
              ("interlock_open", 3, 1), ("laser_latch", 4, 1), ("laser_power", 5, 8),
              ("laser_enable", 13, 1), ("laser_alarm", 14, 4), ("laser_guide", 18, 1),
              ("xy2_sync", 19, 1))


def pack_pins(values):
    """The values of :data:`PIN_FIELDS`' pins, in that order, as one packed number."""
    packed = 0
    for (_, first, _width), value in zip(PIN_FIELDS, values):
        packed |= value << first
    return packed


class Engine(Protocol):
    """A backend of the simulated board."""

    #: ``"python"`` or ``"compiled"``: what ``SimulatedBoard.backend`` says.
    name: str

    def run_until(self, seconds):
        """Run the board on to ``seconds`` of its own time."""

    def reset(self):
        """Back to power-up: the same design, every signal and memory at its initial value."""

    def close(self):
        """Let go of what the engine holds (a waveform file, the compiled board's memory)."""
