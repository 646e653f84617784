import gc

import pytest


@pytest.fixture(autouse=True)
def collect_garbage():
    """Collect after each test, so Amaranth's UnusedElaboratable warning (raised when an unused
    component is garbage-collected) fails the test that left it, not a later one at random.

    What survives a test's collection is frozen (``gc.freeze``: left out of every later
    collection), so each collection looks only at what that test made. A full collection over
    the simulators the workers keep built (SimBoard.powered_up) took up to 0.7 s a test, 210 s
    of the suite in all."""
    yield
    gc.collect()
    gc.freeze()
