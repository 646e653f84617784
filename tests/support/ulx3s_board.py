"""The ULX3S bitstream on the simulated board: its configuration (every feature: all three
modes, correction with its 33 × 33 table, the interpolator, the RTC delays, wobble, the job
player, both links), at a clock its PLL also makes, for the tests that run the iCEBreaker's
builds to run this one too (tests/sim/test_compiled.py, on both backends)."""

from dataclasses import replace

from galvoscan.build import starting_table
from galvoscan.gateware.top import ScanSettings
from galvoscan.platforms.ulx3s import ULX3SScanner


def ulx3s_board(clock=8e6, *, settings=None, **options):
    """``SimulatedBoard`` keyword arguments for the ULX3S bitstream at ``clock`` (8 MHz: the
    slowest the PLL makes that carries 1 Mbaud, a third of the clocks of its 24 MHz for the
    same frames), with the build ``options`` given (the tests' shorter ``mo_lead`` or
    ``start_debounce_ms``); ``settings``: the scan settings it starts with (None: stopped in
    vector mode, as ``galvoscan mark`` finds a board)."""
    config = replace(ULX3SScanner.config(clock=clock), **options)
    return dict(config=config,
                correction=starting_table("ulx3s"),
                settings=ScanSettings(mode="vector", run=False) if settings is None
                else settings)
