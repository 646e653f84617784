"""The Python backend of the simulated board: the system top in Amaranth's simulator, its pins
driven and recorded by Amaranth processes (the reference the compiled backend is checked
against, :mod:`galvoscan.compiled`).

An engine moves a :class:`~.board.SimulatedBoard` on to a time of its own: it takes the bytes
the host queued on ``board.to_board`` as their start bits begin, and appends to the board's
records what the pins did. Every process here wakes at fixed instants (a UART bit, 10 µs for
the machine's pins) or on a pin's edge, so that the compiled board can wake at the same ones.
"""

from amaranth.sim import Simulator

from .link import Timed
from .xy2_receiver import XY2Receiver


__all__ = ["PythonEngine", "LASER_PINS", "MACHINE_PERIOD_S"]


# The laser pins recorded at every change, in this order.
LASER_PINS = ("laser_enable", "laser_mo", "laser_am", "laser_prr", "laser_latch", "laser_guide")

#: How often the machine's interlock and alarm pins are set from the board's attributes.
MACHINE_PERIOD_S = 10e-6


class PythonEngine:
    """Amaranth's simulator of ``board.top``."""

    name = "python"

    def __init__(self, board):
        self.board = board
        top = board.top
        self._timed = Timed(top)
        self.sim = Simulator(self._timed)
        self.sim.add_clock(1 / board.clk_freq)
        self._receiver = XY2Receiver()
        for process in (self._uart_in, self._uart_out, self._scan_head, self._sync_edges,
                        self._laser, self._machine):
            self.sim.add_testbench(process, background=True)
        # A process, not a testbench: the pins are logic, and may change more than once
        # while the design settles after a clock edge; a process sees every change.
        self.sim.add_process(self._laser_pins)

    def run_until(self, seconds):
        self.sim.run_until(seconds)

    def close(self):
        pass

    async def _uart_in(self, ctx):
        """The host's transmitter: each byte 8N1 on uart_rx, back to back."""
        board, rx = self.board, self.board.top.uart_rx
        ctx.set(rx, 1)
        while True:
            if not board.to_board:
                await ctx.delay(board.bit_time)
                continue
            byte = board.to_board.popleft()
            for level in (0, *((byte >> i) & 1 for i in range(8)), 1):
                ctx.set(rx, level)
                await ctx.delay(board.bit_time)
            board.bytes_in.append((ctx.get(self._timed.cycles), byte))

    async def _uart_out(self, ctx):
        """The host's receiver: a start bit's falling edge, then each bit in its middle."""
        board, tx = self.board, self.board.top.uart_tx
        while True:
            await ctx.negedge(tx)
            await ctx.delay(1.5 * board.bit_time)
            value = 0
            for i in range(8):
                value |= ctx.get(tx) << i
                await ctx.delay(board.bit_time)
            if ctx.get(tx):
                board.from_board.append(value)
            else:
                board.framing_errors += 1

    async def _scan_head(self, ctx):
        top = self.board.top
        async for _, sync, x, y, cycles in ctx.negedge(top.xy2_clk).sample(
                top.xy2_sync, top.xy2_x, top.xy2_y, self._timed.cycles):
            frame = self._receiver.sample(sync, x, y)
            if frame is not None:
                self.board.frames.append((cycles, frame.x, frame.y))

    async def _sync_edges(self, ctx):
        async for _, cycles in ctx.posedge(self.board.top.xy2_sync).sample(self._timed.cycles):
            self.board.sync_rises.append(cycles)

    async def _laser(self, ctx):
        top = self.board.top
        async for _, am, cycles in ctx.posedge(top.laser_prr).sample(top.laser_am,
                                                                      self._timed.cycles):
            if am:
                self.board.pulses.append(cycles)

    async def _laser_pins(self, ctx):
        pins = [getattr(self.board.top, name) for name in LASER_PINS]
        async for *values, cycles in ctx.changed(*pins).sample(self._timed.cycles):
            self.board.laser_changes.append((cycles, tuple(values)))

    async def _machine(self, ctx):
        # The interlock loop and the laser's alarm outputs, as the machine has them.
        board = self.board
        alarm = getattr(board.top, "laser_alarm", None)
        while True:
            ctx.set(board.top.interlock_open, 0 if board.interlock_closed else 1)
            if alarm is not None:
                ctx.set(alarm, 0 if board.alarms_clear else 2 ** len(alarm) - 1)
            await ctx.delay(MACHINE_PERIOD_S)
