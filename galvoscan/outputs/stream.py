"""Running a job on a board: parameters set, the laser armed, vector segments streamed into the
512-segment queue as it empties, and the laser disarmed however the job ends.

The queue's depth is the board's: read off ``fifo_free`` while the queue is empty (a real
board's is 512; a simulated one may be built shorter).

A segment is one checked frame (its end point and its operation together), and the board
answers each with the free places left in its queue: the streamer sends at most a batch of
segments, reads their answers, and sends the next batch into the room the last answer gave.
Status is read between batches: a latched fault, an open interlock or an alarm stops the job
at once. The watchdog is fed by the segments themselves; while the streamer waits on an armed
board (the MO lead, a full queue, the last segments marking) it writes ``keepalive``.

Before it arms, the streamer reads back every setting the job wrote and refuses to arm on any
difference. Every ending says how far the job got: the board counts the segments its
sequencer took (``vec_taken``), and a fault stops the sequencer where it is.

A :class:`Pause` (set from another thread: a meerk40t device's pause button, GRBL's ``!``) holds
a vector job on the board between segments: the feed stops, the queue is marked out, the laser
is disarmed (``arm = 0``); resumed, it is armed again, the MO lead waited out, and the feed goes
on from the next segment. The pen stays down across the hold, so a line held mid-way goes on
from its last point without marking it again. The one underrun the board counts as its queue
runs dry at the hold is the pause's, not a fault: the report leaves it out.

Whatever stops a job early (Ctrl-C, a lost link, a board fault, an error in this code), the
first thing sent after it is ``arm = 0``, then ``run = 0`` (and a job on the fly's fly
off: RTC's ``fly_return``); the exception then goes on to the caller.

A job on the fly (its registers hold ``fly_ctrl``: :mod:`galvoscan.plan.fly`) is set up with
the fly off; as it starts, once armed and past the MO lead, the encoder's count is zeroed
(``fly_clear``: the part is where the drawing is) and the fly turned on, just before
``run = 1``; it is turned off as the job ends, however it ends. The points the fly carried
past the field's edge (held there, the laser off: ``fly_clipped``) are counted in the
report. A job whose parts come on a belt queues the fly's start (``FLY_START``, after its wait
for the part sensor) instead: the board clears the count and turns the fly on as the part
arrives, and the host only writes ``run = 1``.

A job with I/O steps (:class:`~galvoscan.geometry.segments.IOStep`: a wait for the part
sensor, an output for a PLC) needs a bitstream with I/O in the queue (``caps.io``); the
steps go into the queue between the segments, and the board does each when the segments
before it are marked. While a wait holds the queue the streamer keeps the watchdog fed; a
wait that runs out of time (the board's ``io`` register: ``timed_out``) stops the job as a
fault does, and however an I/O job ends its queue is flushed (``vec_flush``: a held wait
dropped). Nothing of a job is dropped silently: a refused segment (``vec_rejected``) or frame
(``errors``) is counted and reported, and :class:`StreamReport` says how many.
"""

import sys
import threading
import time
from dataclasses import dataclass, field

from ..gateware.points import FIELD_CENTRE
from ..gateware.host.regmap import (BY_NAME, Capabilities, DELAY_REGISTERS, FlyControl,
                                    HeadState, IOKind, IOState, Mode, Status,
                                    VECTOR_QUEUE_DEPTH, pack)
from ..geometry.corners import corner_frames
from ..geometry.segments import LINE, PIXELS, has_pixel_lines, io_steps
from ..link.client import ClientError, LinkLost, encode_write
from .board_state import read_head
from .queue_words import check_segment, job_segments, queue_word


__all__ = ["JobAborted", "JobRefused", "JobInterrupted", "StreamReport", "JobStreamer", "Pause",
           "QUEUE_DEPTH", "COUNTERS", "DEFAULT_BATCH"]


#: Segments the bitstream's vector queue holds (the streamer reads a board's own depth).
QUEUE_DEPTH = VECTOR_QUEUE_DEPTH
#: Segments the streamer writes between two reads of ``fifo_free`` (see :class:`JobStreamer`).
DEFAULT_BATCH = 128
#: The board's counters a job reports, read before and after.
COUNTERS = ("vec_underruns", "vec_stalls", "vec_rejected", "errors")
_COUNTER_TOP = 0xFFFF


class JobAborted(Exception):
    """The board stopped the job (a fault, the interlock, an alarm, the link); the laser is
    disarmed.

    Attributes
    ----------
    taken, total : int or None
        Segments the board's sequencer had taken when the job stopped, of the job's (None:
        not known, the link being lost).
    complete : bool
        Every segment was marked to its end before the job stopped: the part is done.
    """

    def __init__(self, message, *, taken=None, total=None, complete=False):
        super().__init__(message)
        self.taken = taken
        self.total = total
        self.complete = complete


class JobRefused(JobAborted):
    """The board cannot mark the job (its bitstream lacks what the job needs): refused before
    anything of the job was sent; the laser was never armed for it."""


class JobInterrupted(KeyboardInterrupt):
    """Ctrl-C stopped a job; the laser is disarmed. Says how far the job got, as
    :class:`JobAborted` does (``taken``, ``total``, ``complete``)."""

    def __init__(self, message, *, taken=None, total=None, complete=False):
        super().__init__(message)
        self.taken = taken
        self.total = total
        self.complete = complete


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
    resent : int
        Frames the host sent again because the board refused them as damaged or out of step,
        or their answers were lost: every one then landed (a job with a frame that did not
        land stops; it does not end with a report).
    holds : int
        Times a :class:`Pause` held the job. The underrun the board counts as its queue runs
        dry at a hold (one a hold at most: the feed had stopped on purpose) is not in
        ``counters``.
    clipped : int
        A job on the fly: points the belt carried past the field's edge, held there with the
        laser off (not marked).
    """
    segments: int = 0
    counters: dict = field(default_factory=dict)
    pulses: int = 0
    seconds: float = 0.0
    resent: int = 0
    holds: int = 0
    clipped: int = 0

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
                   pulses=sum(r.pulses for r in reports), seconds=sum(r.seconds for r in reports),
                   resent=sum(r.resent for r in reports), holds=sum(r.holds for r in reports),
                   clipped=sum(r.clipped for r in reports))

    @property
    def clean(self):
        """No segment refused for a full queue, no underrun, and (on the fly) no point held
        at the field's edge. (Frames the link damaged are counted in ``errors``, and were
        sent again: every write of a job that ends with a report landed, acknowledged.)"""
        return not self.clipped and \
            not any(self.counters.get(name) for name in ("vec_underruns", "vec_rejected"))


class Pause:
    """A pause for a running vector job, set and cleared from any thread; the
    :class:`JobStreamer` given it looks at it between batches of segments.

    Paused, the streamer sends nothing more (a pixel line's pixel words still follow their
    line), lets the board mark what its queue holds, and disarms (``arm = 0``: every laser
    output off); it then waits, reading the board's status (a fault or the interlock still
    ends the job), until resumed: it arms again, waits out the MO lead and feeds the next
    segment. Nothing is sent twice and nothing is left out; the pen stays down, so a line
    held mid-way goes on from its last point without marking it again. A pause before the
    laser was armed (the queue still filling) only stops the feed.

    Attributes
    ----------
    holding : :class:`threading.Event`
        Set while the board holds the job: its queue empty and the laser disarmed.
    holds : int
        How many times a job was held.
    """

    def __init__(self):
        self._wanted = threading.Event()
        self.holding = threading.Event()
        self.holds = 0

    def pause(self):
        """Hold the job (from any thread)."""
        self._wanted.set()

    def resume(self):
        """Let the job go on (from any thread)."""
        self._wanted.clear()

    @property
    def paused(self):
        """A pause is asked for (the board may still be marking its queue: see
        :attr:`holding`)."""
        return self._wanted.is_set()


def _hold_point(segments, sent):
    """Where the feed of ``segments`` stops for a pause, ``sent`` of them sent: there, unless
    that would part a pixel line from its pixel words (the line sweeps at one speed: it must
    not wait for them), then after them."""
    index = sent
    while index < len(segments) and (segments[index][0] == PIXELS or
                                     (index > 0 and segments[index - 1][0] == LINE)):
        index += 1
    return index


class JobStreamer:
    """Runs jobs on a board through a :class:`~galvoscan.link.client.HostClient`.

    Parameters
    ----------
    board : :class:`~galvoscan.link.client.HostClient`
    batch : int
        Most segments written between two reads of ``fifo_free`` (a frame each: the
        frames in flight). A read waits for the board's answer, and over USB an answer
        takes a round trip (1 ms with the FTDI driver's low-latency mode, 16 ms without), so
        a batch must be long enough to carry the link past it: 128 segments are 15 ms at
        1 Mbaud.
    poll_s : float
        Host seconds between status reads while waiting on the board.
    progress : callable, optional
        Called with the number of segments taken, as they are.
    pause : :class:`Pause`, optional
        Holds a vector job on the board while it is paused.
    """

    def __init__(self, board, *, batch=DEFAULT_BATCH, poll_s=0.02, progress=None,
                 pause=None):
        if not 1 <= batch <= QUEUE_DEPTH:
            raise ValueError(f"batch must be from 1 to {QUEUE_DEPTH}, not {batch!r}")
        self.board = board
        # Every wait counts the link's clock: a simulated board's own time (its transport
        # gives it), else the host's. A board without a clock of its own (a model) has the
        # host's.
        self._now = getattr(board, "now", time.monotonic)
        self._sleep = getattr(board, "sleep", time.sleep)
        self.batch = batch
        self.poll_s = poll_s
        self.progress = progress
        self.pause = pause
        self._armed = False
        self._ready_timeout_s = 5.0
        self._holds = self._held_underruns = 0
        self._pulses_seen = None
        self._capabilities = None
        self._fly = None            # a job on the fly's fly_ctrl (the fly on), while it runs
        self._fly_clear = True
        self._fly_queued = False    # the job's queue starts the fly (FLY_START), not the host
        self._io = False            # the job has I/O steps (its queue is flushed as it ends)
        self._waits = []            # its waits for an input (time-outs read in status())
        self._clipped = 0
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
            raise JobAborted("the board's watchdog fired: no segment or keepalive came for "
                             "longer than `watchdog` ms")
        if flags.fault_link:
            raise JobAborted("the board refused a frame while armed (damaged or lost on the "
                             "line): it switched the laser off at once")
        if self._waits and IOState.from_bits(self.board.read("io")).timed_out:
            step = self._waits[0]
            limit = f"{step[1] / 1000:g} s" if step[1] >= 1000 else f"{step[1]} ms"
            raise JobAborted(f"no part came: input {step.index} was not "
                             f"{'high' if step.level else 'low'} within {limit} (the wait's "
                             f"time-out), so the board stopped the job; the laser is off")
        caps = self.capabilities()
        if caps.head and caps.laser and \
                HeadState.from_bits(self.board.read("head_state")).fault:
            head = read_head(self.board, caps)
            raise JobAborted(f"the scan head reported a fault "
                             f"({head.problem() or 'well again now'}): the laser is off "
                             f"(`galvoscan status` says the head's bits; `galvoscan send "
                             f"fault_clear=1` once it is well)")
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
            try:
                self._capabilities = Capabilities.from_bits(self.board.read("caps"))
            except LinkLost:
                # A silent or damaged link, not an old bitstream: raised as it is, so that a
                # job says how far it got (a read of caps lost to a line held for 30 ms was
                # said to be a bitstream to build again).
                raise
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
        head = read_head(self.board, self.capabilities())
        if head is not None and not head.missing and head.problem():
            # (A missing head matters only to a job that makes the laser obey it: verify.)
            raise JobAborted(f"the scan head reports {head.problem()}: not starting "
                             f"(`galvoscan status` says its bits)")
        free = self.board.read("fifo_free")
        # Not busy: the queue is empty and nothing is in the sequencer's hand, so every place
        # is free and `free` is the queue's depth.
        if flags.vector_busy:
            raise JobAborted(f"the board's vector queue still holds segments of an earlier "
                             f"job ({free} places free): reset the board first")
        self.queue_depth = free

    # --- stopping ------------------------------------------------------------------------------

    def disarm(self):
        """``arm = 0`` then ``run = 0``, the guide laser off and a job on the fly's fly off
        (``fly_ctrl``'s on bit 0: the count still follows the encoder it was set to, so a
        later layer of the part goes on from it); best effort (the link may be what
        failed)."""
        writes = [("arm", 0), ("run", 0), ("guide", 0)]
        if self._io:
            # A wait that holds the queue (for a part that did not come) is dropped, and the
            # fly the queue started with it.
            writes.append(("vec_flush", 1))
        if self._fly is not None:
            writes.append(("fly_ctrl", self._fly & ~pack(FlyControl, on=1)))
        for name, value in writes:
            try:
                self.board.write(name, value)
            except LinkLost:        # a lost link: the board's watchdog switches it off
                return
            except Exception:
                pass

    # --- running -------------------------------------------------------------------------------

    def setup(self, registers):
        """Write ``{name: value}`` (checked against the map before the first is sent); returns
        them."""
        for name, value in registers.items():
            encode_write(name, value)
        caps = self.capabilities()
        if "mode" in registers:
            mode = Mode(registers["mode"])
            if not getattr(caps, mode.label):
                raise JobAborted(f"the board has no {mode.label} mode: its bitstream was "
                                 f"built without it (galvoscan build --modes)")
        if registers.get("head_check") and not caps.head:
            raise JobAborted("head_check asks the laser to obey the scan head, but the board's "
                             "bitstream does not read the head's STATUS line (galvoscan build "
                             "--head-status)")
        if registers.get("wob_shape") and not caps.wobble:
            raise JobAborted("the board has no wobble stage: its bitstream was built "
                             "without it (galvoscan build --wobble)")
        self.board.write_many([(name, value) for name, value in registers.items()
                               if not self._not_built(name, caps)])
        # (wob_shape off, on a board that has no wobble to turn off, is not written; nor
        # head_check off on a board that cannot read the head.)
        return registers

    def verify(self, registers):
        """Read back every setting of ``registers``: a difference refuses to arm."""
        caps = self.capabilities()
        for name, value in registers.items():
            if BY_NAME[name].access != "rw" or self._not_built(name, caps):
                continue
            got = self.board.read(name)
            if got != value:
                raise JobAborted(f"the board holds {name} = {got} where the job wrote {value}: "
                                 f"not arming")
        if registers.get("head_check"):
            head = read_head(self.board, caps)
            if head.problem():
                raise JobAborted(f"the scan head has {head.problem()}, and head_check makes "
                                 f"the laser obey it: not arming (`galvoscan status` says its "
                                 f"bits)" if head.missing else
                                 f"the scan head reports {head.problem()}: not arming")

    @staticmethod
    def _not_built(name, caps):
        """A setting off that the board's bitstream has no register for."""
        return (name == "wob_shape" and not caps.wobble) or \
            (name == "head_check" and not caps.head)

    def wait_ready(self, timeout_s):
        """Wait until the laser has led with MO for the MO lead (status ``laser_ready``)."""
        deadline = self._now() + timeout_s
        while not self.status().laser_ready:
            if self._now() > deadline:
                raise JobAborted(f"the laser did not become ready within {timeout_s:g} s")
            self.keepalive()
            self._sleep(self.poll_s)

    def wait_idle(self, timeout_s):
        """Wait until the vector queue is empty and the last point marked."""
        deadline = self._now() + timeout_s
        while self.status().vector_busy:
            if self._now() > deadline:
                raise JobAborted(f"the board was still marking after {timeout_s:g} s")
            self.keepalive()
            self._sleep(self.poll_s)

    def keepalive(self):
        """Feed the armed board's watchdog (status reads do not)."""
        self.board.write("keepalive", 1)

    def stream(self, segments, *, start, timeout_s, corners=None):
        """Feed ``segments`` (``(op, x, y)``, galvo units) into the queue as it frees up.

        ``start()`` is called once, when the first batch is in (or the job is all in): it
        arms and starts the scan. ``corners``: each segment's corner hold in frames, sent in
        ``vec_op`` bits 7:1 (:func:`~galvoscan.geometry.corners.corner_frames`; for
        ``polygon_scaled``).
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
        hold_at = None          # where a pause stops the feed
        deadline = self._now() + timeout_s
        while sent < len(segments):
            if self.pause is not None and self.pause.paused:
                if hold_at is None:
                    hold_at = _hold_point(segments, sent)
                if sent == hold_at:
                    self._hold(started, timeout_s)
                    hold_at = None
                    free = self.board.read("fifo_free")
                    deadline = self._now() + timeout_s
                    continue
            else:
                hold_at = None
            end = len(segments) if hold_at is None else hold_at
            if free == 0:
                self.status()
                if started:
                    self.keepalive()
                free = self.board.read("fifo_free")
                if free == 0:
                    if self._now() > deadline:
                        raise JobAborted(f"the queue did not move for {timeout_s:g} s")
                    self._sleep(self.poll_s)
                    continue
                deadline = self._now() + timeout_s
            count = min(free, self.batch, end - sent)
            words = [queue_word(segment, hold)
                     for segment, hold in zip(segments[sent:sent + count],
                                              corners[sent:sent + count])]
            # Each answered with the free places after it: the last one's is the room now.
            free = self.board.queue_segments([(op_word, x, y) for x, y, op_word in words])
            sent += count
            self.sent = sent
            if self.progress is not None:
                self.progress(count)
            if not started and (sent == len(segments) or free < self.batch):
                start()
                started = True
        if not started:
            start()
        return sent

    def _hold(self, started, timeout_s):
        """A pause, the feed stopped: the queue marked out and the laser disarmed
        (``started``: the job runs), then, once resumed, armed again past the MO lead. The
        underrun of the queue running dry is counted as the hold's."""
        pause = self.pause
        rearm = started and self._armed
        if started:
            # No segment comes now: the queue runs dry once, at its end, and no sooner.
            before = self.board.read("vec_underruns")
            self.wait_idle(timeout_s)
            self._held_underruns += (self.board.read("vec_underruns") - before) & _COUNTER_TOP
        if rearm:
            self.board.write("arm", 0)
        pause.holds += 1
        self._holds += 1
        pause.holding.set()
        try:
            while pause.paused:
                self.status()
                self._sleep(self.poll_s)
        finally:
            pause.holding.clear()
        if rearm:
            self.board.write("arm", 1)
            self.wait_ready(self._ready_timeout_s)

    def _start(self, *, armed, ready_timeout_s):
        """Arm (unless ``armed`` is false), wait out the MO lead, run."""
        self._armed = armed
        self._ready_timeout_s = ready_timeout_s
        if armed:
            self.board.write("arm", 1)
            self.wait_ready(ready_timeout_s)
        if self._fly is not None and not self._fly_queued:
            # The part is where the drawing is now: the count from here (unless a layer
            # before this one started it), the fly on, then the run.
            self.board.write_many([*([("fly_clear", 1)] if self._fly_clear else []),
                                   ("fly_ctrl", self._fly), ("run", 1)])
            return
        self.board.write("run", 1)

    def _taken(self):
        """``vec_taken`` now, or None (no vector mode, or no answer)."""
        if not self.capabilities().vector:
            return None
        try:
            return self.board.read("vec_taken")
        except ClientError:
            return None

    def _job(self, body, total=None):
        """What every job does around its ``body()`` (which returns the segments it sent):
        refuse a board not ready, count, disarm however it ends (saying how far it got),
        report the counters' rise. ``total``: the job's segments."""
        started = time.monotonic()      # the report's seconds: the host's
        self.check_ready()
        before = self.counters()
        self._count_pulses()
        first = self.pulses
        taken_before = self._taken() if total is not None else None
        self.sent = 0
        self._holds = self._held_underruns = 0
        self._clipped = 0
        retries = getattr(self.board, "retries", 0)
        try:
            sent = body()
        except BaseException as error:
            self.disarm()
            if total is None or not isinstance(error, (JobAborted, ClientError,
                                                       KeyboardInterrupt)):
                raise
            ending = self._ending(error, taken_before, total)
            if isinstance(error, KeyboardInterrupt):
                raise JobInterrupted(str(ending), taken=ending.taken, total=total,
                                     complete=ending.complete) from error
            raise ending from error
        self.disarm()
        try:
            after = self.counters()
            self._count_pulses()
        except ClientError as error:
            if total is None:
                raise
            # Marked to its end (the queue ran empty), then the link failed.
            raise JobAborted(f"every segment ({total}) was marked: the part is done, but the "
                             f"link failed before its counters were read ({error})",
                             taken=total, total=total, complete=True) from error
        counters = {name: (after[name] - before[name]) & _COUNTER_TOP for name in COUNTERS}
        counters["vec_underruns"] -= min(self._held_underruns, counters["vec_underruns"])
        return StreamReport(
            segments=sent, pulses=self.pulses - first, seconds=time.monotonic() - started,
            counters=counters, resent=getattr(self.board, "retries", 0) - retries,
            holds=self._holds, clipped=self._clipped)

    def _ending(self, error, taken_before, total):
        """``error`` as a :class:`JobAborted` that says how far the job got."""
        watchdog = getattr(self, "_watchdog_ms", None)
        if isinstance(error, LinkLost):
            bound = f"within {watchdog} ms of the last segment it took" if watchdog else \
                "when its watchdog runs out"
            return JobAborted(f"the link to the board is lost ({error}); the board had "
                              f"acknowledged {self.sent} of {total} segments, and it stops the "
                              f"laser {bound}", total=total)
        said = "the laser is disarmed" if isinstance(error, KeyboardInterrupt) else str(error)
        now = self._taken()
        if now is None or taken_before is None:
            return JobAborted(f"{said} (how far the job got is not known: the board does not "
                              f"answer)", total=total)
        taken = (now - taken_before) & _COUNTER_TOP
        busy = None
        try:
            busy = Status.from_bits(self.board.read("status")).vector_busy
        except Exception:
            pass
        complete = taken >= total and busy is False
        where = (f"every segment ({total}) was marked: the part is done" if complete else
                 f"stopped at segment {min(taken, total)} of {total}: the part is not done")
        return JobAborted(f"{said}; {where}", taken=taken, total=total, complete=complete)

    def _without_missing_delays(self, registers):
        """``registers`` less the RTC delays if the board has none (the default bitstream:
        ``galvoscan build --delays`` builds them), with one line saying so."""
        delays = [name for name in registers if name in DELAY_REGISTERS]
        if delays and not self.capabilities().delays:
            print("galvoscan: note: the board has no laser or scanner delays (its bitstream "
                  "was built without --delays): marking without them", file=sys.stderr)
            return {name: value for name, value in registers.items()
                    if name not in DELAY_REGISTERS}
        return registers

    def run_vector(self, segments, registers, *, ready_timeout_s=5.0, timeout_s=60.0,
                   armed=True, clear_count=True):
        """A whole vector job: checks, parameters, arm, stream, wait, disarm, report.

        ``registers`` are written after ``mode = vector`` and ``run = 0`` (pitch, pulses per
        point, jump delay, power, PRR …). With ``armed`` false the job runs with the laser
        off (framing with the guide laser). A job on the fly (``registers`` hold ``fly_ctrl``,
        with the fly off) turns it on as it starts, the count zeroed first unless
        ``clear_count`` is false (a later layer of the same part: the belt has carried it on
        since the first)."""
        segments = job_segments(segments)
        if has_pixel_lines(segments) and not self.capabilities().pixel_lines:
            if not any(op == PIXELS for op, *_ in segments):
                # Pixel lines without pixel words: SkyWriting's run-ins and run-outs.
                raise JobRefused("the board's bitstream has no pixel lines, which "
                                 "SkyWriting's run-ins and run-outs are (build --preset "
                                 "engraver has them, and the ULX3S's): mark without "
                                 "SkyWriting (--sky 0); nothing was sent")
            raise JobRefused("the board's bitstream has no pixel lines (build --preset "
                             "engraver has them, and the ULX3S's): mark the photo as runs "
                             "with --image-lines runs; nothing was sent")
        fly = "fly_ctrl" in registers
        if fly and not self.capabilities().fly:
            raise JobRefused("the board's bitstream has no marking on the fly (the ULX3S's "
                             "has it): mark the job standing still, without --fly; nothing "
                             "was sent")
        steps = io_steps(segments)
        if steps and not self.capabilities().io:
            raise JobRefused("the board's bitstream has no I/O in the queue (the ULX3S's has "
                             "it): mark the job without --wait-input and --set-output; nothing "
                             "was sent")
        if any(step.kind not in (IOKind.WAIT_INPUT, IOKind.SET_OUTPUT) for step in steps) and \
                not self.capabilities().fly:
            raise JobRefused("the job waits for an encoder's count or starts the fly in its "
                             "queue, and the board's bitstream has no marking on the fly (the "
                             "ULX3S's has it); nothing was sent")
        if "z" in registers and not self.capabilities().z:
            raise JobRefused("the board's bitstream has no Z channel (the ULX3S's has it): "
                             "mark the job without --z or a layer's z; nothing was sent")
        # (Said once every refusal above is past: a job refused says only why.)
        registers = self._without_missing_delays(registers)
        if "z" not in registers and self.capabilities().z:
            # A job that gives no Z is marked at the focus shifter's middle, never at what the
            # job before it left there.
            registers = {**registers, "z": FIELD_CENTRE}

        def body():
            written = self.setup({"run": 0, "mode": Mode.VECTOR.value, **registers})
            self.verify(written)
            self._io = bool(steps)
            self._waits = [step for step in steps if step.kind == IOKind.WAIT_INPUT]
            if fly:
                self._fly = written["fly_ctrl"] | pack(FlyControl, on=1)
                self._fly_clear = clear_count
                self._fly_queued = any(step.kind == IOKind.FLY_START for step in steps)
                clipped = self.board.read("fly_clipped")
            self._watchdog_ms = self.board.read("watchdog")
            corners = corner_frames(segments, written["polygon_delay"]) \
                if written.get("polygon_scaled") else None
            sent = self.stream(segments, timeout_s=timeout_s, corners=corners,
                               start=lambda: self._start(
                armed=armed, ready_timeout_s=ready_timeout_s))
            self.wait_idle(timeout_s)
            if registers.get("wob_shape"):
                # A later job that does not ask for wobble must not inherit it.
                self.board.write("wob_shape", 0)
            if fly:
                self._clipped = (self.board.read("fly_clipped") - clipped) & _COUNTER_TOP
            return sent
        try:
            return self._job(body, total=len(segments))
        finally:
            self._fly = None
            self._fly_queued = self._io = False
            self._waits = []

    def run_area(self, registers, *, pulses, timeout_s, ready_timeout_s=5.0):
        """A spiral or raster job: set up, arm, run until the laser has fired ``pulses``
        pulses (the board's own clock: this works on a simulated board too), disarm."""
        def body():
            first = self.pulses
            self.verify(self.setup(registers))
            self._start(armed=True, ready_timeout_s=ready_timeout_s)
            deadline = self._now() + timeout_s
            while self.pulses - first < pulses:
                self.status()
                if self.progress is not None:
                    self.progress(min(self.pulses - first, pulses))
                if self._now() > deadline:
                    raise JobAborted(f"the laser fired {self.pulses - first} of {pulses} "
                                     f"pulses in {timeout_s:g} s")
                self.keepalive()
                self._sleep(self.poll_s)
            return 0
        return self._job(body)
