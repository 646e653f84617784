"""The system top in the simulator, with a scan head on its XY2-100 wires and a host on its UART
and SPI pins. The host side is bit-banged here from the command frame (README "Controlling it
from a host") and standard 8N1 / SPI mode 0, independently of the gateware; the transports
plug into the real :class:`HostClient`, so the bytes the client produces are the bytes on the
simulated pins.
"""

from collections import deque

from amaranth.sim import Simulator

from galvoscan.gateware.top import GalvoScanTop

from wires import frames_from_samples


class SimBoard:
    def __init__(self, *, clk_freq=4e6, baud=500_000, interlock_closed=True, alarms_clear=True,
                 record_laser=False, **top_kwargs):
        self.top = top = GalvoScanTop(clk_freq=clk_freq, baud=baud, **top_kwargs)
        self.clk_freq = clk_freq
        self.bit_time = 1 / baud
        self.sim = Simulator(top)
        self.sim.add_clock(1 / clk_freq)
        self.now = 0.0

        self.xy2_samples = []           # (sync, x, y) at each falling xy2_clk edge
        self.parity_times = []          # when each frame's last bit was sampled
        self.uart_to_board = deque()    # bytes, or ("pause", seconds), or ("bad_stop", byte)
        self.uart_from_board = []       # bytes received on uart_tx
        self.uart_framing_errors = 0
        self.spi_queue = deque()        # (bits, results list)

        self.sim.add_testbench(self._scan_head, background=True)
        self.sim.add_testbench(self._uart_host_tx, background=True)
        self.sim.add_testbench(self._uart_host_rx, background=True)
        self.sim.add_testbench(self._spi_host, background=True)
        self.interlock_closed = interlock_closed
        self.alarms_clear = alarms_clear
        self.sim.add_testbench(self._interlock, background=True)
        #: (laser_mo, laser_am, laser_prr, interlock_open, laser_latch, laser_power,
        #: laser_enable, laser_alarm, laser_guide) on every clock, if recorded.
        self.laser_pins = []
        #: xy2_sync on every clock, if the laser is recorded (frame k's position is in force
        #: from sync's (k+1)-th rising edge: the end of that frame).
        self.sync_pins = []
        if record_laser:
            self.sim.add_testbench(self._laser_recorder, background=True)
        # Start the processes now, in this thread (a simulator never run leaves its testbench
        # coroutines un-awaited, which Python reports at garbage collection).
        self.run_for(1 / clk_freq)

    # --- processes ---------------------------------------------------------------------------

    async def _scan_head(self, ctx):
        top = self.top
        async for _, sync, x, y in ctx.negedge(top.xy2_clk).sample(
                top.xy2_sync, top.xy2_x, top.xy2_y):
            self.xy2_samples.append((sync, x, y))
            if not sync:
                # The end of the run_for() step in which the frame ended.
                self.parity_times.append(self.now)

    async def _laser_recorder(self, ctx):
        top = self.top
        while True:
            self.laser_pins.append((ctx.get(top.laser_mo), ctx.get(top.laser_am),
                                    ctx.get(top.laser_prr), ctx.get(top.interlock_open),
                                    ctx.get(top.laser_latch), ctx.get(top.laser_power),
                                    ctx.get(top.laser_enable),
                                    ctx.get(top.laser_alarm) if hasattr(top, "laser_alarm")
                                    else 0, ctx.get(top.laser_guide)))
            self.sync_pins.append(ctx.get(top.xy2_sync))
            await ctx.tick()

    async def _interlock(self, ctx):
        # The interlock loop and the laser's alarm outputs; a test opens or closes the loop by
        # setting `interlock_closed`, raises every alarm by clearing `alarms_clear`.
        alarm = getattr(self.top, "laser_alarm", None)
        while True:
            ctx.set(self.top.interlock_open, 0 if self.interlock_closed else 1)
            if alarm is not None:
                ctx.set(alarm, 0 if self.alarms_clear else 2 ** len(alarm) - 1)
            await ctx.delay(1e-6)

    async def _uart_host_tx(self, ctx):
        ctx.set(self.top.uart_rx, 1)
        while True:
            if not self.uart_to_board:
                await ctx.delay(self.bit_time)
                continue
            item = self.uart_to_board.popleft()
            stop = 1
            if isinstance(item, tuple):
                kind, value = item
                if kind == "pause":
                    await ctx.delay(value)
                    continue
                assert kind == "bad_stop"
                item, stop = value, 0
            for level in [0, *((item >> i) & 1 for i in range(8)), stop]:
                ctx.set(self.top.uart_rx, level)
                await ctx.delay(self.bit_time)
            ctx.set(self.top.uart_rx, 1)
            if not stop:
                await ctx.delay(self.bit_time)   # let the line idle after a break

    async def _uart_host_rx(self, ctx):
        while True:
            await ctx.negedge(self.top.uart_tx)
            await ctx.delay(self.bit_time * 1.5)
            value = 0
            for i in range(8):
                value |= ctx.get(self.top.uart_tx) << i
                await ctx.delay(self.bit_time)
            if ctx.get(self.top.uart_tx):
                self.uart_from_board.append(value)
            else:
                self.uart_framing_errors += 1

    async def _spi_host(self, ctx):
        top = self.top
        ctx.set(top.spi_cs_n, 1)
        while True:
            if not self.spi_queue:
                await ctx.delay(5e-6)
                continue
            bits, results, half_period, phase = self.spi_queue.popleft()
            if phase:
                await ctx.delay(phase)      # the host's clock is not the board's
            ctx.set(top.spi_cs_n, 0)
            for bit in bits:
                ctx.set(top.spi_copi, bit)
                await ctx.delay(half_period)
                ctx.set(top.spi_sck, 1)
                results.append(ctx.get(top.spi_cipo))
                await ctx.delay(half_period)
                ctx.set(top.spi_sck, 0)
            await ctx.delay(half_period)
            ctx.set(top.spi_cs_n, 1)
            await ctx.delay(4 * half_period)
            results.append("done")

    # --- driving the simulation ------------------------------------------------------------------

    def run_for(self, seconds):
        if seconds <= 0:
            return
        self.now += seconds
        self.sim.run_until(self.now)

    def run_until(self, condition, *, timeout, step=50e-6):
        waited = 0.0
        while not condition():
            if waited > timeout:
                raise TimeoutError(f"simulated {timeout * 1e3:.1f} ms without an answer")
            self.run_for(step)
            waited += step

    LASER_PIN_NAMES = ("laser_mo", "laser_am", "laser_prr", "interlock_open", "laser_latch",
                       "laser_power", "laser_enable", "laser_alarm", "laser_guide")

    def top_pin(self, name):
        """A laser pin's value on the last clock recorded (``record_laser=True``)."""
        return self.laser_pins[-1][self.LASER_PIN_NAMES.index(name)]

    def xy2_frames(self):
        """All XY2-100 frames so far, decoded by the tests' reader, with the time each ended."""
        complete = len(self.parity_times) * 20
        frames = frames_from_samples(self.xy2_samples[:complete])
        return list(zip(self.parity_times, frames))

    def frames_after(self, t):
        return [frame for end, frame in self.xy2_frames() if end > t]


