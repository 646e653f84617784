import gc

import pytest


@pytest.fixture(autouse=True)
def collect_garbage():
    """Collect after each test, so Amaranth's UnusedElaboratable warning (raised when an unused
    component is garbage-collected) fails the test that left it, not a later one at random."""
    yield
    gc.collect()
