"""The compiled backend of the simulated board: the system top as native code with the board
of ``board.cc`` around it, behind the engine contract both backends keep
(:class:`galvoscan.sim.contract.Engine`), so that a
:class:`~galvoscan.sim.board.SimulatedBoard` keeps the same records whichever runs it."""

import ctypes

from ..contract import LASER_PINS, SPI_IDLE_S
from ..xy2_receiver import XY2ProtocolError
from .model import compiled_model


__all__ = ["CompiledEngine"]


def _fs(seconds):
    """A delay in femtoseconds, rounded as Amaranth rounds a testbench's delay."""
    return round(float(seconds) * 1e15)


# The board's records (gs_board_take, board.cc's Record), its flags and its queue's items.
(FRAMES, SYNC_RISES, PULSES, LASER_CHANGES, BYTES_IN, BYTES_OUT, XY2_SAMPLES, PIN_CHANGES,
 SPI_RESULTS, Z_FRAMES, IO_CHANGES) = range(11)
RECORD_SAMPLES, RECORD_PINS = 1, 2
BAD_STOP = 0x100
SPI_DONE = 2


class CompiledEngine:
    """``board.top`` compiled (built and cached at the first use of its design)."""

    name = "compiled"

    def __init__(self, board, *, record_samples=False, record_pins=False, model=None,
                 say=None):
        if record_pins == "every clock":
            raise ValueError("pins sampled on every clock are the Python backend's (the "
                             "check of the recording by changes)")
        self.board = board
        self.model = model or compiled_model(board.top, say=say)
        self._lib = self.model.lib
        self._flags = (RECORD_SAMPLES if record_samples else 0) | \
                      (RECORD_PINS if record_pins else 0)
        self._buffer = (ctypes.c_int64 * 65536)()
        self._handle = None
        self.reset()

    def reset(self):
        """Back to power-up: a new board around the same model."""
        self.close()
        board = self.board
        period_fs = int(1 / board.clk_freq * 1e15)      # as Simulator.add_clock takes it
        timing = (ctypes.c_int64 * 6)(int(1 / board.clk_freq / 2 * 1e15), period_fs // 2,
                                      _fs(board.bit_time), _fs(1.5 * board.bit_time),
                                      _fs(board.machine_period_s), _fs(SPI_IDLE_S))
        self._handle = self._lib.gs_board_new(timing, self._flags)
        if not self._handle:
            raise MemoryError("no memory for the compiled board")
        if board.flash is not None:
            memory = bytes(board.flash.memory)
            if self._lib.gs_board_flash(self._handle, 0, memory, len(memory),
                                        int(board.flash.powered_down)) != 0:
                raise ValueError("the compiled model has no flash: it was built without "
                                 "the job player")
        self._machine_sent = None   # the machine's inputs as last handed to the model
        self._io_sent = 0           # the inputs io_in likewise (the model's: 0)
        self._head_sent = ()        # the head's word likewise (none yet: the model's is -1)
        self._belt_sent = (0, "x")  # the belt's rate and axis likewise (the model's: still)
        self._status = (ctypes.c_int64 * 4)()
        self._counted = (0, 0)      # UART items and SPI transfers started, as last counted
        self._given = 0          # items of board.to_board already handed to the model
        self._spi_given = 0      # transfers of board.spi_queue likewise
        self._spi_results = []   # the result lists of the transfers handed over, in order

    def _items(self, items):
        for item in items:
            if isinstance(item, tuple):
                kind, value = item
                yield -_fs(value) if kind == "pause" else BAD_STOP | value
            else:
                yield item

    def run_until(self, seconds):
        lib, handle, board = self._lib, self._handle, self.board
        if self._given < len(board.to_board):
            fresh = list(self._items(list(board.to_board)[self._given:]))
            lib.gs_board_send(handle, (ctypes.c_int64 * len(fresh))(*fresh), len(fresh))
            self._given = len(board.to_board)
        if self._spi_given < len(board.spi_queue):
            for bits, results, half_period, phase in list(board.spi_queue)[self._spi_given:]:
                bits = bytes(bits)
                lib.gs_board_spi(handle, bits, len(bits), _fs(half_period), _fs(phase))
                self._spi_results.append(results)
            self._spi_given = len(board.spi_queue)
        # (The inputs only when they change: a host polling in steps of a UART bit runs the
        # board hundreds of thousands of times, and each call here costs more than a clock.)
        machine = (bool(board.interlock_closed), bool(board.alarms_clear),
                   bool(board.start_pressed))
        if machine != self._machine_sent:
            lib.gs_board_machine(handle, int(machine[0]), int(machine[1]))
            lib.gs_board_start(handle, int(machine[2]))
            self._machine_sent = machine
        if board.io_inputs != self._io_sent:
            lib.gs_board_io(handle, board.io_inputs & 0b11)
            self._io_sent = board.io_inputs
        belt = board.belt
        if (belt.counts_per_s, belt.axis) != self._belt_sent or belt.glitch_periods:
            self._belt_sent = (belt.counts_per_s, belt.axis)
            lib.gs_board_belt(handle, belt.counts_per_s, "xy".index(belt.axis),
                              belt.glitch_periods)
            belt.glitch_periods = 0
        if board.head_word != self._head_sent:
            lib.gs_board_head(handle, -1 if board.head_word is None else board.head_word)
            self._head_sent = board.head_word
        status, (started, transfers) = self._status, self._counted
        outcome = lib.gs_board_run_until(handle, int(seconds * 1e15))
        if self._belt_sent[0]:
            # (The count as the model left it: a rate of the same value changes nothing.)
            belt.count = lib.gs_board_belt(handle, belt.counts_per_s, "xy".index(belt.axis), 0)
        lib.gs_board_status(handle, status)
        for _ in range(status[0] - started):
            board.to_board.popleft()
            self._given -= 1
        for _ in range(status[2] - transfers):
            board.spi_queue.popleft()
            self._spi_given -= 1
        self._counted = (status[0], status[2])
        board.framing_errors = status[1]
        if status[3]:
            self._take_records(status[3])
        if outcome != 0:
            raise XY2ProtocolError(lib.gs_board_message(handle).decode())

    def _take(self, which):
        lib, handle, buffer = self._lib, self._handle, self._buffer
        values = []
        while True:
            n = lib.gs_board_take(handle, which, buffer, len(buffer))
            values.extend(buffer[:n])
            if n < len(buffer):
                return values

    def _take_records(self, pending):
        """The records whose bits are set in ``pending``, appended to the board's."""
        board = self.board
        if pending & 1 << FRAMES:
            values = self._take(FRAMES)
            board.frames.extend(zip(values[0::3], values[1::3], values[2::3]))
        if pending & 1 << SYNC_RISES:
            board.sync_rises.extend(self._take(SYNC_RISES))
        if pending & 1 << PULSES:
            board.pulses.extend(self._take(PULSES))
        if pending & 1 << LASER_CHANGES:
            values = self._take(LASER_CHANGES)
            for cycle, pins in zip(values[0::2], values[1::2]):
                board.laser_changes.append(
                    (cycle, tuple((pins >> i) & 1 for i in range(len(LASER_PINS)))))
        if pending & 1 << BYTES_IN:
            values = self._take(BYTES_IN)
            board.bytes_in.extend(zip(values[0::2], values[1::2]))
        if pending & 1 << BYTES_OUT:
            board.from_board.extend(self._take(BYTES_OUT))
        if pending & 1 << XY2_SAMPLES:
            values = self._take(XY2_SAMPLES)
            board.xy2_samples.extend((cycle, bits & 1, (bits >> 1) & 1, (bits >> 2) & 1)
                                     for cycle, bits in zip(values[0::2], values[1::2]))
        if pending & 1 << PIN_CHANGES:
            values = self._take(PIN_CHANGES)
            board.pin_changes.extend(zip(values[0::2], values[1::2]))
        if pending & 1 << Z_FRAMES:
            values = self._take(Z_FRAMES)
            board.z_frames.extend(zip(values[0::2], values[1::2]))
        if pending & 1 << IO_CHANGES:
            values = self._take(IO_CHANGES)
            board.io_changes.extend(zip(values[0::2], values[1::2]))
        if pending & 1 << SPI_RESULTS:
            for value in self._take(SPI_RESULTS):
                if value == SPI_DONE:
                    self._spi_results.pop(0).append("done")
                else:
                    self._spi_results[0].append(value)

    def flash_counts(self):
        """``(carried out, ignored)``: the flash's instructions so far."""
        return self._lib.gs_board_counter(self._handle, 5), \
            self._lib.gs_board_counter(self._handle, 6)

    def crash(self):
        """Make the model fail as a broken one would (for the test of what the user then
        sees: one line, and the process gone)."""
        self._lib.gs_board_crash(self._handle)

    def close(self):
        if self._handle:
            self._lib.gs_board_free(self._handle)
            self._handle = None

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass
