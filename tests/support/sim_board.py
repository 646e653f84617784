"""The system top in the simulator, with a scan head on its XY2-100 wires and a host on its UART
and SPI pins. The host side is bit-banged here from the command frame (docs/reference/host-link.md)
and standard 8N1 / SPI mode 0, independently of the gateware; the transports
plug into the real :class:`HostClient`, so the bytes the client produces are the bytes on the
simulated pins.
"""

import contextlib
import math

import pytest

from galvoscan.gateware.clocking import DEFAULT_BAUD
from galvoscan.gateware.top import ScanSettings
from galvoscan.sim.board import PIN_FIELDS, SimulatedBoard

from link_codec import cobs_encode, command
from wires import frames_from_samples

#: The register a last SPI frame reads, to clock out the answer before it (it changes nothing).
LINK_SEQ = 0x18


def _arguments_key(value):
    """``value`` (arguments of a build) as a string that two equal builds share."""
    import enum
    if isinstance(value, (bool, int, float, str, type(None), enum.Enum)):
        return repr(value)
    if isinstance(value, (tuple, list)):
        return "(" + ", ".join(map(_arguments_key, value)) + ")"
    if isinstance(value, dict):
        return _arguments_key(sorted(value.items()))
    if hasattr(value, "__dict__"):          # ScanSettings and the like: by their contents
        return type(value).__qualname__ + _arguments_key(vars(value))
    raise TypeError(f"no key for {value!r}")


