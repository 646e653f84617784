"""The compiled backend of the simulated board: the system top as native code with the board
of ``board.cc`` around it, behind the same engine interface as the Python one
(:class:`galvoscan.sim.board_engine.PythonEngine`), so that a
:class:`~galvoscan.sim.board.SimulatedBoard` keeps the same records whichever runs it."""

import ctypes

from ..sim.board_engine import LASER_PINS, MACHINE_PERIOD_S
from ..sim.xy2_receiver import XY2ProtocolError
from .model import compiled_model


__all__ = ["CompiledEngine"]


def _fs(seconds):
    """A delay in femtoseconds, rounded as Amaranth rounds a testbench's delay."""
    return round(float(seconds) * 1e15)


# The board's records (gs_board_take) and how many values each entry has.
FRAMES, SYNC_RISES, PULSES, LASER_CHANGES, BYTES_IN, BYTES_OUT = range(6)
WIDTH = {FRAMES: 3, SYNC_RISES: 1, PULSES: 1, LASER_CHANGES: 2, BYTES_IN: 2, BYTES_OUT: 1}


class CompiledEngine:
    """``board.top`` compiled (built and cached at the first use of its design)."""

    name = "compiled"

    def __init__(self, board, *, model=None, say=None):
        self.board = board
        self.model = model or compiled_model(board.top, say=say)
        self._lib = self.model.lib
        period_fs = int(1 / board.clk_freq * 1e15)      # as Simulator.add_clock takes it
        timing = (ctypes.c_int64 * 5)(int(1 / board.clk_freq / 2 * 1e15), period_fs // 2,
                                      _fs(board.bit_time), _fs(1.5 * board.bit_time),
                                      _fs(MACHINE_PERIOD_S))
        self._handle = self._lib.gs_board_new(timing)
        if not self._handle:
            raise MemoryError("no memory for the compiled board")
        self._given = 0          # bytes of board.to_board already handed to the model
        self._buffer = (ctypes.c_int64 * 65536)()

    def run_until(self, seconds):
        lib, handle, board = self._lib, self._handle, self.board
        if self._given < len(board.to_board):
            fresh = bytes(list(board.to_board)[self._given:])
            lib.gs_board_send(handle, fresh, len(fresh))
            self._given = len(board.to_board)
        lib.gs_board_machine(handle, int(bool(board.interlock_closed)),
                             int(bool(board.alarms_clear)))
        started = lib.gs_board_counter(handle, 0)
        outcome = lib.gs_board_run_until(handle, int(seconds * 1e15))
        for _ in range(lib.gs_board_counter(handle, 0) - started):
            board.to_board.popleft()
            self._given -= 1
        board.framing_errors = lib.gs_board_counter(handle, 1)
        self._take_records()
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

    def _take_records(self):
        board = self.board
        values = self._take(FRAMES)
        board.frames.extend(zip(values[0::3], values[1::3], values[2::3]))
        board.sync_rises.extend(self._take(SYNC_RISES))
        board.pulses.extend(self._take(PULSES))
        values = self._take(LASER_CHANGES)
        for cycle, pins in zip(values[0::2], values[1::2]):
            board.laser_changes.append(
                (cycle, tuple((pins >> i) & 1 for i in range(len(LASER_PINS)))))
        values = self._take(BYTES_IN)
        board.bytes_in.extend(zip(values[0::2], values[1::2]))
        board.from_board.extend(self._take(BYTES_OUT))

    def close(self):
        if self._handle:
            self._lib.gs_board_free(self._handle)
            self._handle = None

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass
