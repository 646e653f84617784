"""A board without hardware: the system top in the simulator, its UART served on a
pseudo-terminal, so that ``send``, ``read``, ``mark`` and ``clean --port PTY`` run against it
unchanged (``galvoscan board --sim``).

The host's bytes are clocked into ``uart_rx`` at the baud rate, 8N1, and ``uart_tx`` is read
back bit by bit, as the board's FTDI chip does; a scan head on the XY2-100 wires and a laser on
the DB25 pins record what the board does.

The board runs on one of two backends behind one contract (:mod:`.contract`): the compiled
model (:mod:`.compiled`; the command line's default, ``--backend auto``, wherever a C++
compiler can build it) some 14 times slower than the board itself, or Amaranth's simulator
(:mod:`.board_engine`, the reference) some 4,000 times slower (``docs/bench.json``, on two
cores: 840,000 and 3,000 of the board's 12 MHz clocks a second). A host talking to it needs an
answer timeout to match: :meth:`SimulatedBoard.answer_timeout_s` works it out from the speed
measured (``galvoscan board --sim`` prints it). Anything timed in seconds on the host (a
cleaning run's duration) is counted in the board's own time (its laser pulses) rather than by
the host's clock.
"""

import math
import os
import pty
import select
import threading
import time
import tty
from collections import deque
from dataclasses import dataclass

from ..gateware.clocking import DEFAULT_BAUD
from ..gateware.player.image_format import JOB_OFFSET
from ..gateware.top import GalvoScanTop
from ..link.client import ClockedTransport, PacketTransport
from ..settings.laser import TIMEOUT
from .board_engine import PythonEngine
from .compiled import CompiledEngine, CompileError, compiled_model
from .compiled.netlist import build_record, netlist_design
from .contract import BACKENDS, LASER_PINS, MACHINE_PERIOD_S, PIN_FIELDS
from .head import HEALTHY_HEAD
from .spi_flash import SPIFlashModel
from .xy2_receiver import frame_of_each_pulse


__all__ = ["SimulatedBoard", "Belt", "PartSensor", "PTYServer", "SimTransport", "SimSPITransport",
           "BACKENDS",
           "LASER_PINS", "PIN_FIELDS"]




@dataclass
class PartSensor:
    """A part sensor on input ``input``: the first part reaches it ``first_s`` after it is
    set up, then one every ``every_s`` (None: that one alone), each seen for ``seen_s``.
    ``level``: what the input reads while a part is seen (the rest of the time, the other)."""
    input: int = 0
    first_s: float = 1e-3
    every_s: float = None
    seen_s: float = 2e-3
    level: int = 1
    start_s: float = 0.0

    def seen(self, now):
        """Whether a part is seen at the board's time ``now``."""
        since = now - self.start_s - self.first_s
        if since < 0:
            return False
        if self.every_s is not None:
            since %= self.every_s
        return since < self.seen_s

    def next_change(self, now):
        """The board's time the sensor next comes to a part or leaves it, after ``now`` (inf:
        never)."""
        first = self.start_s + self.first_s
        since = now - first
        if since < 0:
            return first
        if self.every_s is None:
            return first + self.seen_s if since < self.seen_s else math.inf
        phase = since % self.every_s
        base = now - phase
        return base + self.seen_s if phase < self.seen_s else base + self.every_s


@dataclass
class Belt:
    """The conveyor's encoder (:mod:`.belt`): its rate, count and the glitches to come."""
    axis: str = "x"
    counts_per_s: int = 0
    count: int = 0
    fraction: int = 0
    glitch_periods: int = 0


class SimulatedBoard:
    """The system top at the board's clock, with a host UART, a scan head and a laser.

    Parameters
    ----------
    config : :class:`~galvoscan.gateware.build_config.BuildConfig`, optional
        The build simulated (a board's bitstream: ``galvoscan.build.PRESETS``); its clock and
        baud are the board's. None: one of ``clk_freq``, ``baud`` and ``top_kwargs``.
    clk_freq : float
        System clock (12 MHz, the iCEBreaker's).
    baud : int or None
        The UART's rate (the bitstream's default, 1 Mbaud; None: the top's default for the
        clock).
    backend : str
        ``"python"``: Amaranth's simulator (the reference); ``"compiled"``: the top compiled to
        native code (:mod:`galvoscan.sim.compiled`, built once per design and cached), some
        hundreds of times faster; ``"auto"``: the compiled one where it can be built, else the
        Python one, with a line to ``say`` saying why. Both give the same records.
    say : callable, optional
        Told in a line each when the compiled model is being built, or why it is not used.
    record_samples : bool
        Record the scan head's raw samples (:attr:`xy2_samples`), for a decoder of one's own.
    record_pins : bool or str
        Record the pins of :data:`PIN_FIELDS` at their changes (:attr:`pin_changes`), or
        ``"every clock"`` (:attr:`pins_every_clock`; the Python backend only).
    machine_period_s : float
        How often the interlock and alarm pins are set from :attr:`interlock_closed` and
        :attr:`alarms_clear` (10 µs).
    interlock_closed, alarms_clear : bool
        The machine's inputs at power-up (and after :meth:`reset`).
    head_word : int or None
        The status word the scan head answers each frame with on its STATUS line, at power-up
        (and after :meth:`reset`), on a build with the head status receiver
        (:data:`~.head.HEALTHY_HEAD`, a head with nothing to report); None: no head answers.
    flash : bytes or :class:`~.spi_flash.SPIFlashModel`, optional
        The configuration flash of a build with the job player (``player=True``): a job
        image (put at its offset, the rest erased) or a flash model. None: an erased flash.
    vcd : path, optional
        Write a waveform of the whole run, until :meth:`close` (the Python backend).
    netlist : path, optional
        A build's folder: simulate its synthesized netlist, gate by gate, instead of a top
        built here (the compiled backend; the clock and baud are the build's).
        :attr:`top` is then None.
    top_kwargs
        More :class:`~galvoscan.gateware.top.GalvoScanTop` parameters (``table``,
        ``settings``; without ``config``, its options: ``mo_lead`` …).

    Attributes
    ----------
    backend : str
        The backend that runs it (``"python"`` or ``"compiled"``).
    frames : list of (int, int, int)
        ``(cycle, x, y)``: the clock on which each XY2-100 frame was complete, and its position.
    z_frames : list of (int, int)
        ``(cycle, z)``: the same for the Z line's frames (a build with the Z channel).
    pulses : list of int
        Clock of each laser pulse (a PRR rising edge with modulation on).
    laser_changes : list of (int, tuple)
        ``(cycle, pins)`` each time a laser pin changed (pins in :data:`LASER_PINS` order).
    bytes_in : list of (int, int)
        ``(cycle, byte)``: every byte the host sent, and the clock its stop bit ended.
    xy2_samples : list of (int, int, int, int)
        ``(cycle, sync, x, y)`` at each falling ``xy2_clk`` edge (``record_samples``).
    pin_changes : list of (int, int)
        ``(clock, pins)``: the pins of :data:`PIN_FIELDS`, packed, as they are once the
        design has settled after that rising clock edge (clock 0: at power-up), at least
        whenever they changed; of several entries for one clock the last holds
        (``record_pins``).
    to_board : deque
        What the host sends on the UART: bytes, ``("pause", seconds)`` and
        ``("bad_stop", byte)`` (appended to only).
    start_pressed : bool
        The foot switch on ``start_n``, pressed (set by the host; the machine's period).
    io_inputs : int
        The inputs ``io_in`` of a build with I/O in the queue, bit k for input k (set by the
        host, or by :attr:`part_sensor`; the machine's period). 0 at power-up.
    part_sensor : :class:`PartSensor` or None
        A part sensor on an input: it sets that bit of :attr:`io_inputs` as parts pass it.
    io_changes : list of (int, int)
        ``(cycle, outputs)``: each change of the outputs ``io_out`` (bit k for output k; 0 at
        power-up), and the clock it was seen on.
    belt : :class:`Belt`
        The conveyor's encoder on a build that marks on the fly (:meth:`belt_moves`; its
        ``count``, and ``glitch_periods``: machine periods with both lines turned over).
    head_word : int or None
        The head's status word now (set by a test: a head that grows hot), sent from the
        next frame on; None: no head answers.
    spi_queue : deque
        SPI transfers to clock in: ``(bits, results, half_period_s, phase_s)``; ``results``
        gets CIPO's bit as SCK rises for each bit, then ``"done"`` (appended to only).
    """

    def __init__(self, *, config=None, clk_freq=12e6, baud=DEFAULT_BAUD, backend="python",
                 say=None,
                 record_samples=False, record_pins=False, machine_period_s=MACHINE_PERIOD_S,
                 interlock_closed=True, alarms_clear=True, head_word=HEALTHY_HEAD, flash=None,
                 vcd=None, netlist=None, **top_kwargs):
        if backend not in BACKENDS:
            raise ValueError(f"backend must be one of {', '.join(BACKENDS)}, not {backend!r}")
        if netlist is not None:
            self._netlist_board(netlist, backend, say, record_samples=record_samples,
                                record_pins=record_pins, machine_period_s=machine_period_s,
                                machine=(interlock_closed, alarms_clear), extra=top_kwargs)
            return
        if config is None:
            self.top = GalvoScanTop(clk_freq=clk_freq, baud=baud, **top_kwargs)
        else:           # (the build's clock and baud)
            self.top = GalvoScanTop(config, **top_kwargs)
        self.config = self.top.config
        self.clk_freq = self.config.clk_freq
        self._set_flash(flash)
        self.baud = self.config.baud
        self.machine_period_s = machine_period_s
        self._machine_at_power_up = (interlock_closed, alarms_clear)
        self._head_at_power_up = self._checked_head(head_word)
        self._power_up_records()
        if vcd and backend == "compiled":
            raise ValueError("a waveform (vcd) needs the Python backend")
        records = dict(record_samples=record_samples, record_pins=record_pins)
        self.engine = (PythonEngine(self, vcd=vcd, **records) if vcd else
                       self._engine(backend, say or (lambda line: None), **records))
        self.backend = self.engine.name
        self.run_for(1 / self.clk_freq)     # start the processes in this thread

    def belt_moves(self, mm_s, counts_per_mm, *, axis="x"):
        """Run the belt under the encoder on ``axis`` at ``mm_s`` (signed), its encoder giving
        ``counts_per_mm`` counts a mm (every edge a count): from the next machine period on."""
        if axis not in ("x", "y"):
            raise ValueError(f"the belt's encoder is on x or y, not {axis!r}")
        rate = round(mm_s * counts_per_mm)
        if abs(rate) * self.machine_period_s > 1:
            raise ValueError(f"{mm_s:g} mm/s at {counts_per_mm:g} counts/mm is more than a "
                             f"count a machine period ({self.machine_period_s * 1e6:g} µs)")
        self.belt.axis, self.belt.counts_per_s = axis, rate

    @staticmethod
    def _checked_head(word):
        if word is not None and (isinstance(word, bool) or not isinstance(word, int) or
                                 not 0 <= word <= 0xFFFF):
            raise ValueError(f"head_word must be a 16-bit status word or None, not {word!r}")
        return word

    def _netlist_board(self, netlist, backend, say, *, machine_period_s, machine, extra,
                       **records):
        if backend == "python" or extra or records.get("record_pins") == "every clock":
            raise ValueError("a netlist runs on the compiled backend alone, as it was built")
        record = build_record(netlist) or {}
        self.clk_freq = float(record.get("clock_mhz", 12)) * 1e6
        self.baud = int(record.get("baud", DEFAULT_BAUD))
        self.top = self.config = None
        self.machine_period_s = machine_period_s
        self._machine_at_power_up = machine
        self._head_at_power_up = None
        self._power_up_records()
        model = compiled_model(netlist_design(netlist), say=say)
        self.engine = CompiledEngine(self, model=model, **records)
        self.backend = self.engine.name
        self.run_for(1 / self.clk_freq)

    def _set_flash(self, flash):
        """The configuration flash's contents at every power-up from now on."""
        if flash is not None and not self.config.player:
            raise ValueError("a flash is read by the job player: build it with player=True")
        self._flash_at_power_up = flash

    def _power_up_records(self):
        self.now = 0.0
        self.to_board = deque()         # what the host sends, not yet on uart_rx
        self.from_board = deque()       # bytes off uart_tx, not yet given to the host
        self.spi_queue = deque()        # SPI transfers not yet started
        self.framing_errors = 0
        self.bytes_in = []              # (cycle its stop bit ended, byte) of every byte in
        self.frames = []
        self.z_frames = []
        self.io_changes = []
        self.io_inputs = 0
        self.part_sensor = None
        self.sync_rises = []
        self.pulses = []
        self.laser_changes = []
        self.xy2_samples = []
        self.pin_changes = []
        self.pins_every_clock = []
        self.interlock_closed, self.alarms_clear = self._machine_at_power_up
        self.head_word = self._head_at_power_up
        self.belt = Belt()
        self.start_pressed = False
        self.flash = None
        if self.config is not None and self.config.player:
            flash = self._flash_at_power_up
            if isinstance(flash, SPIFlashModel):
                self.flash = flash
            else:
                self.flash = SPIFlashModel({JOB_OFFSET: flash} if flash else None)

    def _engine(self, backend, say, **records):
        if backend == "python" or records.get("record_pins") == "every clock":
            return PythonEngine(self, **records)
        try:
            return CompiledEngine(self, say=say, **records)
        except CompileError as error:
            if backend == "compiled":
                raise
            say(f"the compiled simulator is not available ({error}); using Amaranth's "
                f"simulator, some 200 times slower")
            return PythonEngine(self, **records)

    def reset(self, *, flash=...):
        """Back to power-up (the same design, every record empty, the machine's inputs as
        at power-up), far quicker than building the board again; with ``flash`` (as the
        constructor takes it) in the configuration flash from now on, if given."""
        if flash is not ...:
            self._set_flash(flash)
        self._power_up_records()
        self.engine.reset()
        self.run_for(1 / self.clk_freq)

    @property
    def bit_time(self):
        return 1 / self.baud

    # --- driving it ----------------------------------------------------------------------------

    def run_for(self, seconds):
        """Advance the board by ``seconds`` of its own time (with a part sensor, in steps that
        end where it comes to a part or leaves it, so that a host's long poll misses none)."""
        if seconds <= 0:
            return
        end = self.now + seconds
        while True:
            sensor = self.part_sensor
            until = end
            if sensor is not None:
                bit = 1 << sensor.input
                level = sensor.level if sensor.seen(self.now) else 1 - sensor.level
                self.io_inputs = (self.io_inputs & ~bit) | (bit if level else 0)
                # (At least a clock on: a change a rounding away is taken at the next step.)
                until = min(end, max(sensor.next_change(self.now), self.now + 1 / self.clk_freq))
            self.now = until
            self.engine.run_until(self.now)
            if until >= end:
                return

    def parts_arrive(self, *, input=0, first_s=1e-3, every_s=None, seen_s=2e-3, level=1):
        """Set a :class:`PartSensor` on ``input``, from now on."""
        if not 0 <= input < 2:
            raise ValueError(f"the part sensor is on input 0 or 1, not {input!r}")
        self.part_sensor = PartSensor(input=input, first_s=first_s, every_s=every_s,
                                      seen_s=seen_s, level=level, start_s=self.now)

    def speed(self, seconds=0.2e-3):
        """How fast it runs, as a fraction of real time: measured by running ``seconds`` of
        its own time (idle, as it is before a host's first frame)."""
        started = time.perf_counter()
        self.run_for(seconds)
        return seconds / max(time.perf_counter() - started, 1e-9)

    def answer_timeout_s(self):
        """The answer timeout a host should give it, in seconds of the host's clock: 20 ms
        of the board's own time (a frame and its answer take well under 1 ms) at the speed
        measured now, and 5 s at least, for a host busy with other work; at most the longest
        ``--timeout`` a command takes, so that what ``board --sim`` advises is accepted."""
        return min(TIMEOUT.high, max(5.0, 20e-3 / self.speed()))

    def close(self):
        """Free the backend's model (the compiled one's memory)."""
        self.engine.close()

    def press_start(self, hold_s=30e-3):
        """Press the foot switch for ``hold_s`` (longer than its debounce), and let go."""
        self.start_pressed = True
        self.run_for(hold_s)
        self.start_pressed = False

    def busy(self):
        """Bytes still to go in or out."""
        return bool(self.to_board)

    def points(self):
        """``(x, y, pulses, frames, cycle, first_pulse)`` per run of frames at one position,
        from power-up: ``cycle`` is the clock on which the run's first frame was complete,
        ``first_pulse`` that of its first laser pulse (None without one)."""
        counts = [0] * len(self.frames)
        first = [None] * len(self.frames)
        for k, cycle in frame_of_each_pulse(self.sync_rises, self.pulses, len(self.frames)):
            counts[k] += 1
            if first[k] is None:
                first[k] = cycle
        points = []
        for (cycle, x, y), n, pulse in zip(self.frames, counts, first):
            if points and points[-1][:2] == [x, y]:
                points[-1][2] += n
                points[-1][3] += 1
                if points[-1][5] is None:
                    points[-1][5] = pulse
            else:
                points.append([x, y, n, 1, cycle, pulse])
        return [tuple(p) for p in points]