class SimBoard:
    """The tests' board: galvoscan's :class:`~galvoscan.sim.board.SimulatedBoard` on the
    ``backend`` asked for (Amaranth's by default; the long simulations, the fuzz and the
    random jobs, ask for the compiled one, which tests/sim/test_compiled.py holds to the same
    records), with the tests' own view of it: the XY2-100 wires'
    samples decoded by the tests' reader (:func:`wires.frames_from_samples`), the pins made
    into one entry a clock, and the host's UART and SPI transports below."""

    def __init__(self, *, clk_freq=4e6, baud=500_000, interlock_closed=True, alarms_clear=True,
                 record_laser=False, backend="python", **top_kwargs):
        self.board = SimulatedBoard(clk_freq=clk_freq, baud=baud, backend=backend,
                                    record_samples=True, record_pins=record_laser,
                                    machine_period_s=1e-6, interlock_closed=interlock_closed,
                                    alarms_clear=alarms_clear, **top_kwargs)
        self.top = self.board.top
        self.clk_freq = clk_freq
        self.bit_time = 1 / baud
        self._record_laser = record_laser
        self._power_up()

    @property
    def backend(self):
        return self.board.backend

    def _power_up(self):
        """What the host and the recorders know at power-up, then the first clock."""
        self.xy2_samples = []           # (sync, x, y) at each falling xy2_clk edge
        self.parity_times = []          # when each frame's last bit was sampled
        self._frames = []               # the frames decoded so far (xy2_frames)
        self._samples_seen = 0
        self._by_clock = ([], [])
        self._changes_seen = 0
        # The machine's inputs reach the pins from the first instant.
        self.run_for(0)

    _built = {}

    @classmethod
    def powered_up(cls, **kwargs):
        """A board as :class:`SimBoard` ``(**kwargs)`` builds it, from power-up: the one built
        for the same arguments before, reset (every signal and memory to its initial value,
        every process started again), if there is one. For property tests, whose examples
        each want a new board: a reset is a millisecond, a build half a second."""
        key = _arguments_key(kwargs)
        board = cls._built.get(key)
        if board is None:
            board = cls._built[key] = cls(**kwargs)
        else:
            board.board.reset()
            board._power_up()
        return board

    # --- what the host sets and sees -------------------------------------------------------------

    @property
    def now(self):
        return self.board.now

    @property
    def interlock_closed(self):
        return self.board.interlock_closed

    @interlock_closed.setter
    def interlock_closed(self, closed):
        self.board.interlock_closed = closed

    @property
    def alarms_clear(self):
        return self.board.alarms_clear

    @alarms_clear.setter
    def alarms_clear(self, clear):
        self.board.alarms_clear = clear

    @property
    def uart_to_board(self):
        """Bytes, or ("pause", seconds), or ("bad_stop", byte), not yet on uart_rx."""
        return self.board.to_board

    @property
    def uart_from_board(self):
        """Bytes received on uart_tx."""
        return list(self.board.from_board)

    @property
    def uart_framing_errors(self):
        return self.board.framing_errors

    @property
    def spi_queue(self):
        """(bits, results list, half period, phase) of each SPI transfer not yet started."""
        return self.board.spi_queue

    # --- driving the simulation ------------------------------------------------------------------

    def run_for(self, seconds):
        if seconds > 0:
            self.board.run_for(seconds)
        # The end of the run_for() step in which each frame ended.
        for _, sync, x, y in self.board.xy2_samples[self._samples_seen:]:
            self.xy2_samples.append((sync, x, y))
            if not sync:
                self.parity_times.append(self.now)
        self._samples_seen = len(self.board.xy2_samples)

    def run_until(self, condition, *, timeout, step=50e-6):
        waited = 0.0
        while not condition():
            if waited > timeout:
                raise TimeoutError(f"simulated {timeout * 1e3:.1f} ms without an answer")
            self.run_for(step)
            waited += step

    # --- the pins ------------------------------------------------------------------------------

    LASER_PIN_NAMES = ("laser_mo", "laser_am", "laser_prr", "interlock_open", "laser_latch",
                       "laser_power", "laser_enable", "laser_alarm", "laser_guide")

    @staticmethod
    def _unpack(packed):
        return tuple((packed >> first) & ((1 << width) - 1) for _, first, width in PIN_FIELDS)

    def _clocks_so_far(self):
        """Rising clock edges simulated (the first at half a period, then one a period);
        one at the very end of the last run_for() is not."""
        edges = self.now * self.clk_freq - 0.5
        nearest = round(edges)
        return max(0, nearest if abs(edges - nearest) < 1e-6 else math.floor(edges) + 1)

    def _pins_on_every_clock(self):
        """Bring :attr:`laser_pins` and :attr:`sync_pins` up to now from the changes."""
        laser, sync = self._by_clock
        changes = self.board.pin_changes
        for clock, packed in changes[self._changes_seen:]:
            values = self._unpack(packed)
            if clock < len(laser):              # (a clock already filled in: from it on)
                laser[clock:] = [values[:-1]] * (len(laser) - clock)
                sync[clock:] = [values[-1]] * (len(sync) - clock)
            else:
                if clock > len(laser):
                    laser.extend([laser[-1]] * (clock - len(laser)))
                    sync.extend([sync[-1]] * (clock - len(sync)))
                laser.append(values[:-1])
                sync.append(values[-1])
        self._changes_seen = len(changes)
        if laser:
            missing = self._clocks_so_far() + 1 - len(laser)
            laser.extend([laser[-1]] * missing)
            sync.extend([sync[-1]] * missing)
        return laser, sync

    @property
    def laser_pins(self):
        """(laser_mo, laser_am, laser_prr, interlock_open, laser_latch, laser_power,
        laser_enable, laser_alarm, laser_guide) on every clock, if recorded."""
        if self._record_laser == "every clock":
            return [self._unpack(packed)[:-1] for packed in self.board.pins_every_clock]
        return self._pins_on_every_clock()[0]

    @property
    def sync_pins(self):
        """xy2_sync on every clock, if the laser is recorded (frame k's position is in force
        from sync's (k+1)-th rising edge: the end of that frame)."""
        if self._record_laser == "every clock":
            return [self._unpack(packed)[-1] for packed in self.board.pins_every_clock]
        return self._pins_on_every_clock()[1]

    def top_pin(self, name):
        """A laser pin's value on the last clock recorded (``record_laser=True``)."""
        return self.laser_pins[-1][self.LASER_PIN_NAMES.index(name)]

    def xy2_frames(self):
        """All XY2-100 frames so far, decoded by the tests' reader, with the time each ended.
        (A frame is 20 samples from the first on, so those decoded before are kept and only
        the new ones decoded: a long board's frames are not decoded again at every look.)"""
        done = len(self._frames) * 20
        complete = len(self.parity_times) * 20
        self._frames += frames_from_samples(self.xy2_samples[done:complete])
        return list(zip(self.parity_times, self._frames))

    def frames_after(self, t):
        return [frame for end, frame in self.xy2_frames() if end > t]


class SimUARTTransport:
    """The host's serial port on the simulated pins: each frame COBS-encoded (the tests' own
    encoder) with a zero byte after it, back to back on ``uart_rx``; answers read off
    ``uart_tx``, six bytes each. Plugs into the real :class:`~galvoscan.link.client.HostClient`.

    ``queue_writes``: :meth:`transact` only queues its bytes and returns no answers (as an
    OS that has taken them); they go out as the simulation runs."""

    def __init__(self, board, *, queue_writes=False, timeout=0.01):
        self.board = board
        self.queue_writes = queue_writes
        self.timeout = timeout          # board seconds
        self._seen = 0
        self._rest = b""

    def queue(self, data):
        """Add raw bytes to what the host sends."""
        self.board.uart_to_board.extend(data)

    def drain(self):
        """Run until everything queued has gone out (and the decoder has seen it)."""
        character = 10 * self.board.bit_time
        self.board.run_until(lambda: not self.board.uart_to_board, timeout=0.1, step=character)
        self.board.run_for(12 * self.board.bit_time)

    def send_bytes(self, data):
        self.queue(data)
        self.drain()

    def incoming(self):
        """Bytes off ``uart_tx`` since the last call (a faulty line may change them)."""
        new = bytes(self.board.uart_from_board[self._seen:])
        self._seen = len(self.board.uart_from_board)
        return new

    def packets(self, count, *, timeout=None):
        """The next ``count`` answers off ``uart_tx``, six bytes each, waiting up to
        ``timeout`` board seconds for them (fewer if they do not come)."""
        self.heard = bool(self._rest)

        def enough():
            new = self.incoming()
            self.heard = self.heard or bool(new)
            self._rest += new
            return len(self._rest) >= 6 * count
        try:
            self.board.run_until(enough, timeout=self.timeout if timeout is None else timeout,
                                 step=self.board.bit_time)
        except TimeoutError:
            pass
        taken, self._rest = self._rest[:6 * count], self._rest[6 * count:]
        return [taken[i:i + 6] for i in range(0, len(taken), 6)]

    def transact(self, frames):
        self.queue(b"".join(cobs_encode(frame) + b"\0" for frame in frames))
        if self.queue_writes:
            return []
        self.drain()
        return self.packets(len(frames))

    def flush(self):
        """Start afresh: a zero byte ends whatever the board was gathering, and what comes back
        until the line has been quiet for twenty character times is dropped."""
        self.send_bytes(b"\0")
        quiet = 20 * 10 * self.board.bit_time
        while True:
            self.board.run_for(quiet)
            if not self.incoming():
                break
        self._rest = b""


class SimSPITransport:
    """Frames clocked in on ``spi_copi`` with SCK at ``clk_freq / clocks_per_sck``; each
    answer is clocked out during the next frame (a last read of ``link_seq`` clocks out the
    last)."""

    def __init__(self, board, *, clocks_per_sck=12, phase=0.37):
        self.board = board
        self.half_period = clocks_per_sck / board.clk_freq / 2
        # Offset of the host's SCK edges from the board's clock edges, in board clocks.
        self.phase = phase / board.clk_freq

    def transfer_bits(self, bits):
        results = []
        self.board.spi_queue.append((list(bits), results, self.half_period, self.phase))
        # The host's part of a transfer (its phase, two half periods a bit, one more, and four
        # with cs_n high), then a look after every half period, so that the next transfer
        # follows this one at once.
        self.board.run_for(self.phase + (2 * len(bits) + 5) * self.half_period)
        self.board.run_until(lambda: results and results[-1] == "done", timeout=0.01,
                             step=self.half_period)
        return results[:-1]

    def transfer(self, frame):
        """Clock ``frame`` in; the first six bytes that came back (the answer to the frame
        before)."""
        bits = [(byte >> (7 - i)) & 1 for byte in frame for i in range(8)]
        got = self.transfer_bits(bits)
        return bytes(int("".join(map(str, got[i:i + 8])), 2) for i in range(0, 48, 8))

    def transact(self, frames):
        fetch = command(0xFF, LINK_SEQ, read=True)
        returned = [self.transfer(frame) for frame in [*frames, fetch]]
        return returned[1:]


