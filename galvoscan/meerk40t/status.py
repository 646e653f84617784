"""The galvoscan board's state in meerk40t's status bar.

meerk40t's main window shows what a device signals as ``pipe;usb_status`` in its status bar
(``Laser: …``, ``meerk40t/gui/wxmmain.py``), where its balor device signals its USB link. The
galvoscan device signals the board's state there, a short text (:func:`short_text`): ready or
busy, armed or disarmed, the interlock open or closed, a laser alarm, the latched faults. It is
read off the board's ``status`` register

- by each status read the device's own job or framing makes (the streamer's), the job busy;
- after each job or framing, on the link the job had;
- every ``status_poll_s`` seconds (a setting of :class:`~galvoscan.meerk40t.device.GalvoscanDevice`)
  while the device is active and its link free, in a thread of its own (a ``sim`` link's
  simulated board is made by the first read, which may compile it);

and signalled when it changes. ``board_status`` in meerk40t's console says the same state in a
line (:func:`console_line`).
"""

import threading
import time

from meerk40t.kernel import Job

from ..link.client import ClientError


__all__ = ["SIGNAL", "LATCHED", "latched", "short_text", "console_line", "BoardStatus"]

#: The signal meerk40t's status bar shows (``Laser: {text}``).
SIGNAL = "pipe;usb_status"

#: The faults the board latches until ``fault_clear`` (the ``status`` register's ``fault_*``).
LATCHED = ("interlock", "watchdog", "alarm", "link")

#: How often the scheduler asks whether a poll is due, s (the poll's own period is the
#: device's ``status_poll_s``).
TICK_S = 0.1


def _items(flags, marking):
    """The state's items that the status bar and the console share."""
    return ["busy" if marking or flags.vector_busy or flags.player_busy else "ready",
            "armed" if flags.armed else "disarmed",
            "interlock open" if flags.interlock_open else "interlock closed",
            *(["laser alarm"] if flags.alarm else [])]


def latched(flags):
    """The names of the faults ``flags`` (the ``status`` register's) has latched."""
    return [name for name in LATCHED if getattr(flags, f"fault_{name}")]


def short_text(flags, *, marking=False):
    """The board's state for the status bar, from its ``status`` flags; ``marking``: a job of
    the device's is running (busy whatever the queue holds)."""
    faults = latched(flags)
    return ", ".join(_items(flags, marking) + ([f"fault: {', '.join(faults)}"] if faults else []))


def console_line(flags):
    """The board's state in meerk40t's console (``board_status``)."""
    faults = latched(flags)
    return ", ".join(_items(flags, False) + [
        f"latched fault: {', '.join(faults)} (`galvoscan send fault_clear=1` clears it)"
        if faults else "no fault latched"])


class BoardStatus:
    """The device's board state, signalled as :data:`SIGNAL` when it changes. ``read(wait_s)``
    (the driver's): the board's ``status`` read over the device's link and shown here (through
    :meth:`seen`, or :meth:`failed` and raised as :class:`~galvoscan.link.client.ClientError`,
    :class:`OSError` or :class:`ValueError`), under the link's lock; None when a job has the
    link for longer than ``wait_s`` seconds."""

    def __init__(self, service, read):
        self.service = service
        self._read = read
        #: The last text signalled (None: none yet).
        self.text = None
        self._polling = threading.Lock()
        self._last_poll = None
        self._job = Job(process=self._tick, interval=TICK_S,
                        job_name=f"{service.path}/galvoscan_board_status")

    def show(self, text):
        """Signal ``text`` if it is not what the status bar shows already."""
        if text != self.text:
            self.text = text
            self.service.signal(SIGNAL, text)

    def seen(self, flags, *, marking=False):
        """The state read off the board (its ``status`` flags) by whoever had the link."""
        self.show(short_text(flags, marking=marking))

    def failed(self, error):
        """The board could not be read: why, in the status bar."""
        self.show(f"no board: {error}")

    def poll(self):
        """Read the board now, if no job has the link, and show its state (a job's own reads
        show it)."""
        try:
            self._read(0)
        except (ClientError, OSError, ValueError):
            pass                                # (shown by failed)

    # --- the periodic poll, while the device is active -----------------------------------------

    def start(self):
        """Poll every ``status_poll_s`` seconds from now (the first poll one period on)."""
        self._last_poll = time.monotonic()
        self.service.kernel.schedule(self._job)

    def stop(self):
        self.service.kernel.unschedule(self._job)

    def _tick(self):
        period = float(getattr(self.service, "status_poll_s", 0) or 0)
        if period <= 0 or time.monotonic() - self._last_poll < period:
            return
        if not self._polling.acquire(blocking=False):
            return                              # (the last poll still runs)
        self._last_poll = time.monotonic()
        threading.Thread(target=self._poll_once, name="galvoscan board status",
                         daemon=True).start()

    def _poll_once(self):
        try:
            self.poll()
        finally:
            self._last_poll = time.monotonic()
            self._polling.release()
