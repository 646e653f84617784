"""The galvoscan board's state in meerk40t's status bar.

meerk40t's main window shows what a device signals as ``pipe;usb_status`` in its status bar
(``Laser: …``, ``meerk40t/gui/wxmmain.py``), where its balor device signals its USB link. The
galvoscan device signals the board's state there in a few words, said by galvoscan's one
account of the board's state (:meth:`galvoscan.outputs.board_state.BoardState.short`): ready
or busy, armed or disarmed, the interlock open or closed, a laser alarm, the scan head (on a
bitstream that reads its STATUS line), the latched faults. It is read off the board

- by each ``status`` read the device's own job or framing makes (the streamer's), the job
  busy (paused while the board holds it), the head as last read whole;
- after each job or framing, on the link the job had;
- every ``status_poll_s`` seconds (a setting of :class:`~galvoscan.meerk40t.device.GalvoscanDevice`)
  while the device is active and its link free, in a thread of its own (a ``sim`` link's
  simulated board is made by the first read, which may compile it);

and signalled when it changes. ``board_status`` in meerk40t's console says the same state in a
line (:meth:`~galvoscan.outputs.board_state.BoardState.summary`).
"""

import threading
import time

from meerk40t.kernel import Job

from ..link.client import ClientError
from ..outputs.board_state import BoardState


__all__ = ["SIGNAL", "BoardStatus"]

#: The signal meerk40t's status bar shows (``Laser: {text}``).
SIGNAL = "pipe;usb_status"

#: How often the scheduler asks whether a poll is due, s (the poll's own period is the
#: device's ``status_poll_s``).
TICK_S = 0.1


class BoardStatus:
    """The device's board state, signalled as :data:`SIGNAL` when it changes. ``read(wait_s)``
    (the driver's): the board's state read over the device's link and shown here (through
    :meth:`seen`, or :meth:`failed` and raised as :class:`~galvoscan.link.client.ClientError`,
    :class:`OSError` or :class:`ValueError`), under the link's lock; None when a job has the
    link for longer than ``wait_s`` seconds."""

    def __init__(self, service, read):
        self.service = service
        self._read = read
        #: The last text signalled (None: none yet).
        self.text = None
        self._head = None
        self._polling = threading.Lock()
        self._last_poll = None
        self._job = Job(process=self._tick, interval=TICK_S,
                        job_name=f"{service.path}/galvoscan_board_status")

    def show(self, text):
        """Signal ``text`` if it is not what the status bar shows already."""
        if text != self.text:
            self.text = text
            self.service.signal(SIGNAL, text)

    def seen(self, state, *, activity=None):
        """The board's :class:`~galvoscan.outputs.board_state.BoardState`, read whole by whoever
        had the link (``activity``: what the device knows the board is doing, as
        :meth:`~galvoscan.outputs.board_state.BoardState.short` takes it)."""
        self._head = state.head
        self.show(state.short(activity))

    def seen_flags(self, flags, *, activity):
        """Only the ``status`` flags, as a job's own reads have them: the head as last read."""
        self.show(BoardState(flags=flags, head=self._head).short(activity))

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
