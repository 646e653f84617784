"""Replay the spiral through the system top in the Amaranth simulator, reading the XY2-100 wires.

The top is built with the spiral mode only (``modes=("spiral",)``), which simulates faster.

The design is simulated at a system clock of twice the bit rate (4 MHz for 2 Mbit/s), the
smallest ratio the PHY allows: the frames on the wires are the same as at the board's 12 MHz
(the PHY proofs cover both ratios), and the simulation runs three times faster.
"""

import contextlib
import csv

from amaranth.sim import Simulator

from ..gateware.top import GalvoScanTop
from .board import SimulatedBoard
from .compiled import CompileError
from .xy2_receiver import XY2Frame, XY2Receiver


__all__ = ["SIM_CLOCKS_PER_BIT", "replay_spiral", "write_csv"]


#: System clocks per XY2 bit in simulation.
SIM_CLOCKS_PER_BIT = 2


def replay_spiral(*, frames, table=None, settings=None, bit_rate=2_000_000, vcd=None,
                  progress=None, correction="identity", backend="python", say=None,
                  netlist=None):
    """Simulate the system top and return the first ``frames`` frames read off the wires.

    Parameters
    ----------
    frames : int
        Frames to collect, counted from power-up (the first ``PARK_FRAMES`` are the park
        position).
    table, settings, correction
        As for :class:`~galvoscan.gateware.top.GalvoScanTop`.
    vcd : path, optional
        Write a waveform of the whole run.
    progress : callable, optional
        Called with the number of new frames as they arrive (for a progress bar).
    backend : str
        ``"python"`` (Amaranth's simulator) or ``"compiled"``/``"auto"``: the simulated board's
        (:class:`~galvoscan.sim.board.SimulatedBoard`), which writes no waveform; ``say``
        is told about its compile.
    netlist : path, optional
        A build's folder: the frames off the wires of its synthesized netlist, gate by gate
        (the compiled backend; ``table``, ``settings`` and ``correction`` are the build's).

    Returns
    -------
    list of :class:`~galvoscan.sim.xy2_receiver.XY2Frame`
    """
    if frames < 1:
        raise ValueError(f"frames must be at least 1, not {frames}")
    clk_freq = SIM_CLOCKS_PER_BIT * bit_rate
    if netlist is not None:
        return _replay_on_board(frames=frames, clk_freq=None, progress=progress,
                                backend="compiled", say=say, netlist=netlist)
    if backend != "python":
        if vcd:
            raise ValueError("a waveform (vcd) needs the Python backend")
        try:
            return _replay_on_board(frames=frames, clk_freq=clk_freq, progress=progress,
                                    backend="compiled", say=say, bit_rate=bit_rate,
                                    table=table, settings=settings, modes=("spiral",),
                                    correction=correction)
        except CompileError as error:
            if backend == "compiled":
                raise
            # (auto: the lean replay below, not the whole board on Amaranth's simulator.)
            (say or (lambda line: None))(
                f"the compiled simulator is not available ({error}); using Amaranth's "
                f"simulator, some 200 times slower")
    # The spiral alone: the other modes, idle, change none of its frames (the tests replay
    # the full build too), and leaving them out makes the simulation half again as fast.
    top = GalvoScanTop(clk_freq=clk_freq, bit_rate=bit_rate, table=table, settings=settings,
                       modes=("spiral",), correction=correction)
    sim = Simulator(top)
    sim.add_clock(1 / clk_freq)

    received = []
    receiver = XY2Receiver()

    async def scan_head(ctx):
        samples = ctx.negedge(top.xy2_clk).sample(top.xy2_sync, top.xy2_x, top.xy2_y)
        async for _clk, sync, x, y in samples:
            frame = receiver.sample(sync, x, y)
            if frame is not None:
                received.append(frame)
                if progress is not None:
                    progress(1)
                if len(received) == frames:
                    return

    sim.add_testbench(scan_head)
    with sim.write_vcd(vcd) if vcd else contextlib.nullcontext():
        sim.run()
    return received


def _replay_on_board(*, frames, clk_freq, progress, backend, say, **top_kwargs):
    """The first ``frames`` frames off the simulated board's wires (the compiled backend)."""
    if top_kwargs.get("netlist"):
        board = SimulatedBoard(backend=backend, say=say, **top_kwargs)
    else:
        board = SimulatedBoard(clk_freq=clk_freq, baud=None, backend=backend, say=say,
                               **top_kwargs)
    try:
        if progress is not None:
            progress(0)                         # (the model is built: the run starts here)
        frame_time = 20e-6                      # two XY2-100 frames
        while len(board.frames) < frames:
            seen = len(board.frames)
            # Some 1000 frames a step: one call into the model each.
            board.run_for(min(1000, frames - seen + 1) * frame_time)
            if progress is not None and len(board.frames) > seen:
                progress(min(len(board.frames), frames) - seen)
        return [XY2Frame(x, y) for _, x, y in board.frames[:frames]]
    finally:
        board.close()


def write_csv(path, frames):
    """One row per frame: ``frame,x,y`` (galvo units)."""
    with open(path, "w", newline="") as f:
        out = csv.writer(f)
        out.writerow(["frame", "x", "y"])
        for index, frame in enumerate(frames):
            out.writerow([index, frame.x, frame.y])
