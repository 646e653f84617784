"""The galvoscan device's driver: what meerk40t's spooler calls (``LaserJob.execute_item`` calls
it by name). Cuts are gathered by :meth:`GalvoscanDriver.plot`; :meth:`~GalvoscanDriver.plot_start`
turns them into galvoscan's job (:mod:`.cutcode`), plans and checks it with galvoscan's planner
(:func:`galvoscan.api.plan_made`) before a byte is sent, and runs it on the board
(:func:`galvoscan.api.run`). A refusal, or a job the board stopped, is one line in meerk40t's
console. A WaitCut (meerk40t's wait operation) splits the job into parts, all planned and
checked first; between them the board is held for the wait (:meth:`GalvoscanDriver._hold`: the
time let pass on the link's clock, the laser disarmed), as the driver's own ``wait`` holds it;
its ``dwell`` fires the laser where the head is. Input and output cuts (meerk40t's I/O
operations) split it too: their steps are done by the board's queue between the parts
(:func:`galvoscan.api.run_io`, the laser never armed), on a bitstream with I/O in the queue
(refused, nothing sent, on one without). A G-code file opened in meerk40t comes as a
blob (:meth:`GalvoscanDriver.blob`), read by galvoscan's G-code reader.

Stop (the device's ``estop``) acts at the next exchange on the link: the streamer's first write
after it is ``arm = 0`` (:meth:`galvoscan.outputs.stream.JobStreamer.disarm`). Pause holds the
job on the board (:class:`galvoscan.api.Pause`: the feed stopped, the queue marked out,
``arm = 0``) and the spooler's next job; resume arms again and goes on. GRBL's
``!`` and ``~`` (meerk40t's ``grblcontrol``) call the same, and its ``?`` says ``Hold``
meanwhile.

meerk40t's trace (its Outline button: ``element* trace hull``) moves the head round the
elements' outline between the device's ``pre_outline`` and ``post_outline``: the driver gathers
those moves and walks the outline with the guide laser, the laser never armed, as ``mark
--frame`` does, after galvoscan's planner has checked it lies in the field.

The board's state goes to meerk40t's status bar (:mod:`.status`), in the words of
:class:`galvoscan.outputs.board_state.BoardState`: from the job's own status reads (``paused``
while the board holds it), after each job (read before the job's outcome is said), and polled
while the link is free.
"""

import contextlib
import tempfile
import threading
from pathlib import Path

import numpy as np
from meerk40t.core.cutcode.dwellcut import DwellCut
from meerk40t.core.cutcode.waitcut import WaitCut

from .. import api
from ..build import simulated_bitstream
from ..cli.jobargs import frame_job
from ..cli.job_reports import describe_job
from ..cli.layers import describe_layers
from ..gateware.host.regmap import Status
from ..link.client import ClientError, HostClient, SerialTransport
from ..outputs.board_state import read_board_state
from ..outputs.stream import (JobAborted, JobInterrupted, JobRefused, JobStreamer,
                              StreamReport)
from ..geometry.field import from_galvo
from ..geometry.segments import PIXELS
from ..plan.vector_job import hull_outline
from ..sim.board import SimTransport
from .cutcode import job_from_cuts, job_parts, outline_cuts
from .status import BoardStatus


__all__ = ["GalvoscanDriver", "StopRequested", "SIM"]

#: The link setting that runs jobs on a simulated board in meerk40t's own process.
SIM = "sim"
#: A hold (a wait) is let pass in slices of this (s), a stop heard between them.
HOLD_SLICE_S = 0.05
#: The blobs of meerk40t's G-code loader (its ``data_type``) the device marks.
GCODE_BLOBS = ("grbl", "gcode")


class StopRequested(KeyboardInterrupt):
    """meerk40t's stop, raised into the streamer at its next link exchange (as Ctrl-C is:
    the streamer disarms, then says how far the job got)."""


