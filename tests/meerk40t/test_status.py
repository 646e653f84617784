"""The board's state in meerk40t's status bar (galvoscan/meerk40t/status.py, in the words of
galvoscan/outputs/board_state.py), headless: the signal meerk40t's main window shows as
"Laser: …" (tests/support/meerk40t_session.py finds it in meerk40t's own source) heard by a
listener on the kernel, as the window hears it, while the galvoscan device (the module's, from
tests/meerk40t/conftest.py) polls the simulated board, runs jobs on it, and the simulated
machine opens its interlock, raises its laser's alarm, and its scan head reports."""

import time

import pytest

pytest.importorskip("meerk40t")

from galvoscan.gateware.host.regmap import HeadStatus  # noqa: E402
from galvoscan.link.client import HostClient            # noqa: E402
from galvoscan.meerk40t.driver import SIM               # noqa: E402
from galvoscan.sim.board import SimTransport, SimulatedBoard  # noqa: E402
from galvoscan.sim.head import HEALTHY_HEAD             # noqa: E402

from meerk40t_session import spool_and_wait, status_bar_heard, status_bar_signal  # noqa: E402
from ulx3s_board import ulx3s_board                     # noqa: E402


#: The device's status poll here, s (short, so that a change shows within the test's time).
POLL_S = 0.2
#: The longest a state may take to be heard: a few polls and the kernel's signal ticks.
HEARD_WITHIN_S = 5.0
#: The state of the powered-up simulated board: nothing queued, the laser disarmed, its
#: interlock closed, no alarm, no fault latched (and a bitstream without the head's receiver).
READY = {"ready", "disarmed", "interlock closed"}


@pytest.fixture(scope="module")
def heard(meerk40t):
    """Each text the status bar was sent, in order, as the set of its items
    (:func:`meerk40t_session.status_bar_heard`), the device's status polled every
    :data:`POLL_S` meanwhile."""
    kernel, device, board, _ = meerk40t
    with status_bar_heard(kernel) as heard:
        device.status_poll_s = POLL_S
        try:
            yield heard
        finally:
            device.status_poll_s = 0.0


def _items(text):
    return set(text.split(", "))


def _hear(heard, wanted, what):
    """Wait until the last text heard satisfies ``wanted`` (its items); return its items."""
    deadline = time.monotonic() + HEARD_WITHIN_S
    while not (heard and wanted(heard[-1])):
        assert time.monotonic() < deadline, f"never heard {what}: heard {heard[-5:]}"
        time.sleep(0.02)
    return heard[-1]


def test_ready_after_the_start(meerk40t, heard):
    """With no job spooled, the device's poll makes the simulated board and reads it: ready,
    disarmed, the interlock closed."""
    kernel, device, board, _ = meerk40t
    assert _hear(heard, lambda items: items == READY, "ready") == READY
    assert device.driver.board is board.board
    assert device.driver.last_report is None and device.driver.last_error is None


def test_busy_during_a_job_and_ready_after_it(meerk40t, heard):
    """A rectangle marked: busy and armed while it runs (the job's own reads of the board),
    then ready and disarmed again."""
    kernel, device, board, _ = meerk40t
    _hear(heard, lambda items: items == READY, "ready")
    start = len(heard)
    spool_and_wait(kernel, device,
                   "rect 40mm 40mm 30mm 30mm engrave -s 400 -p 300 frequency 50")
    assert device.driver.last_error is None, device.driver.last_error
    _hear(heard, lambda items: items == READY, "ready after the job")
    assert any({"busy", "armed", "interlock closed"} <= items for items in heard[start:]), \
        heard[start:]


def test_the_interlock_and_an_alarm_while_idle(meerk40t, heard):
    """The machine's interlock opened, then its laser's alarm raised, with no job: each shown
    by the next poll; opening the interlock disarmed latches no fault; both cleared, ready."""
    kernel, device, board, _ = meerk40t
    _hear(heard, lambda items: items == READY, "ready")
    try:
        board.board.interlock_closed = False
        items = _hear(heard, lambda items: "interlock open" in items, "the interlock open")
        assert items == {"ready", "disarmed", "interlock open"}
        board.board.alarms_clear = False
        items = _hear(heard, lambda items: "laser alarm" in items, "the alarm")
        assert items == {"ready", "disarmed", "interlock open", "laser alarm"}
    finally:
        board.board.interlock_closed = board.board.alarms_clear = True
    _hear(heard, lambda items: items == READY, "ready again")


