"""A board without hardware: the system top in the simulator, its UART served on a
pseudo-terminal, so that ``send``, ``read``, ``mark`` and ``clean --port PTY`` run against it
unchanged (``galvoscan board --sim``).

The host's bytes are clocked into ``uart_rx`` at the baud rate, 8N1, and ``uart_tx`` is read
back bit by bit, as the board's FTDI chip does; a scan head on the XY2-100 wires and a laser on
the DB25 pins record what the board does. The simulation runs about a thousand times slower
than the board: a host talking to it needs a long answer timeout (``--timeout 60``), and
anything timed in seconds on the host (a cleaning run's duration) is counted in the board's
own time (its laser pulses) rather than by the host's clock.
"""

import os
import select
import threading
import time
from collections import deque

from amaranth.sim import Simulator

from ..gateware.clocking import DEFAULT_BAUD
from ..gateware.top import GalvoScanTop
from .link import Timed
from .xy2_receiver import XY2Receiver, frame_of_each_pulse


__all__ = ["SimulatedBoard", "PTYServer", "SimTransport", "SIM_TIMEOUT_S"]


#: Answer timeout a host should give the simulated board, in seconds of the host's clock.
SIM_TIMEOUT_S = 60.0

# The laser pins recorded at every change, in this order.
LASER_PINS = ("laser_enable", "laser_mo", "laser_am", "laser_prr", "laser_latch", "laser_guide")