class _StoppableClient:
    """A :class:`~galvoscan.link.client.HostClient` whose next exchange after :meth:`stop`
    raises :class:`StopRequested`, once; the disarming writes (``arm``, ``run`` or ``guide``
    to 0) always go through. Each ``status`` it reads is handed to ``seen`` (its flags)."""

    _DISARM = ("arm", "run", "guide")

    def __init__(self, client, seen):
        self._client = client
        self._seen = seen
        self.stopping = threading.Event()

    def __getattr__(self, name):
        return getattr(self._client, name)

    def _check(self):
        if self.stopping.is_set():
            self.stopping.clear()
            raise StopRequested("stopped from meerk40t")

    def read(self, name):
        self._check()
        value = self._client.read(name)
        if name == "status":
            self._seen(Status.from_bits(value))
        return value

    def write(self, name, value):
        if not (name in self._DISARM and value == 0):
            self._check()
        return self._client.write(name, value)

    def queue_segments(self, segments):
        self._check()
        return self._client.queue_segments(segments)

    def sleep(self, seconds):
        self._check()
        return self._client.sleep(seconds)


class GalvoscanDriver:
    """meerk40t's driver for a galvoscan board. ``make_board``: the simulated board the
    ``sim`` link runs (made at the first job, kept for the device's life)."""

    def __init__(self, service):
        self.service = service
        self.name = str(service)
        self.native_x = self.native_y = 0x8000
        self.paused = False
        #: Holds the job on the board while paused (:class:`galvoscan.api.Pause`).
        self.hold = api.Pause()
        #: The operation being marked: its speed (mm/s) and power (‰), meerk40t's units (GRBL's
        #: ``?`` reports them).
        self.speed = self.power = 0
        self.queue = []
        self._outline = None
        self.board = None
        self.make_board = self._default_board
        self.last_report = None
        self.last_error = None
        self.last_plan = None
        self._client = None
        self._lock = threading.Lock()
        self.state = "idle"
        #: The board's state in meerk40t's status bar.
        self.status_bar = BoardStatus(service, self.read_status)

    def __repr__(self):
        return f"GalvoscanDriver({self.name})"

    # --- the link ------------------------------------------------------------------------------

    def _default_board(self):
        """The simulated board of the default bitstream at the profile's baud, as ``mark
        --sim`` runs it (compiled where it can be)."""
        config, contents = simulated_bitstream("icebreaker", baud=self.service.profile.link.baud)
        return api.SimulatedBoard(config=config, backend="auto", **contents)

    def _open(self):
        """A :class:`~galvoscan.link.client.HostClient` to the device's board, and what
        closes it."""
        link = self.service.link
        if link == SIM:
            if self.board is None:
                self.status_bar.show("starting the simulated board")
                self.board = self.make_board()
            return HostClient(SimTransport(self.board)), lambda: None
        profile = self.service.profile
        transport = SerialTransport(link, baud=profile.link.baud, timeout=profile.link.timeout_s)
        transport.__enter__()
        return HostClient(transport), lambda: transport.__exit__(None, None, None)

    # --- what the spooler calls ----------------------------------------------------------------

    def hold_work(self, priority):
        return priority <= 0 and self.paused

    def job_start(self, job):
        pass

    def job_finish(self, job):
        pass

    def get(self, key, default=None):
        return default

    def set(self, key, value):
        pass

    def status(self):
        """Where the head is, and ``hold`` (paused), ``busy`` or ``idle``."""
        return (self.native_x, self.native_y), "hold" if self.paused else self.state, \
            "galvoscan"

    def laser_off(self, *values):
        pass

    def laser_on(self, *values):
        pass

    def geometry(self, geom):
        self._say("galvoscan: error: meerk40t's geometry jobs are not marked by the galvoscan "
                  "device (its cutcode is): nothing sent")

    def plot(self, plot):
        self.queue.append(plot)

    def blob(self, data_type, data):
        """meerk40t's G-code loader's blob (a .gcode, .nc or .gc file opened in meerk40t):
        read by galvoscan's G-code reader, as ``galvoscan mark FILE.gcode`` reads it (each S and
        F a layer of its own), placed as meerk40t places a G-code file on its GRBL device: the
        file's 0,0 at the lens field's lower left corner, Y up; planned and checked before a
        byte is sent. Another kind of blob is one line, nothing sent."""
        self.last_report = self.last_error = None
        if data_type not in GCODE_BLOBS:
            self._refuse(f"meerk40t's {data_type!r} data is not marked by the galvoscan device "
                         f"(G-code is): nothing sent")
            return
        profile = self.service.profile
        half = profile.field.size_mm / 2
        with tempfile.TemporaryDirectory() as folder:
            path = Path(folder) / "meerk40t.gcode"
            path.write_bytes(data.encode("latin-1") if isinstance(data, str) else bytes(data))
            try:
                plan = api.plan(api.Job(drawings=(api.Drawing(str(path), origin="page",
                                                              offset_mm=(-half, -half)),),
                                        tolerance_mm=self.service.tolerance_mm), profile)
            except ValueError as error:
                self._refuse(f"G-code refused, nothing sent: "
                             f"{str(error).replace(str(path), 'the G-code')}")
                return
        self.last_plan = plan
        for line in describe_job(plan.vector_job, profile, ""):
            self._say(f"galvoscan: {line}")
        for line in describe_layers(plan.vector_job, profile):
            self._say(f"galvoscan: {line}")
        self._run([("plan", plan)])

    def plot_start(self):
        """Plan and check the gathered cuts, then run them on the board; nothing is sent if
        any part of them is refused. A WaitCut splits them: the parts before and after it are
        marked with the board held for its time between them (:meth:`_hold`)."""
        cuts, self.queue = self.queue, []
        if not cuts:            # (meerk40t's G-code reader ends every M5 so, moves or not)
            return
        first = next((cut.settings for cut in cuts if cut.settings), None) or {}
        self.speed, self.power = first.get("speed", 0), first.get("power", 0)
        self.last_report = self.last_error = None
        profile = self.service.profile
        steps = []
        try:
            for kind, part in job_parts(cuts):
                if kind in ("hold", "io"):
                    steps.append((kind, part))
                    continue
                job, objects = job_from_cuts(part, profile,
                                             tolerance_mm=self.service.tolerance_mm)
                steps.append(("plan", api.plan_made(objects, job, profile)))
        except ValueError as error:
            self._refuse(f"job refused, nothing sent: {error}")
            return
        plans = [plan for kind, plan in steps if kind == "plan"]
        if plans:
            self.last_plan = plans[-1]
        for plan in plans:
            vector_job = plan.vector_job
            for line in describe_job(vector_job, profile, ""):
                self._say(f"galvoscan: {line}")
            for line in describe_layers(vector_job, profile):
                self._say(f"galvoscan: {line}")
        self._run(steps)

    @contextlib.contextmanager
    def _on_the_board(self, *, marking, doing="framing"):
        """The board's client, opened for one job under the lock (the job talks through
        ``self._client``, which meerk40t's stop can interrupt, and whose status reads go to the
        status bar), the device busy (``marking``: its laser status active; else ``doing``, in
        the status bar) until the job ends,
        however it ends, the board's state read for the status bar, and the link closed; None
        (one line said, nothing sent) when it cannot be opened. The job's outcome is said after
        this (its ``last_report`` or ``last_error`` set once the link is free)."""
        with self._lock:
            self.state = "busy"
            if marking:
                self.service.laser_status = "active"
            self.status_bar.show("busy, marking a job" if marking else f"busy, {doing}")
            try:
                client, close = self._open()
            except (ClientError, OSError, ValueError) as error:
                client = close = None
                self.status_bar.failed(error)
                self._refuse(f"the board cannot be opened, nothing sent: {error}")
            else:
                self._client = _StoppableClient(client, self._seen_by_the_job)
            try:
                yield client
            finally:
                self._client = None
                self.state = "idle"
                if marking:
                    self.service.laser_status = "idle"
                if close is not None:
                    try:
                        self.status_bar.seen(read_board_state(client))
                    except (ClientError, OSError, ValueError) as error:
                        self.status_bar.failed(error)
                    close()

    def _seen_by_the_job(self, flags):
        """A ``status`` read of the running job's: busy in the status bar, or paused while the
        board holds the job."""
        self.status_bar.seen_flags(
            flags, activity="paused" if self.hold.holding.is_set() else "busy")

    def _run(self, steps):
        """Run ``steps`` (``("plan", plan)`` and ``("hold", seconds)``, in order) on the board
        in one session of the link, and say how it went."""
        with self._on_the_board(marking=True) as client:
            if client is None:
                return
            report, failure = self._marked(steps, client)
        if failure is not None:
            self._refuse(failure)
            return
        self.last_report = report
        self._head_at_the_end(steps)
        counters = report.counters
        holds = report.stream.holds
        waits = sum(seconds for kind, seconds in steps if kind == "hold")
        self._say(f"galvoscan: marked {report.segments} segments, {report.pulses} pulses"
                  f"{'' if report.clean else ' (NOT as planned)'}; underruns "
                  f"{counters['vec_underruns']}, stalls {counters['vec_stalls']}, rejected "
                  f"{counters['vec_rejected']}, errors {counters['errors']}"
                  f"{f'; held {holds} time(s)' if holds else ''}"
                  f"{f'; waited {waits * 1e3:g} ms' if waits else ''}")

    def _head_at_the_end(self, steps):
        """The head where the last plan of ``steps`` left it (its last segment's end, galvo
        units): what meerk40t's position and GRBL's ``?`` report."""
        plans = [step for kind, step in steps if kind == "plan"]
        if not plans:
            return
        vector_job = plans[-1].vector_job
        jobs = [lj.job for lj in vector_job.layers] if vector_job.layers else [vector_job]
        # (A pixel word's x and y are pixels, not a place.)
        ends = [segment for segment in jobs[-1].segments if segment[0] != PIXELS]
        if ends:
            _, x, y, *_ = ends[-1]
            self.native_x, self.native_y = int(x), int(y)

    def _marked(self, steps, client):
        """``(report, None)``: ``steps`` run on the board (the plans' reports as one);
        ``(None, why)``: it stopped."""
        try:
            reports = []
            if any(kind == "io" for kind, _ in steps) and \
                    not JobStreamer(self._client).capabilities().io:
                raise JobRefused("the board's bitstream has no I/O in the queue, which "
                                 "meerk40t's input and output operations need (the ULX3S's "
                                 "has it); nothing was sent")
            for kind, step in steps:
                if kind == "hold":
                    self._hold(step)
                elif kind == "io":
                    reports.append(api.run_io(step, self._client, pause=self.hold))
                else:
                    reports.append(api.run(step, self._client, say=self._say,
                                           pause=self.hold))
                    if not reports[-1].clean:
                        break
            return api.Report(StreamReport.total(r.stream for r in reports)), None
        except JobInterrupted as error:
            # Stopped from meerk40t: the streamer has disarmed; what is left in the queue is
            # emptied so that the next job is not refused (a board without vec_flush says
            # so: `galvoscan send soft_reset=1` empties it).
            more = ""
            try:
                client.write("vec_flush", 1)
            except (ClientError, ValueError, KeyError) as flush:
                more = f"; its queue could not be emptied ({flush})"
            return None, f"job stopped, laser disarmed: {error}{more}"
        except StopRequested as error:
            # (Stopped while holding: nothing armed, nothing queued.)
            return None, f"job stopped, laser disarmed: {error} during a wait"
        except JobRefused as error:
            return None, f"job refused: {error}"
        except JobAborted as error:
            return None, f"job stopped, laser disarmed: {error}"
        except (ClientError, OSError) as error:
            return None, f"job stopped, laser disarm sent: the link failed: {error}"

    def _hold(self, seconds):
        """Hold the board ``seconds`` on the link's clock (a simulated board runs for them in
        its own time; a real one is left that long by the host), the laser disarmed (each part
        of a job ends so) and the mirrors where the last part left them; in slices, so that
        meerk40t's stop ends it (:class:`StopRequested`) and a pause lengthens it."""
        left = seconds
        while left > 0:
            if self.hold.paused:
                self._client.sleep(HOLD_SLICE_S)        # (paused: the wait waits too)
                continue
            step = min(left, HOLD_SLICE_S)
            self._client.sleep(step)
            left -= step

    def frame(self, times):
        """Trace the last planned job's outline (its convex hull) ``times`` times with the
        guide laser on and the laser never armed, as ``mark --frame`` does."""
        plan = self.last_plan
        self.last_report = self.last_error = None
        if plan is None:
            self._refuse("nothing to frame: no job has been planned yet")
            return
        self._guide_trace(hull_outline(plan.vector_job.paths_mm), times, plan, "job")

    def outline_start(self):
        """meerk40t's trace begins (the device's ``pre_outline``): its moves are gathered."""
        self._outline = []

    def outline_end(self):
        """meerk40t's trace ends (``post_outline``): the outline its moves went round,
        checked by galvoscan's planner (in the field) and walked once with the guide laser,
        the laser never armed."""
        points, self._outline = self._outline, None
        self.last_report = self.last_error = None
        if not points:
            self._refuse("nothing to trace: meerk40t's trace gave no outline")
            return
        if points[-1] != points[0]:
            points.append(points[0])
        profile = self.service.profile
        try:
            job, objects = job_from_cuts(outline_cuts(points), profile,
                                         tolerance_mm=self.service.tolerance_mm)
            plan = api.plan_made(objects, job, profile)
        except ValueError as error:
            self._refuse(f"outline refused, nothing sent: {error}")
            return
        outline = from_galvo(np.array(points, dtype=float), profile.field.size_mm)
        self._guide_trace(outline, 1, plan, "selection")

    def _guide_trace(self, outline_mm, times, plan, what):
        """Walk ``outline_mm`` ``times`` times at ``plan``'s settings with the guide laser on
        and the laser never armed; ``what`` it is, for the console."""
        profile = self.service.profile
        if not profile.laser.guide:
            self._refuse("nothing framed: the machine profile says there is no guide laser "
                         "([laser] guide)")
            return
        failure = None
        with self._on_the_board(marking=False) as client:
            if client is None:
                return
            try:
                api.load_lens_table(self._client, profile, self._say)
                frame_job(JobStreamer(self._client, pause=self.hold), profile, outline_mm,
                          times, plan.vector_job.registers,
                          timeout_s=max(60.0, 10 * times * plan.estimate_s),
                          say=lambda line: self._say(f"galvoscan: {line}"), what=what)
            except (JobAborted, JobInterrupted) as error:
                failure = f"framing stopped, guide laser off: {error}"
            except (ClientError, OSError) as error:
                failure = f"framing stopped: the link failed: {error}"
        if failure is not None:
            self._refuse(failure)
            return
        self.last_report = "framed"

    def move_abs(self, x, y):
        """To ``x``, ``y`` (meerk40t's lengths: ``"12.5mm"``, or its scene units), through the
        device's view; gathered while meerk40t traces an outline."""
        x, y = self.service.view.position(x, y)
        if self._outline is not None:
            self._outline.append((float(x), float(y)))
        self.native_x = min(max(round(x), 0), 0xFFFF)
        self.native_y = min(max(round(y), 0), 0xFFFF)

    def move_rel(self, dx, dy, confined=False):
        dx, dy = self.service.view.position(dx, dy, vector=True)
        self.native_x = min(max(round(self.native_x + dx), 0), 0xFFFF)
        self.native_y = min(max(round(self.native_y + dy), 0), 0xFFFF)

    def home(self):
        self.native_x = self.native_y = 0x8000

    def physical_home(self):
        self.home()

    def rapid_mode(self):
        pass

    def program_mode(self):
        pass

    def raster_mode(self, *args):
        pass

    def wait_finished(self):
        pass

    def wait(self, time_in_ms):
        """Hold the board ``time_in_ms`` ms (meerk40t's wait: a wait operation spooled, G-code's
        G4 through ``grblcontrol``), the laser disarmed, as a WaitCut within a job is held
        (:meth:`_hold`); a time that is not one (below 0, not a number, over an hour) is one
        line and nothing is sent."""
        self.last_report = self.last_error = None
        try:
            (kind, seconds), = job_parts([WaitCut(time_in_ms)]) or [("hold", 0.0)]
        except ValueError as error:
            self._refuse(f"wait refused, nothing sent: {error}")
            return
        failure = None
        with self._on_the_board(marking=False, doing="holding (a wait)") as client:
            if client is None:
                return
            try:
                self._hold(seconds)
            except StopRequested as error:
                failure = f"wait stopped: {error}"
            except (ClientError, OSError) as error:
                failure = f"wait stopped: the link failed: {error}"
        if failure is not None:
            self._refuse(failure)
            return
        self._say(f"galvoscan: waited {seconds * 1e3:g} ms")
        self.last_report = "waited"

    def dwell(self, time_in_ms, settings=None):
        """Fire the laser ``time_in_ms`` ms where the head is (meerk40t's dwell), at
        ``settings``' power and frequency (else the profile's): a dwell cut there, planned,
        checked and marked as a dots operation's is (:meth:`plot_start`)."""
        self.queue.append(DwellCut((self.native_x, self.native_y), dwell_time=time_in_ms,
                                   settings=dict(settings) if settings else {}))
        self.plot_start()

    def function(self, function):
        function()

    def console(self, value):
        self.service(value)

    def beep(self):
        pass

    def signal(self, signal, *args):
        self.service.signal(signal, *args)

    def pause(self):
        """Hold the job on the board (the feed stopped, the queue marked out, the laser
        disarmed) and the spooler's next job."""
        self.paused = True
        self.hold.pause()
        self.service.signal("pause")

    def resume(self):
        """Let a held job go on (the laser armed again), and the spooler's next."""
        self.paused = False
        self.hold.resume()
        self.service.signal("pause")

    def reset(self):
        """Stop: the running job's next link exchange raises, and the streamer sends
        ``arm = 0`` first; with no job running, ``arm = 0`` is sent now. A held job is
        stopped, not let go on."""
        client = self._client
        if client is not None:
            # (Stopping first: a held job let go on meets the stop at its first write.)
            client.stopping.set()
            self.paused = False
            self.hold.resume()
            return
        self.paused = False
        self.hold.resume()
        if self.service.link == SIM and self.board is None:
            return                          # (no board yet: nothing armed)
        with self._lock:
            try:
                client, close = self._open()
            except (OSError, ValueError):
                return
            try:
                JobStreamer(client).disarm()
            finally:
                close()

    def read_status(self, wait_s=None):
        """The board's :class:`~galvoscan.outputs.board_state.BoardState`, read over the
        device's link (a ``sim`` link's board made if it is not yet) and shown in the status
        bar, or why it cannot be (and raised); None when a job or another read has the link for
        longer than ``wait_s`` seconds (None: as long as it has it). Read and shown under the
        link's lock, so that a job that takes the link next is not shown ready."""
        if not self._lock.acquire(timeout=-1 if wait_s is None else wait_s):
            return None
        try:
            try:
                client, close = self._open()
                try:
                    state = read_board_state(client)
                finally:
                    close()
            except (ClientError, OSError, ValueError) as error:
                self.status_bar.failed(error)
                raise
            self.status_bar.seen(state)
            return state
        finally:
            self._lock.release()

    def board_status(self):
        """The board's state in one line: marking or held (a job of this device's is running:
        as its last status read saw the board), else read off the board: busy or ready, armed,
        the interlock, an alarm, the latched faults and the head (and shown in the status
        bar)."""
        if self.service.link == SIM and self.board is None:
            return "no simulated board yet (the first job or status poll makes it)"
        state = None
        while state is None:
            if self._client is not None:
                return "a job held (paused), the laser disarmed" if self.hold.holding.is_set() \
                    else f"marking a job ({self.status_bar.text})"
            state = self.read_status(wait_s=0.1)    # (None: a poll's read, or a job starting)
        return state.summary() + ("" if state.head is None else
                                  f"; head: {state.head.describe()}")

    # --- the console ---------------------------------------------------------------------------

    def _say(self, line):
        self.service.channel("console")(line)

    def _refuse(self, line):
        self.last_error = line
        self._say(f"galvoscan: error: {line}")