#: The smallest system top that runs vector jobs: no other mode, no correction stage. Vector
#: mode's board tests (points on the wires, pulses on the DB25 pins) run on it at half the
#: simulation cost of the default build, whose spiral, raster and correction sit idle or pass
#: points through in vector mode; the default build's vector path is run by the wobble mark,
#: clean, job and link tests.
VECTOR_ONLY = {"modes": ("vector",), "correction": None}

#: :data:`VECTOR_ONLY` starting in vector mode, stopped: the board the command line's jobs
#: (``mark``, the job streamer) run on in the tests.
VECTOR_BOARD = dict(VECTOR_ONLY, settings=ScanSettings(mode="vector", run=False))


#: What the tests' ``--sim`` boards differ in from the command line's (the iCEBreaker's 12 MHz,
#: the 5 ms MO lead): 8 MHz, the slowest clock that carries the link's 1 Mbaud (8 clocks a
#: bit) and XY2-100 (4 clocks a bit), so a third fewer clocks to simulate for the same frames,
#: and a 0.5 ms MO lead, for jobs whose tests check what is marked, not the lead
#: (tests/gateware/laser/test_laser.py checks the lead).
QUICK_SIM_BOARD = {"clk_freq": 8e6, "mo_lead": 0.5e-3}

#: The smallest build with I/O in the queue (which needs pixel lines, hence the delays), on
#: the fly as the ULX3S's is (the queue's waits for an encoder's count are wired then), at
#: :data:`QUICK_SIM_BOARD`'s clock and lead: one compiled model for every I/O test.
IO_BOARD = dict(VECTOR_BOARD, **QUICK_SIM_BOARD, vector_delays=True, pixel_lines=True,
                queue_io=True, fly=True, vector_queue_depth=16)


def part_arrivals(board):
    """The clocks a simulated board's part sensor saw each part come on, until the board's
    time now: from the sensor's own description (the first ``first_s`` after it was set,
    then one every ``every_s``), not from the board's records."""
    sensor = board.part_sensor
    clocks, k = [], 0
    while (at := sensor.start_s + sensor.first_s + k * (sensor.every_s or 0)) < board.now:
        clocks.append(at * board.clk_freq)
        if sensor.every_s is None:
            break
        k += 1
    return clocks


def quick_board(**kwargs):
    """The default build at :data:`QUICK_SIM_BOARD` and the link's 1 Mbaud on the compiled
    board, the model tests/sim/test_compiled.py holds to Amaranth's simulator record for
    record (``kwargs``: what is recorded, e.g. ``record_laser=True``; nothing that changes
    the build, so that every test shares one compiled model)."""
    return SimBoard(backend="compiled", baud=DEFAULT_BAUD, **QUICK_SIM_BOARD, **kwargs)


@contextlib.contextmanager
def quick_sim_board(**top_kwargs):
    """Within it, ``--sim`` (``galvoscan.sim.board.SimulatedBoard``) builds its board with
    :data:`QUICK_SIM_BOARD` and ``top_kwargs`` (e.g. ``vector_queue_depth``)."""
    import galvoscan.sim.board as module
    original = module.SimulatedBoard

    class QuickSimulatedBoard(original):
        #: Every board built, for the test to look at.
        built = []

        def __init__(self, **kwargs):
            super().__init__(**{**QUICK_SIM_BOARD, **top_kwargs, **kwargs})
            self.built.append(self)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(module, "SimulatedBoard", QuickSimulatedBoard)
        yield QuickSimulatedBoard


@contextlib.contextmanager
def quick_replay_job(mo_lead=1e-3):
    """Within it, ``galvoscan sim --mode vector`` (``galvoscan.sim.vector.replay_job``) simulates at
    4 MHz, 2 clocks per XY2 bit (the same frames and pulses as at the board's 12 MHz, a third
    of the clocks), with a 1 ms MO lead (``mo_lead``, in seconds) where the board's is 5 ms
    (the lead, which the host only waits out, is checked on the pins by
    tests/gateware/laser/test_laser.py; 1 ms is what the test of the host waiting in the
    board's time needs on the compiled board, and one compiled build serves both)."""
    import functools
    import galvoscan.sim.vector as module
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(module, "replay_job", functools.partial(module.replay_job, clk_freq=4e6,
                                                              mo_lead=mo_lead))
        yield