class SimUARTTransport:
    """Frames as bytes on ``uart_rx``; answers read off ``uart_tx``. A pause of more than three
    character times follows every frame, as a careful host leaves."""

    def __init__(self, board, *, pause_chars=4):
        self.board = board
        self.pause = pause_chars * 10 * board.bit_time

    def queue(self, data, *, pause=True):
        """Add bytes to what the host sends, with or without the pause that ends a frame."""
        self.board.uart_to_board.extend(data)
        if pause:
            self.board.uart_to_board.append(("pause", self.pause))

    def flush(self):
        """Run until everything queued has gone out (and the decoder has seen it)."""
        character = 10 * self.board.bit_time
        self.board.run_until(lambda: not self.board.uart_to_board, timeout=0.1, step=character)
        self.board.run_for(12 * self.board.bit_time)

    def send_bytes(self, data, *, pause=True):
        self.queue(data, pause=pause)
        self.flush()

    def write_frame(self, frame):
        self.send_bytes(frame)

    def query(self, frame):
        received = len(self.board.uart_from_board)
        self.send_bytes(frame)
        self.board.run_until(lambda: len(self.board.uart_from_board) >= received + 4,
                             timeout=0.01)
        return bytes(self.board.uart_from_board[received:received + 4])


class SimSPITransport:
    """Frames clocked in on ``spi_copi`` with SCK at ``clk_freq / clocks_per_sck``; the answer
    to a read is clocked out during the next frame (a read of ``errors``)."""

    def __init__(self, board, *, clocks_per_sck=12, phase=0.37):
        self.board = board
        self.half_period = clocks_per_sck / board.clk_freq / 2
        # Offset of the host's SCK edges from the board's clock edges, in board clocks.
        self.phase = phase / board.clk_freq

    def transfer_bits(self, bits):
        results = []
        self.board.spi_queue.append((list(bits), results, self.half_period, self.phase))
        self.board.run_until(lambda: results and results[-1] == "done", timeout=0.01)
        return results[:-1]

    def transfer(self, frame):
        bits = [(byte >> (7 - i)) & 1 for byte in frame for i in range(8)]
        got = self.transfer_bits(bits)
        return bytes(int("".join(map(str, got[i:i + 8])), 2) for i in range(0, 32, 8))

    def write_frame(self, frame):
        self.transfer(frame)

    def query(self, frame):
        from galvoscan.client import FTDISPITransport
        self.transfer(frame)
        return self.transfer(FTDISPITransport.FETCH)
