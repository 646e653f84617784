"""The Python backend of the simulated board: the system top in Amaranth's simulator, its pins
driven and recorded by Amaranth processes (the reference the compiled backend is checked
against, :mod:`galvoscan.sim.compiled`).

An engine (:class:`~.contract.Engine`) moves a :class:`~.board.SimulatedBoard` on to a time of its own: it takes what the
host queued (``board.to_board``, ``board.spi_queue``) as it goes onto the pins, and appends to
the board's records what the pins did. Every process here wakes at fixed instants (a UART
bit, an SPI half period, the machine's period, 5 µs for an idle SPI host) or on a pin's
edge, so that the compiled board can wake at the same ones.
"""

from amaranth.hdl import C, ClockDomain, Elaboratable, Module, Signal
from amaranth.sim import Simulator

from .contract import LASER_PINS, PIN_FIELDS, SPI_IDLE_S, pack_pins
from .belt import advance, lines
from .head import status_frame_bits
from .xy2_receiver import XY2Receiver


__all__ = ["PythonEngine"]


class _Clocked(Elaboratable):
    """The top with its clock domain made here, so the clock is a signal to read, and a count
    of its rising edges."""

    def __init__(self, top):
        self.top = top
        self.sync = ClockDomain("sync")
        self.cycles = Signal(48)

    def elaborate(self, platform):
        m = Module()
        m.domains.sync = self.sync
        m.submodules.top = self.top
        m.d.sync += self.cycles.eq(self.cycles + 1)
        return m


