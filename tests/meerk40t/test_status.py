"""The board's state in meerk40t's status bar (galvoscan/meerk40t/status.py), headless: the
signal meerk40t's main window shows as "Laser: …" (found in meerk40t's own wxmmain.py, read as
text: no wxPython here) heard by a listener on the kernel, as the window hears it, while the
galvoscan device polls the simulated board, runs jobs on it, and the simulated machine opens
its interlock and raises its laser's alarm."""

import re
import time
from pathlib import Path

import pytest

meerk40t_package = pytest.importorskip("meerk40t")

from galvoscan.link.client import HostClient            # noqa: E402
from galvoscan.meerk40t.driver import SIM               # noqa: E402
from galvoscan.sim.board import SimTransport            # noqa: E402

from meerk40t_kernel import galvoscan_in_meerk40t       # noqa: E402


#: The device's status poll here, s (short, so that a change shows within the test's time).
POLL_S = 0.2
#: The longest a state may take to be heard: a few polls and the kernel's signal ticks.
HEARD_WITHIN_S = 5.0
#: The state of the powered-up simulated board: nothing queued, the laser disarmed, its
#: interlock closed, no alarm, no fault latched.
READY = {"ready", "disarmed", "interlock closed"}


def _status_bar_signal():
    """The signal whose text meerk40t's main window puts in its status bar as "Laser: …": the
    ``@signal_listener`` of the handler that sets it, read off meerk40t's source."""
    source = (Path(meerk40t_package.__file__).parent / "gui" / "wxmmain.py").read_text()
    found = re.findall(r'@signal_listener\("([^"]+)"\)\s+def \w+\(self, origin, value\):\s+'
                       r'self\.main_statusbar\.SetStatusText\(\s+_\("Laser: \{index\}"\)'
                       r'\.format\(index=value\)', source)
    assert len(found) == 1, "meerk40t's window no longer shows a device's state so"
    return found[0]


@pytest.fixture(scope="module")
def meerk40t():
    """``(kernel, device, board, heard)``: the galvoscan device on the simulated board, its
    status polled every :data:`POLL_S`; ``heard``: each text the status bar was sent, in
    order."""
    with galvoscan_in_meerk40t(status_poll_s=POLL_S) as (kernel, device, board, _):
        heard = []
        signal = _status_bar_signal()

        def listener(origin, text):
            heard.append(text)
        kernel.listen(signal, listener)
        try:
            yield kernel, device, board, heard
        finally:
            kernel.unlisten(signal, listener)


def _items(text):
    return set(text.split(", "))


def _hear(heard, wanted, what):
    """Wait until the last text heard satisfies ``wanted`` (its items); return its items."""
    deadline = time.monotonic() + HEARD_WITHIN_S
    while not (heard and wanted(_items(heard[-1]))):
        assert time.monotonic() < deadline, f"never heard {what}: heard {heard[-5:]}"
        time.sleep(0.02)
    return _items(heard[-1])


def _spool(kernel, device, command, plan, *, timeout_s=60):
    """Spool ``command``'s job and wait until the device has run or refused it."""
    device.driver.last_report = device.driver.last_error = None
    kernel.elements.clear_all()
    kernel.console(f"{command} {plan} copy-selected preprocess validate blob preopt optimize "
                   f"spool\n")
    deadline = time.monotonic() + timeout_s
    while device.driver.last_report is None and device.driver.last_error is None:
        assert time.monotonic() < deadline, "the device did not finish the job"
        time.sleep(0.02)


def test_ready_after_the_start(meerk40t):
    """With no job spooled, the device's poll makes the simulated board and reads it: ready,
    disarmed, the interlock closed."""
    kernel, device, board, heard = meerk40t
    assert _hear(heard, lambda items: items == READY, "ready") == READY
    assert device.driver.board is board.board
    assert device.driver.last_report is None and device.driver.last_error is None


def test_busy_during_a_job_and_ready_after_it(meerk40t):
    """A rectangle marked: busy and armed while it runs (the job's own reads of the board),
    then ready and disarmed again."""
    kernel, device, board, heard = meerk40t
    _hear(heard, lambda items: items == READY, "ready")
    start = len(heard)
    _spool(kernel, device, "rect 40mm 40mm 30mm 30mm engrave -s 400 -p 300 frequency 50",
           "plan1")
    assert device.driver.last_error is None, device.driver.last_error
    _hear(heard, lambda items: items == READY, "ready after the job")
    during = [_items(text) for text in heard[start:]]
    assert any({"busy", "armed", "interlock closed"} <= items for items in during), during


def test_the_interlock_and_an_alarm_while_idle(meerk40t):
    """The machine's interlock opened, then its laser's alarm raised, with no job: each shown
    by the next poll; opening the interlock disarmed latches no fault; both cleared, ready."""
    kernel, device, board, heard = meerk40t
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


def test_a_fault_latched_by_the_interlock_opening_mid_job(meerk40t):
    """The interlock opened while a job marks (armed): the job stops, disarmed, the rest of it
    left in the board's queue (busy), and the status bar shows the latched interlock fault,
    after the interlock closes too, until ``fault_clear``; the queue emptied, ready."""
    kernel, device, board, heard = meerk40t
    _hear(heard, lambda items: items == READY, "ready")

    def open_when_armed(origin, text):
        if {"busy", "armed"} <= _items(text):
            board.board.interlock_closed = False
    kernel.listen(_status_bar_signal(), open_when_armed)
    try:
        # (4 sides of 70 mm at 200 mm/s: 1.4 s of the board's time, so that the interlock
        # opens with most of it still queued)
        _spool(kernel, device, "rect 20mm 20mm 70mm 70mm engrave -s 200 -p 300 frequency 50",
               "plan2")
    finally:
        kernel.unlisten(_status_bar_signal(), open_when_armed)
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


def test_a_board_that_cannot_be_read_says_why(meerk40t, tmp_path):
    """The link set to a port that is not there: the next poll says in the status bar that
    there is no board, and why (the port's error); the simulated board again: ready."""
    kernel, device, board, heard = meerk40t
    _hear(heard, lambda items: items == READY, "ready")
    missing = tmp_path / "no-such-port"
    device.link = str(missing)
    try:
        _hear(heard, lambda items: any(item.startswith("no board:") and str(missing) in item
                                       for item in items), "no board")
    finally:
        device.link = SIM
    _hear(heard, lambda items: items == READY, "ready again")
