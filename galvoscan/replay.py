"""Replay the spiral through the system top in the Amaranth simulator, reading the XY2-100 wires.

The top is built with the spiral mode only (``modes=("spiral",)``), which simulates faster.

The design is simulated at a system clock of twice the bit rate (4 MHz for 2 Mbit/s), the
smallest ratio the PHY allows: the frames on the wires are the same as at the board's 12 MHz
(the PHY proofs cover both ratios), and the simulation runs three times faster.
"""

import contextlib
import csv

from amaranth.sim import Simulator

from .gateware.top import GalvoScanTop
from .xy2_receiver import XY2Receiver


__all__ = ["SIM_CLOCKS_PER_BIT", "replay_spiral", "write_csv", "plot_path", "plot_job"]


#: System clocks per XY2 bit in simulation.
SIM_CLOCKS_PER_BIT = 2


def replay_spiral(*, frames, table=None, settings=None, bit_rate=2_000_000, vcd=None,
                  progress=None, correction="identity"):
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

    Returns
    -------
    list of :class:`~galvoscan.xy2_receiver.XY2Frame`
    """
    if frames < 1:
        raise ValueError(f"frames must be at least 1, not {frames}")
    clk_freq = SIM_CLOCKS_PER_BIT * bit_rate
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


def write_csv(path, frames):
    """One row per frame: ``frame,x,y`` (galvo units)."""
    with open(path, "w", newline="") as f:
        out = csv.writer(f)
        out.writerow(["frame", "x", "y"])
        for index, frame in enumerate(frames):
            out.writerow([index, frame.x, frame.y])


def plot_path(path, frames, *, title="Simulated XY2-100 output"):
    """Plot the path through the frames' positions over the whole field."""
    import matplotlib
    matplotlib.use("Agg")
    from matplotlib import pyplot as plt

    xs = [f.x for f in frames]
    ys = [f.y for f in frames]
    fig, ax = plt.subplots(figsize=(6, 6), dpi=120)
    ax.plot(xs, ys, linewidth=0.25, color="tab:blue")
    ax.plot(xs, ys, ".", markersize=0.8, color="black")
    ax.set_xlim(0, 65535)
    ax.set_ylim(0, 65535)
    ax.set_aspect("equal")
    ax.set_xlabel("X (galvo units)")
    ax.set_ylabel("Y (galvo units)")
    ax.set_title(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def plot_job(path, result, *, title):
    """Plot a vector job's path: jumps grey, marked points coloured by their pulses."""
    import matplotlib
    matplotlib.use("Agg")
    from matplotlib import pyplot as plt

    points = result.points
    xs = [p[0] for p in points]
    ys = [p[1] for p in points]
    fig, ax = plt.subplots(figsize=(6, 6), dpi=120)
    ax.plot(xs, ys, linewidth=0.4, color="lightgrey")
    marked = [p for p in points if p[2]]
    if marked:
        dots = ax.scatter([p[0] for p in marked], [p[1] for p in marked],
                          c=[p[2] for p in marked], s=4, cmap="viridis")
        fig.colorbar(dots, ax=ax, label="pulses on the point", shrink=0.8)
    ax.set_aspect("equal")
    ax.set_xlabel("X (galvo units)")
    ax.set_ylabel("Y (galvo units)")
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