class PythonEngine:
    """Amaranth's simulator of ``board.top``.

    ``record_pins`` ``"every clock"`` samples the pins on every clock instead of at their
    changes (the tests' check of the recording by changes; this backend only)."""

    name = "python"

    def __init__(self, board, *, record_samples=False, record_pins=False, vcd=None):
        self.board = board
        self._clocked = _Clocked(board.top)
        self.sim = Simulator(self._clocked)
        self.sim.add_clock(1 / board.clk_freq)
        self._record_samples = record_samples
        self._record_pins = record_pins
        self._add_processes()
        self._reserve_power_up()
        self._vcd = None
        if vcd:
            self._vcd = self.sim.write_vcd(vcd)
            self._vcd.__enter__()

    def _add_processes(self):
        self._receiver = XY2Receiver()
        self._z_receiver = XY2Receiver()
        for process in (self._uart_in, self._uart_out, self._spi_host, self._scan_head,
                        self._sync_edges, self._laser, self._machine):
            self.sim.add_testbench(process, background=True)
        if hasattr(self.board.top, "xy2_z"):
            self.sim.add_testbench(self._z_line, background=True)
        if hasattr(self.board.top, "io_out"):
            self.sim.add_testbench(self._io_outputs, background=True)
        if self.board.flash is not None:
            self.sim.add_testbench(self._flash, background=True)
        if hasattr(self.board.top, "xy2_status"):
            self.sim.add_testbench(self._head_status, background=True)
        # A process, not a testbench: the pins are logic, and may change more than once
        # while the design settles after a clock edge; a process sees every change.
        self.sim.add_process(self._laser_pins)
        if self._record_pins == "every clock":
            self.sim.add_testbench(self._pins_every_clock, background=True)
        elif self._record_pins:
            self.sim.add_testbench(self._pins_at_power_up)
            self.sim.add_process(self._pin_changes)

    def run_until(self, seconds):
        self.sim.run_until(seconds)

    def reset(self):
        """Back to power-up: every signal and memory to its initial value, every process
        started again (a millisecond, where building the simulator is half a second)."""
        self.sim.reset()
        self._receiver = XY2Receiver()
        self._z_receiver = XY2Receiver()
        self._reserve_power_up()

    def _reserve_power_up(self):
        # The power-up entry comes first, though the process that records the changes may see
        # one at t = 0 before the testbench that reads the pins at power-up has run.
        if self._record_pins and self._record_pins != "every clock":
            self.board.pin_changes.append(None)

    def close(self):
        if self._vcd is not None:
            vcd, self._vcd = self._vcd, None
            vcd.__exit__(None, None, None)

    # --- the host --------------------------------------------------------------------------------

    async def _uart_in(self, ctx):
        """The host's transmitter: each byte 8N1 on uart_rx, back to back; a ``("pause", s)``
        item idles the line, a ``("bad_stop", byte)`` one sends the byte with its stop bit low
        and lets the line idle a bit after."""
        board, rx = self.board, self.board.top.uart_rx
        ctx.set(rx, 1)
        while True:
            if not board.to_board:
                await ctx.delay(board.bit_time)
                continue
            item = board.to_board.popleft()
            stop = 1
            if isinstance(item, tuple):
                kind, value = item
                if kind == "pause":
                    await ctx.delay(value)
                    continue
                item, stop = value, 0
            for level in (0, *((item >> i) & 1 for i in range(8)), stop):
                ctx.set(rx, level)
                await ctx.delay(board.bit_time)
            ctx.set(rx, 1)
            if not stop:
                await ctx.delay(board.bit_time)
                continue
            board.bytes_in.append((ctx.get(self._clocked.cycles), item))

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

    async def _spi_host(self, ctx):
        """The SPI host: mode 0, each transfer's bits at its own SCK rate, CIPO sampled as SCK
        rises, then cs_n high for four half periods; ``"done"`` ends its results."""
        board, top = self.board, self.board.top
        ctx.set(top.spi_cs_n, 1)
        while True:
            if not board.spi_queue:
                await ctx.delay(SPI_IDLE_S)
                continue
            bits, results, half_period, phase = board.spi_queue.popleft()
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

    async def _machine(self, ctx):
        # The interlock loop and the laser's alarm outputs, as the machine has them, the foot
        # switch, and the belt's encoder (:mod:`.belt`).
        board = self.board
        alarm = getattr(board.top, "laser_alarm", None)
        start = getattr(board.top, "start_n", None)
        io_in = getattr(board.top, "io_in", None)
        fly = hasattr(board.top, "encoder_x_a")
        period_fs = round(float(board.machine_period_s) * 1e15)
        while True:
            if fly:
                belt = board.belt
                belt.count, belt.fraction = advance(belt.count, belt.fraction,
                                                    belt.counts_per_s, period_fs)
                a, b = lines(belt.count, inverted=belt.glitch_periods > 0)
                belt.glitch_periods = max(0, belt.glitch_periods - 1)
                for axis in "xy":
                    on = axis == belt.axis
                    ctx.set(getattr(board.top, f"encoder_{axis}_a"), a if on else 0)
                    ctx.set(getattr(board.top, f"encoder_{axis}_b"), b if on else 0)
            ctx.set(board.top.interlock_open, 0 if board.interlock_closed else 1)
            if alarm is not None:
                ctx.set(alarm, 0 if board.alarms_clear else 2 ** len(alarm) - 1)
            if start is not None:
                ctx.set(start, 0b10 if board.start_pressed else 0b11)
            if io_in is not None:
                ctx.set(io_in, board.io_inputs & 0b11)
            await ctx.delay(board.machine_period_s)

    async def _flash(self, ctx):
        # The configuration flash, at each change of its /CS and SCK.
        board, top = self.board, self.board.top
        period = 1 / board.clk_freq
        async for cs_n, sck in ctx.changed(top.flash_cs_n, top.flash_clk):
            cipo = board.flash.pins(cs_n, sck, ctx.get(top.flash_copi),
                                    ctx.get(self._clocked.cycles) * period)
            ctx.set(top.flash_cipo, cipo)

    # --- the scan head and the laser ---------------------------------------------------------------

    async def _scan_head(self, ctx):
        board, top = self.board, self.board.top
        async for _, sync, x, y, cycles in ctx.negedge(top.xy2_clk).sample(
                top.xy2_sync, top.xy2_x, top.xy2_y, self._clocked.cycles):
            if self._record_samples:
                board.xy2_samples.append((cycles, sync, x, y))
            frame = self._receiver.sample(sync, x, y)
            if frame is not None:
                board.frames.append((cycles, frame.x, frame.y))

    async def _z_line(self, ctx):
        # The Z line's frames, by the same receiver as X and Y's (Z on both of its inputs).
        board, top = self.board, self.board.top
        async for _, sync, z, cycles in ctx.negedge(top.xy2_clk).sample(
                top.xy2_sync, top.xy2_z, self._clocked.cycles):
            frame = self._z_receiver.sample(sync, z, z)
            if frame is not None:
                board.z_frames.append((cycles, frame.x))

    async def _io_outputs(self, ctx):
        # The outputs io_out, at each change, with the clock count it came with.
        board, top = self.board, self.board.top
        async for outputs, in ctx.changed(top.io_out):
            if outputs != (board.io_changes[-1][1] if board.io_changes else 0):
                board.io_changes.append((ctx.get(self._clocked.cycles), outputs))

    async def _head_status(self, ctx):
        # The head's STATUS line (:mod:`.head`): a bit on each rising CLOCK edge, from the one
        # on which SYNC is first high; low with no head (``head_word`` None).
        board, top = self.board, self.board.top
        bit, last_sync, word = None, True, None
        async for _, sync in ctx.posedge(top.xy2_clk).sample(top.xy2_sync):
            bit = 0 if sync and not last_sync else (None if bit is None else bit + 1)
            last_sync = sync
            if bit == 0:            # (a head takes its word for a whole frame)
                word = board.head_word
            level = 0
            if word is not None and bit is not None and bit < len(self._head_bits(word)):
                level = self._head_bits(word)[bit]
            ctx.set(top.xy2_status, level)

    def _head_bits(self, word):
        if word != getattr(self, "_head_word", None):
            self._head_word, self._head_frame = word, status_frame_bits(word)
        return self._head_frame

    async def _sync_edges(self, ctx):
        async for _, cycles in ctx.posedge(self.board.top.xy2_sync).sample(
                self._clocked.cycles):
            self.board.sync_rises.append(cycles)

    async def _laser(self, ctx):
        top = self.board.top
        async for _, am, cycles in ctx.posedge(top.laser_prr).sample(top.laser_am,
                                                                      self._clocked.cycles):
            if am:
                self.board.pulses.append(cycles)

    async def _laser_pins(self, ctx):
        # The pins once the design has settled at an instant, as the compiled board and a
        # scope see them: the laser's inputs pass through synchronizers, so nothing the host
        # or the machine sets moves a laser pin at the instant it is set, and changes seen at
        # one instant are the deltas of one settle (a pin whose logic is one delta shorter
        # than another's is not a state the pins are ever in).
        pins = [getattr(self.board.top, name) for name in LASER_PINS]
        changes, engine = self.board.laser_changes, self.sim._engine
        last_instant = None
        async for *values, cycles in ctx.changed(*pins).sample(self._clocked.cycles):
            values = tuple(values)
            if engine.now == last_instant and changes:
                changes.pop()
            last_instant = engine.now
            if not changes or changes[-1][1] != values:
                changes.append((cycles, values))

    def _pins(self):
        top = self.board.top
        return [getattr(top, name) if hasattr(top, name) else C(0, 1)
                for name, _first, _width in PIN_FIELDS]

    async def _pins_at_power_up(self, ctx):
        self.board.pin_changes[0] = (0, pack_pins([ctx.get(pin) for pin in self._pins()]))

    async def _pin_changes(self, ctx):
        # Clock k's entry is the pins once the design has settled after the k-th rising clock
        # edge (entry 0: at power-up, as _pins_at_power_up finds them). A process sees every
        # change, the last of a clock's the settled one: a change with clk high is on a rising
        # edge, that edge's clock; one with clk low (the host's interlock and alarm pins
        # change between edges) is first seen on the next edge.
        pins = self._pins()
        signals = [pin for pin in pins if isinstance(pin, Signal)]
        async for sampled in ctx.changed(*signals).sample(*pins, self._clocked.cycles,
                                                          self._clocked.sync.clk):
            *values, clock, clk = sampled[len(signals):]
            self.board.pin_changes.append((clock + (not clk), pack_pins(values)))

    async def _pins_every_clock(self, ctx):
        pins = self._pins()
        while True:
            self.board.pins_every_clock.append(pack_pins([ctx.get(pin) for pin in pins]))
            await ctx.tick()