def test_a_fault_latched_by_the_interlock_opening_mid_job(meerk40t, heard):
    """The interlock opened while a job marks (armed): the job stops, disarmed, the rest of it
    left in the board's queue (busy), and the status bar shows the latched interlock fault,
    after the interlock closes too, until ``fault_clear``; the queue emptied, ready."""
    kernel, device, board, _ = meerk40t
    _hear(heard, lambda items: items == READY, "ready")

    def open_when_armed(origin, text):
        if {"busy", "armed"} <= _items(text):
            board.board.interlock_closed = False
    kernel.listen(status_bar_signal(), open_when_armed)
    try:
        # (4 sides of 70 mm at 200 mm/s: 1.4 s of the board's time, so that the interlock
        # opens with most of it still queued)
        spool_and_wait(kernel, device,
                       "rect 20mm 20mm 70mm 70mm engrave -s 200 -p 300 frequency 50")
    finally:
        kernel.unlisten(status_bar_signal(), open_when_armed)
    assert device.driver.last_error and "interlock" in device.driver.last_error
    try:
        # (the job's last read, before it disarmed, may be heard first: armed, the fault)
        items = _hear(heard, lambda items: {"disarmed", "fault: interlock"} <= items,
                      "the latched fault once the job stopped")
        assert items == {"busy", "disarmed", "interlock open", "fault: interlock"}
    finally:
        board.board.interlock_closed = True
    items = _hear(heard, lambda items: "interlock closed" in items, "the interlock closed")
    assert items == {"busy", "disarmed", "interlock closed", "fault: interlock"}
    with device.driver._lock:           # (the link, as a poll or a job takes it)
        client = HostClient(SimTransport(board.board))
        client.write("fault_clear", 1)
        client.write("vec_flush", 1)
    _hear(heard, lambda items: items == READY, "ready once the fault is cleared")


def test_a_board_that_cannot_be_read_says_why(meerk40t, heard, tmp_path):
    """The link set to a port that is not there: the next poll says in the status bar that
    there is no board, and why (the port's error); the simulated board again: ready."""
    kernel, device, board, _ = meerk40t
    _hear(heard, lambda items: items == READY, "ready")
    missing = tmp_path / "no-such-port"
    device.link = str(missing)
    try:
        _hear(heard, lambda items: any(item.startswith("no board:") and str(missing) in item
                                       for item in items), "no board")
    finally:
        device.link = SIM
    _hear(heard, lambda items: items == READY, "ready again")


def test_the_scan_heads_state_on_a_bitstream_that_reads_it(meerk40t, heard):
    """The device's board swapped for the ULX3S's (its bitstream reads the head's STATUS line),
    a healthy head on it: the status bar adds ``head ok``; its Temp OK dropped: ``head: Temp OK
    low``, and ``board_status`` says the head's bits; no head answering: ``head missing``. The
    default bitstream again (no receiver): no word of a head."""
    kernel, device, board, lines = meerk40t
    _hear(heard, lambda items: items == READY, "ready")
    with_head = SimulatedBoard(backend="compiled", head_word=HEALTHY_HEAD, **ulx3s_board())
    with device.driver._lock:           # (the link, as a poll or a job takes it)
        device.driver.board = with_head
    try:
        assert _hear(heard, lambda items: "head ok" in items, "a healthy head") == \
            READY | {"head ok"}
        with_head.head_word = HEALTHY_HEAD & ~(1 << HeadStatus["temp_ok"].offset)
        assert _hear(heard, lambda items: "head: Temp OK low" in items, "Temp OK low") == \
            READY | {"head: Temp OK low"}
        said = len(lines)
        kernel.console("board_status\n")
        found = [line for line in lines[said:] if "galvoscan: board:" in line]
        assert len(found) == 1 and "; head: " in found[0] and "no Temp OK" in found[0], found
        with_head.head_word = None
        assert _hear(heard, lambda items: "head missing" in items, "no head") == \
            READY | {"head missing"}
    finally:
        with device.driver._lock:
            device.driver.board = board.board
    _hear(heard, lambda items: items == READY, "ready on the default bitstream again")
