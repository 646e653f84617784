"""The ULX3S bitstream on the simulated board: its configuration (every feature: all three
modes, correction with its 33 × 33 table, the interpolator, the RTC delays, wobble, the job
player, both links), at a clock its PLL also makes, for the tests that run the iCEBreaker's
builds to run this one too (tests/sim/test_compiled.py, on both backends)."""

import contextlib
from dataclasses import replace

import pytest

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


@contextlib.contextmanager
def ulx3s_sim(mo_lead):
    """Within it, `mark --sim --board ulx3s` runs the ULX3S's bitstream at 8 MHz (with the
    tests' ``mo_lead``: the compiled model tests/sim/test_compiled.py builds too) at 1 Mbaud;
    every board built is in ``built``."""
    import galvoscan.sim.board as module
    original = module.SimulatedBoard

    class Board(original):
        built = []

        def __init__(self, **kwargs):
            kwargs.update(ulx3s_board(mo_lead=mo_lead))
            super().__init__(**kwargs)
            self.built.append(self)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(module, "SimulatedBoard", Board)
        yield Board
