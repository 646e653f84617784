"""Running a job on a board: parameters set, the laser armed, vector segments streamed into the
512-segment queue as it empties, and the laser disarmed however the job ends.

The queue's depth is the board's: read off ``fifo_free`` while the queue is empty (a real
board's is 512; a simulated one may be built shorter).

The link carries one frame at a time; a segment is three (``vec_x``, ``vec_y``, ``vec_op``). The
streamer writes at most a batch of segments between two reads of ``fifo_free``, so no more
than a batch's frames are ever in flight, and a read answered tells it the board has taken
everything sent before. Status is read between batches: a latched fault, an open interlock or
an alarm stops the job at once.

Whatever stops a job early (Ctrl-C, a lost link, a board fault, an error in this code), the
first thing sent after it is ``arm = 0``, then ``run = 0``; the exception then goes on to the
caller. Nothing of a job is dropped silently: a refused segment (``vec_rejected``) or frame
(``errors``) is counted and reported, and :class:`StreamReport` says how many.
"""

import sys
import time
from dataclasses import dataclass, field

from ..gateware.host.regmap import (BY_NAME, VECTOR_QUEUE_DEPTH, Capabilities, Mode, Status,
                                    VectorOp)
from ..gateware.host.fields import pack
from ..gateware.sources.vector import VecOpWord
from .corners import corner_frames


__all__ = ["JobAborted", "StreamReport", "JobStreamer", "QUEUE_DEPTH", "COUNTERS",
           "DEFAULT_BATCH", "check_segment", "segment_words", "job_segments"]


#: Segments the bitstream's vector queue holds (the streamer reads a board's own depth).
QUEUE_DEPTH = VECTOR_QUEUE_DEPTH
#: Segments the streamer writes between two reads of ``fifo_free`` (see :class:`JobStreamer`).
DEFAULT_BATCH = 128
#: The board's counters a job reports, read before and after.
COUNTERS = ("vec_underruns", "vec_stalls", "vec_rejected", "errors")
_COUNTER_TOP = 0xFFFF


class JobAborted(Exception):
    """The board stopped the job (a fault, the interlock, an alarm); the laser is disarmed."""


@dataclass
class StreamReport:
    """What a job did on the board.

    Attributes
    ----------
    segments : int
        Segments the board took.
    counters : dict
        Increase of each of :data:`COUNTERS` during the job (underruns: the queue ran dry while
        marking; stalls: frames a line waited for its next segment; rejected: segments refused
        for a full queue; errors: frames the board refused).
    pulses : int
        Laser pulses emitted during the job (the board's counter, read in time to unwrap it).
    seconds : float
        Host time the job took.
    """
    segments: int = 0
    counters: dict = field(default_factory=dict)
    pulses: int = 0
    seconds: float = 0.0

    @classmethod
    def total(cls, reports):
        """The reports of jobs run one after another (a job's layers, a batch's parts) as one:
        segments, pulses, time and each counter summed."""
        reports = list(reports)
        counters = {}
        for report in reports:
            for name, value in report.counters.items():
                counters[name] = counters.get(name, 0) + value
        return cls(segments=sum(r.segments for r in reports), counters=counters,
                   pulses=sum(r.pulses for r in reports), seconds=sum(r.seconds for r in reports))

    @property
    def clean(self):
        """Nothing refused and no underrun."""
        return not any(self.counters.get(name) for name in
                       ("vec_underruns", "vec_rejected", "errors"))


def check_segment(op, x, y):
    """Refuse a segment the board would: ``op`` a jump or a mark, ends within the field."""
    if op not in ("jump", "mark"):
        raise ValueError(f"a segment is a jump or a mark, not {op!r}")
    for value in (x, y):
        reg = BY_NAME["vec_x"]
        if isinstance(value, bool) or not isinstance(value, int) or \
                not reg.low <= value <= reg.high:
            raise ValueError(f"segment end {value!r} is outside {reg.low} … {reg.high}")


def segment_words(op, x, y, corner_frames=0):
    """The ``(vec_x, vec_y, vec_op)`` register values that queue one segment: what the
    streamer writes and a job image holds."""
    return x, y, pack(VecOpWord, op=VectorOp[op.upper()], corner_frames=corner_frames)


def job_segments(segments):
    """A vector job's segments as the board is sent them: ending on a jump (to where the last
    mark ends: no move), since the board counts a mark that finds the queue empty as an
    underrun, and a job's end is none."""
    segments = list(segments)
    if segments and segments[-1][0] == "mark":
        segments.append(("jump", *segments[-1][1:]))
    return segments