class SimulatedBoard:
    """The system top at the board's clock, with a host UART, a scan head and a laser.

    Parameters
    ----------
    clk_freq : float
        System clock (12 MHz, the iCEBreaker's).
    baud : int
        The UART's rate (the bitstream's default, 1 Mbaud).
    top_kwargs
        More :class:`~galvoscan.gateware.top.GalvoScanTop` parameters (``mo_lead`` …).

    Attributes
    ----------
    frames : list of (int, int, int)
        ``(cycle, x, y)``: the clock on which each XY2-100 frame was complete, and its position.
    pulses : list of int
        Clock of each laser pulse (a PRR rising edge with modulation on).
    laser_changes : list of (int, tuple)
        ``(cycle, pins)`` each time a laser pin changed (pins in :data:`LASER_PINS` order).
    bytes_in : list of (int, int)
        ``(cycle, byte)``: every byte the host sent, and the clock its stop bit ended.
    """

    def __init__(self, *, clk_freq=12e6, baud=DEFAULT_BAUD, **top_kwargs):
        self.clk_freq = clk_freq
        self.baud = baud
        self.top = GalvoScanTop(clk_freq=clk_freq, baud=baud, **top_kwargs)
        self._timed = Timed(self.top)
        self.sim = Simulator(self._timed)
        self.sim.add_clock(1 / clk_freq)
        self.now = 0.0
        self.to_board = deque()         # bytes the host sent, not yet on uart_rx
        self.from_board = deque()       # bytes off uart_tx, not yet given to the host
        self.framing_errors = 0
        self.bytes_in = []              # (cycle its stop bit ended, byte) of every byte in
        self.frames = []
        self.sync_rises = []
        self.pulses = []
        self.laser_changes = []
        self.interlock_closed = True
        self.alarms_clear = True
        self._receiver = XY2Receiver()
        for process in (self._uart_in, self._uart_out, self._scan_head, self._sync_edges,
                        self._laser, self._machine):
            self.sim.add_testbench(process, background=True)
        # A process, not a testbench: the pins are logic, and may change more than once
        # while the design settles after a clock edge; a process sees every change.
        self.sim.add_process(self._laser_pins)
        self.run_for(1 / clk_freq)      # start the processes in this thread

    @property
    def bit_time(self):
        return 1 / self.baud

    # --- the processes -----------------------------------------------------------------------

    async def _uart_in(self, ctx):
        """The host's transmitter: each byte 8N1 on uart_rx, back to back."""
        rx = self.top.uart_rx
        ctx.set(rx, 1)
        while True:
            if not self.to_board:
                await ctx.delay(self.bit_time)
                continue
            byte = self.to_board.popleft()
            for level in (0, *((byte >> i) & 1 for i in range(8)), 1):
                ctx.set(rx, level)
                await ctx.delay(self.bit_time)
            self.bytes_in.append((ctx.get(self._timed.cycles), byte))

    async def _uart_out(self, ctx):
        """The host's receiver: a start bit's falling edge, then each bit in its middle."""
        tx = self.top.uart_tx
        while True:
            await ctx.negedge(tx)
            await ctx.delay(1.5 * self.bit_time)
            value = 0
            for i in range(8):
                value |= ctx.get(tx) << i
                await ctx.delay(self.bit_time)
            if ctx.get(tx):
                self.from_board.append(value)
            else:
                self.framing_errors += 1

    async def _scan_head(self, ctx):
        top = self.top
        async for _, sync, x, y, cycles in ctx.negedge(top.xy2_clk).sample(
                top.xy2_sync, top.xy2_x, top.xy2_y, self._timed.cycles):
            frame = self._receiver.sample(sync, x, y)
            if frame is not None:
                self.frames.append((cycles, frame.x, frame.y))

    async def _sync_edges(self, ctx):
        async for _, cycles in ctx.posedge(self.top.xy2_sync).sample(self._timed.cycles):
            self.sync_rises.append(cycles)

    async def _laser(self, ctx):
        top = self.top
        async for _, am, cycles in ctx.posedge(top.laser_prr).sample(top.laser_am,
                                                                      self._timed.cycles):
            if am:
                self.pulses.append(cycles)

    async def _laser_pins(self, ctx):
        pins = [getattr(self.top, name) for name in LASER_PINS]
        async for *values, cycles in ctx.changed(*pins).sample(self._timed.cycles):
            self.laser_changes.append((cycles, tuple(values)))

    async def _machine(self, ctx):
        # The interlock loop and the laser's alarm outputs, as the machine has them.
        alarm = getattr(self.top, "laser_alarm", None)
        while True:
            ctx.set(self.top.interlock_open, 0 if self.interlock_closed else 1)
            if alarm is not None:
                ctx.set(alarm, 0 if self.alarms_clear else 2 ** len(alarm) - 1)
            await ctx.delay(10e-6)

    # --- driving it ----------------------------------------------------------------------------

    def run_for(self, seconds):
        """Advance the board by ``seconds`` of its own time."""
        if seconds > 0:
            self.now += seconds
            self.sim.run_until(self.now)

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
    """

    def __init__(self, board, *, step=100e-6):
        import pty
        import tty
        self.board = board
        self.step = step
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

    def serve_forever(self):
        """Serve until Ctrl-C (or :meth:`stop` from another thread).

        The simulation runs in the server's own thread, and this one only waits: a Ctrl-C then
        lands here, never inside a step of the simulator (whose coroutines it would leave
        half-run), and the server stops between two steps."""
        self.start()
        try:
            while self._thread.is_alive():
                time.sleep(0.1)
        finally:
            self.stop()

    def _serve(self):
        board = self.board
        try:
            while not self._stop.is_set():
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


class SimTransport:
    """Frames straight into a :class:`SimulatedBoard`'s UART, in the board's own time (no
    pseudo-terminal, no host clock): what a host at the link's full speed, with no latency of
    its own, would get. For measuring the link (``galvoscan bench``)."""

    def __init__(self, board, *, timeout=0.05):
        self.board = board
        self.timeout = timeout          # board seconds

    def write_frame(self, frame):
        board = self.board
        board.to_board.extend(frame)
        # Until the last byte has started: the next frame's follow it back to back.
        while board.to_board:
            board.run_for(len(board.to_board) * 10 * board.bit_time)

    def query(self, frame):
        from ..client import ClientError
        board = self.board
        board.from_board.clear()
        self.write_frame(frame)
        waited = 0.0
        while len(board.from_board) < 4:
            if waited > self.timeout:
                raise ClientError(f"no answer from the simulated board in {self.timeout} s")
            board.run_for(10 * board.bit_time)
            waited += 10 * board.bit_time
        answer = bytes(list(board.from_board)[:4])
        board.from_board.clear()
        return answer