class PTYServer:
    """Serve a :class:`SimulatedBoard`'s UART on a pseudo-terminal, in a thread of its own.

    ``port`` is the terminal's path, for pyserial. The board runs in steps of ``step`` seconds
    of its own time while the link is idle, and for as long as the bytes need while it is not.

    ``real_time``: the board never runs ahead of the host's clock: a board faster than real
    time waits after each step until the wall has caught up, so a host sees a real board's
    timing (its watchdog, a cleaning run's duration, the answers' latency). A board slower
    than real time cannot keep up: :attr:`lag_s` says how far behind it is.
    """

    def __init__(self, board, *, step=100e-6, real_time=False):
        self.board = board
        self.step = step
        self.real_time = real_time
        self._wall_start = self._board_start = None
        self._master, self._slave = pty.openpty()
        tty.setraw(self._slave)
        self.port = os.ttyname(self._slave)
        self._stop = threading.Event()
        self._thread = None
        self.error = None

    def start(self):
        self._thread = threading.Thread(target=self._serve, name="simulated board", daemon=True)
        self._thread.start()
        return self

    def serve_forever(self, report=None, every_s=10.0):
        """Serve until Ctrl-C (or :meth:`stop` from another thread).

        The simulation runs in the server's own thread, and this one only waits: a Ctrl-C then
        lands here, never inside a step of the simulator (whose coroutines it would leave
        half-run), and the server stops between two steps. ``report(lag_s)`` is called
        every ``every_s`` seconds while the board is behind the host's clock."""
        self.start()
        last = time.monotonic()
        try:
            while self._thread.is_alive():
                time.sleep(0.1)
                if report is not None and time.monotonic() - last >= every_s:
                    last = time.monotonic()
                    if self.lag_s > 0:
                        report(self.lag_s)
        finally:
            self.stop()

    @property
    def lag_s(self):
        """Seconds the board's time is behind the host's since the server started (0 while
        it keeps up)."""
        if self._wall_start is None:
            return 0.0
        return max(0.0, (time.monotonic() - self._wall_start) -
                   (self.board.now - self._board_start))

    def _serve(self):
        board = self.board
        self._wall_start, self._board_start = time.monotonic(), board.now
        try:
            while not self._stop.is_set():
                if self.real_time:
                    ahead = (board.now - self._board_start) - \
                        (time.monotonic() - self._wall_start)
                    if ahead > 0:
                        # (Woken early by stop(); a byte from the host waits for the
                        # instant the board's time reaches the wall's.)
                        self._stop.wait(ahead)
                ready, _, _ = select.select([self._master], [], [], 0)
                if ready:
                    try:
                        board.to_board.extend(os.read(self._master, 4096))
                    except OSError:             # the host closed its end
                        pass
                # Long enough to put every waiting byte on the wire and hear an answer.
                pending = len(board.to_board)
                board.run_for(max(self.step, (min(pending, 256) + 6) * 10 * board.bit_time))
                if board.from_board:
                    answer = bytes(board.from_board)
                    board.from_board.clear()
                    os.write(self._master, answer)
        except Exception as error:      # reported by the thread's owner
            self.error = error

    def stop(self):
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        for fd in (self._master, self._slave):
            try:
                os.close(fd)
            except OSError:
                pass

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.stop()


class BoardClock:
    """A simulated board's transports keep its own time: a host's waits on it (the MO lead,
    the queue, an answer) count what the board did, not the host's clock. Before the
    transport's base in its bases."""

    def now(self):
        """The board's own time, in seconds."""
        return self.board.now

    def sleep(self, seconds):
        """Run the board for ``seconds`` of its own time."""
        self.board.run_for(seconds)


class SimTransport(BoardClock, PacketTransport):
    """Frames straight into a :class:`SimulatedBoard`'s UART, in the board's own time (no
    pseudo-terminal, no host clock): what a host at the link's full speed, with no latency of
    its own, would get. ``timeout`` is in board seconds."""

    def __init__(self, board, *, timeout=0.05):
        self.board = board
        self.timeout = timeout          # board seconds
        self.quiet_s = 200 * board.bit_time

    def _write(self, data):
        board = self.board
        board.to_board.extend(data)
        # Until the last byte has started: the next frame's follow it back to back.
        while board.to_board:
            board.run_for(len(board.to_board) * 10 * board.bit_time)

    def _read(self, seconds):
        """What came within ``seconds`` of board time: as soon as anything has, a character
        time at a time."""
        board = self.board
        waited = 0.0
        while not board.from_board and waited < seconds:
            step = max(min(seconds - waited, 10 * board.bit_time), 1 / board.clk_freq)
            board.run_for(step)
            waited += step
        data = bytes(board.from_board)
        board.from_board.clear()
        return data


class SimSPITransport(BoardClock, ClockedTransport):
    """Frames into a :class:`SimulatedBoard`'s SPI target, in the board's own time, as a host
    at the link's top speed sends them (SCK = clock / 12, mode 0); each answer is clocked out
    during the next frame (as ``FTDISPITransport``)."""

    def __init__(self, board, *, clocks_per_sck=12):
        self.board = board
        self.half_period = clocks_per_sck / board.clk_freq / 2

    def transfer(self, frame):
        board = self.board
        bits = [(byte >> (7 - i)) & 1 for byte in frame for i in range(8)]
        results = []
        board.spi_queue.append((bits, results, self.half_period, 0))
        # The transfer's own time (two half periods a bit, one more, four with cs_n high),
        # then a look every half period, so the next transfer follows at once.
        board.run_for((2 * len(bits) + 5) * self.half_period + 1 / board.clk_freq)
        while not results or results[-1] != "done":
            board.run_for(self.half_period)
        value = 0
        for bit in results[:-1]:
            value = (value << 1) | bit
        return value.to_bytes(len(frame), "big")