class JobStreamer:
    """Runs jobs on a board through a :class:`~galvoscan.client.HostClient`.

    Parameters
    ----------
    board : :class:`~galvoscan.client.HostClient`
    batch : int
        Most segments written between two reads of ``fifo_free`` (three frames each: the
        frames in flight). A read waits for the board's answer, and over USB an answer
        takes a round trip (1 ms with the FTDI driver's low-latency mode, 16 ms without), so
        a batch must be long enough to carry the link past it: 128 segments are 15 ms at
        1 Mbaud.
    poll_s : float
        Host seconds between status reads while waiting on the board.
    progress : callable, optional
        Called with the number of segments taken, as they are.
    """

    def __init__(self, board, *, batch=DEFAULT_BATCH, poll_s=0.02, progress=None):
        if not 1 <= batch <= QUEUE_DEPTH:
            raise ValueError(f"batch must be from 1 to {QUEUE_DEPTH}, not {batch!r}")
        self.board = board
        self.batch = batch
        self.poll_s = poll_s
        self.progress = progress
        self._pulses_seen = None
        self._capabilities = None
        self.pulses = 0
        #: Segments the board's queue holds, read by :meth:`check_ready` (None before).
        self.queue_depth = None

    # --- the board's state ---------------------------------------------------------------------

    def status(self):
        """The board's status flags; a fault, an open interlock or an alarm raises
        :class:`JobAborted`. Also keeps the pulse count."""
        flags = Status.from_bits(self.board.read("status"))
        self._count_pulses()
        if flags.fault_interlock or flags.interlock_open:
            raise JobAborted("the interlock opened: the laser is off (close it, then "
                             "`galvoscan send fault_clear=1`)")
        if flags.fault_alarm or flags.alarm:
            raise JobAborted("the laser reported an alarm: the laser is off (see the laser's "
                             "own display; then `galvoscan send fault_clear=1`)")
        if flags.fault_watchdog:
            raise JobAborted("the board's watchdog fired: the link went silent for longer "
                             "than `watchdog` ms")
        return flags

    def _count_pulses(self):
        now = self.board.read("pulses")
        if self._pulses_seen is not None:
            self.pulses += (now - self._pulses_seen) & _COUNTER_TOP
        self._pulses_seen = now

    def capabilities(self):
        """What the board's bitstream holds (its ``caps`` register, read once): asked, not
        tried, so that ``errors`` counts only the board's real refusals."""
        if self._capabilities is None:
            from ..client import ClientError
            try:
                self._capabilities = Capabilities.from_bits(self.board.read("caps"))
            except ClientError as error:
                raise JobAborted(f"the board does not say what its bitstream holds ({error}): "
                                 f"a bitstream built before galvoscan had the caps register; "
                                 f"build and flash it again") from None
        return self._capabilities

    def counters(self):
        return {name: self.board.read(name) for name in COUNTERS}

    def check_ready(self):
        """Refuse to start on a board that is not idle and safe: one line, nothing written."""
        flags = self.status()
        if flags.armed:
            raise JobAborted("the board is armed already: another job may be running "
                             "(`galvoscan send arm=0` stops it)")
        free = self.board.read("fifo_free")
        # Not busy: the queue is empty and nothing is in the sequencer's hand, so every place
        # is free and `free` is the queue's depth.
        if flags.vector_busy:
            raise JobAborted(f"the board's vector queue still holds segments of an earlier "
                             f"job ({free} places free): reset the board first")
        self.queue_depth = free

    # --- stopping ------------------------------------------------------------------------------

    def disarm(self):
        """``arm = 0`` then ``run = 0`` and the guide laser off; best effort (the link may be
        what failed)."""
        for name in ("arm", "run", "guide"):
            try:
                self.board.write(name, 0)
            except Exception:       # a lost link: the board's watchdog switches it off
                pass

    # --- running -------------------------------------------------------------------------------

    def setup(self, registers):
        """Write ``{name: value}`` (checked against the map before the first is sent); returns
        them."""
        from ..client import encode_write
        for name, value in registers.items():
            encode_write(name, value)
        caps = self.capabilities()
        if "mode" in registers:
            mode = Mode(registers["mode"])
            if not getattr(caps, mode.label):
                raise JobAborted(f"the board has no {mode.label} mode: its bitstream was "
                                 f"built without it (galvoscan build --modes)")
        if registers.get("wob_shape") and not caps.wobble:
            raise JobAborted("the board has no wobble stage: its bitstream was built "
                             "without it (galvoscan build --wobble)")
        for name, value in registers.items():
            if name == "wob_shape" and not caps.wobble:
                continue            # (off, on a board that has no wobble to turn off)
            self.board.write(name, value)
        return registers

    def wait_ready(self, timeout_s):
        """Wait until the laser has led with MO for the MO lead (status ``laser_ready``)."""
        deadline = time.monotonic() + timeout_s
        while not self.status().laser_ready:
            if time.monotonic() > deadline:
                raise JobAborted(f"the laser did not become ready within {timeout_s:g} s")
            time.sleep(self.poll_s)

    def wait_idle(self, timeout_s):
        """Wait until the vector queue is empty and the last point marked."""
        deadline = time.monotonic() + timeout_s
        while self.status().vector_busy:
            if time.monotonic() > deadline:
                raise JobAborted(f"the board was still marking after {timeout_s:g} s")
            time.sleep(self.poll_s)

    def stream(self, segments, *, start, timeout_s, corners=None):
        """Feed ``segments`` (``(op, x, y)``, galvo units) into the queue as it frees up.

        ``start()`` is called once, when the first batch is in (or the job is all in): it
        arms and starts the scan. ``corners``: each segment's corner hold in frames, sent in
        ``vec_op`` bits 7:1 (:func:`~.corners.corner_frames`; for ``polygon_scaled``).
        Returns the number of segments written."""
        segments = list(segments)
        for segment in segments:
            check_segment(*segment)
        corners = [0] * len(segments) if corners is None else list(corners)
        # Every place is free (checked by check_ready), else as many as the board says.
        free = self.queue_depth if self.queue_depth is not None else \
            self.board.read("fifo_free")
        sent = 0
        started = False
        deadline = time.monotonic() + timeout_s
        while sent < len(segments):
            if free == 0:
                self.status()
                free = self.board.read("fifo_free")
                if free == 0:
                    if time.monotonic() > deadline:
                        raise JobAborted(f"the queue did not move for {timeout_s:g} s")
                    time.sleep(self.poll_s)
                    continue
                deadline = time.monotonic() + timeout_s
            count = min(free, self.batch, len(segments) - sent)
            for (op, x, y), hold in zip(segments[sent:sent + count],
                                        corners[sent:sent + count]):
                for name, value in zip(("vec_x", "vec_y", "vec_op"),
                                       segment_words(op, x, y, hold)):
                    self.board.write(name, value)
            sent += count
            free -= count
            # A read: the board has taken all of the batch before it answers.
            free = min(free, self.board.read("fifo_free"))
            if self.progress is not None:
                self.progress(count)
            if not started and (sent == len(segments) or free < self.batch):
                start()
                started = True
        if not started:
            start()
        return sent

    def _start(self, *, armed, ready_timeout_s):
        """Arm (unless ``armed`` is false), wait out the MO lead, run."""
        if armed:
            self.board.write("arm", 1)
            self.wait_ready(ready_timeout_s)
        self.board.write("run", 1)

    def _job(self, body):
        """What every job does around its ``body()`` (which returns the segments it sent):
        refuse a board not ready, count, disarm however it ends, report the counters' rise."""
        started = time.monotonic()
        self.check_ready()
        before = self.counters()
        self._count_pulses()
        first = self.pulses
        try:
            sent = body()
        except BaseException:
            self.disarm()
            raise
        self.disarm()
        after = self.counters()
        self._count_pulses()
        return StreamReport(
            segments=sent, pulses=self.pulses - first, seconds=time.monotonic() - started,
            counters={name: (after[name] - before[name]) & _COUNTER_TOP for name in COUNTERS})

    def _without_missing_delays(self, registers):
        """``registers`` less the RTC delays if the board has none (the default bitstream:
        ``galvoscan build --delays`` builds them), with one line saying so."""
        from ..gateware.host.regmap import DELAY_REGISTERS
        delays = [name for name in registers if name in DELAY_REGISTERS]
        if delays and not self.capabilities().delays:
            print("galvoscan: note: the board has no laser or scanner delays (its bitstream "
                  "was built without --delays): marking without them", file=sys.stderr)
            return {name: value for name, value in registers.items()
                    if name not in DELAY_REGISTERS}
        return registers

    def run_vector(self, segments, registers, *, ready_timeout_s=5.0, timeout_s=60.0,
                   armed=True):
        """A whole vector job: checks, parameters, arm, stream, wait, disarm, report.

        ``registers`` are written after ``mode = vector`` and ``run = 0`` (pitch, pulses per
        point, jump delay, power, PRR …). With ``armed`` false the job runs with the laser
        off (framing with the guide laser)."""
        segments = job_segments(segments)
        registers = self._without_missing_delays(registers)

        def body():
            written = self.setup({"run": 0, "mode": Mode.VECTOR.value, **registers})
            corners = corner_frames(segments, written["polygon_delay"]) \
                if written.get("polygon_scaled") else None
            sent = self.stream(segments, timeout_s=timeout_s, corners=corners,
                               start=lambda: self._start(
                armed=armed, ready_timeout_s=ready_timeout_s))
            self.wait_idle(timeout_s)
            if registers.get("wob_shape"):
                # A later job that does not ask for wobble must not inherit it.
                self.board.write("wob_shape", 0)
            return sent
        return self._job(body)

    def run_area(self, registers, *, pulses, timeout_s, ready_timeout_s=5.0):
        """A spiral or raster job: set up, arm, run until the laser has fired ``pulses``
        pulses (the board's own clock: this works on a simulated board too), disarm."""
        def body():
            first = self.pulses
            self.setup(registers)
            self._start(armed=True, ready_timeout_s=ready_timeout_s)
            deadline = time.monotonic() + timeout_s
            while self.pulses - first < pulses:
                self.status()
                if self.progress is not None:
                    self.progress(min(self.pulses - first, pulses))
                if time.monotonic() > deadline:
                    raise JobAborted(f"the laser fired {self.pulses - first} of {pulses} "
                                     f"pulses in {timeout_s:g} s")
                time.sleep(self.poll_s)
            return 0
        return self._job(body)
