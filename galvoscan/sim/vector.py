"""Run a vector job on the simulated system top, as a host would, and read what comes out.

The job goes in through the SPI pins (frames from the host client's encoder, bit-banged at
the link's top speed, the queue topped up as ``fifo_free`` allows); the XY2-100 wires are
decoded as a scan head would; the laser's pulses are counted on the DB25 pins and given to
the point the head holds when they fire. Simulated at the board's 12 MHz (6 clocks per XY2
bit), so the timing is the board's.
"""

import contextlib

from amaranth.sim import Simulator

from ..client import encode_read, encode_write
from ..gateware.host.regmap import BY_NAME, Status
from ..gateware.top import GalvoScanTop, ScanSettings
from ..job import OPS
from .link import Timed, spi_transfer
from .xy2_receiver import XY2Receiver, frame_of_each_pulse


__all__ = ["JobResult", "replay_job"]


class JobResult:
    """What the head and the laser saw.

    Attributes
    ----------
    frames : list of (int, int, int)
        ``(x, y, pulses)`` per XY2-100 frame from power-up: the position, and the pulses that
        fell while the head held it.
    points : list of (int, int, int, int)
        ``(x, y, pulses, frames)`` per run of frames at one position.
    clk_freq : float
    """

    def __init__(self, frames, clk_freq):
        self.frames = frames
        self.clk_freq = clk_freq
        points = []
        for x, y, pulses in frames:
            if points and points[-1][:2] == [x, y]:
                points[-1][2] += pulses
                points[-1][3] += 1
            else:
                points.append([x, y, pulses, 1])
        self.points = [tuple(p) for p in points]

    def marked(self):
        """Points that got at least one pulse."""
        return [p for p in self.points if p[2] > 0]


def replay_job(job, *, prr_hz=60e3, pulses_per_point=1, pitch=60, jump_delay=500,
               clk_freq=12e6, mo_lead=5e-3, progress=None, correction="identity", vcd=None,
               backend="python", say=None):
    """Simulate ``job`` (a list of ``(op, x, y)``) and return a :class:`JobResult`.

    ``vcd``, a path, writes a waveform of the whole run; ``progress`` is called with the
    number of new frames as they reach the head. ``backend`` ``"compiled"`` or ``"auto"``
    runs it on the simulated board instead (:class:`~galvoscan.sim.board.SimulatedBoard`),
    streamed over its UART by the host's job streamer in the board's own time (``say`` is told
    about the compile); it writes no waveform.
    """
    prr = round(prr_hz / 100)
    if not BY_NAME["laser_prr"].low <= prr <= BY_NAME["laser_prr"].high:
        raise ValueError(f"PRR must be from 20 to 200 kHz, not {prr_hz:g} Hz")
    for name, value in (("pulses_per_point", pulses_per_point), ("pitch", pitch),
                        ("jump_delay", jump_delay)):
        reg = BY_NAME[name]
        if not isinstance(value, int) or not reg.low <= value <= reg.high:
            raise ValueError(f"{name} must be an integer from {reg.low} to {reg.high}, "
                             f"not {value!r}")
    registers = {"laser_prr": prr, "pulses_per_point": pulses_per_point, "pitch": pitch,
                 "jump_delay": jump_delay, "laser_power": 128,
                 # The longest watchdog: the simulated host is slow, not silent.
                 "watchdog": BY_NAME["watchdog"].high}
    if backend != "python":
        if vcd:
            raise ValueError("a waveform (vcd) needs the Python backend")
        return _replay_on_board(job, registers, clk_freq=clk_freq, mo_lead=mo_lead,
                                correction=correction, progress=progress, backend=backend,
                                say=say)
    top = GalvoScanTop(clk_freq=clk_freq, settings=ScanSettings(mode="vector", run=False),
                       mo_lead=mo_lead, correction=correction)
    timed = Timed(top)
    sim = Simulator(timed)
    sim.add_clock(1 / clk_freq)

    frame_ends = []                              # cycle a frame was complete, and its position
    sync_rises = []
    pulses = []

    async def spi_frame(ctx, frame):
        return await spi_transfer(ctx, top, frame, clk_freq)

    async def write(ctx, name, value):
        await spi_frame(ctx, encode_write(name, value))

    async def read(ctx, name):
        await spi_frame(ctx, encode_read(name))
        answer = await spi_frame(ctx, encode_read("errors"))    # clocks the answer out
        return (answer >> 8) & 0xFFFF

    async def host(ctx):
        ctx.set(top.interlock_open, 0)
        if hasattr(top, "laser_alarm"):
            ctx.set(top.laser_alarm, 0)     # the laser reports no alarm
        ctx.set(top.spi_cs_n, 1)
        for name, value in (("laser_prr", prr), ("pulses_per_point", pulses_per_point),
                            ("pitch", pitch), ("jump_delay", jump_delay),
                            ("laser_power", 128),
                            # The longest watchdog: the simulated host is slow, not silent.
                            ("watchdog", BY_NAME["watchdog"].high), ("arm", 1)):
            await write(ctx, name, value)
        pending = list(job)
        free = await read(ctx, "fifo_free")     # the queue is empty: its depth
        started = False
        while pending:
            if free == 0:
                free = await read(ctx, "fifo_free")
                if free == 0:
                    await ctx.delay(100e-6)
                continue
            op, x, y = pending.pop(0)
            await write(ctx, "vec_x", x)
            await write(ctx, "vec_y", y)
            await write(ctx, "vec_op", OPS[op].value)
            free -= 1
            if not started and (free == 0 or not pending):
                # The first batch is in; let the MO lead pass, then run.
                await ctx.delay(mo_lead + 100e-6)
                await write(ctx, "run", 1)
                started = True
        while Status.from_bits(await read(ctx, "status")).vector_busy:
            await ctx.delay(100e-6)
        await ctx.delay(50e-6)                   # the last frames reach the head
        rejected = await read(ctx, "vec_rejected")
        errors = await read(ctx, "errors")
        if rejected or errors:
            raise RuntimeError(f"the board refused {errors} frames ({rejected} segments)")

    receiver = XY2Receiver()

    async def scan_head(ctx):
        async for _, sync, x, y, cycles in ctx.negedge(top.xy2_clk).sample(
                top.xy2_sync, top.xy2_x, top.xy2_y, timed.cycles):
            frame = receiver.sample(sync, x, y)
            if frame is not None:
                frame_ends.append((cycles, frame.x, frame.y))
                if progress is not None:
                    progress(1)

    async def sync_edges(ctx):
        async for _, cycles in ctx.posedge(top.xy2_sync).sample(timed.cycles):
            sync_rises.append(cycles)

    async def laser(ctx):
        async for _, am, cycles in ctx.posedge(top.laser_prr).sample(top.laser_am,
                                                                      timed.cycles):
            if am:
                pulses.append(cycles)

    sim.add_testbench(host)
    for process in (scan_head, sync_edges, laser):
        sim.add_testbench(process, background=True)
    with sim.write_vcd(vcd) if vcd else contextlib.nullcontext():
        sim.run()

    counts = [0] * len(frame_ends)
    for k, _ in frame_of_each_pulse(sync_rises, pulses, len(frame_ends)):
        counts[k] += 1
    return JobResult([(x, y, n) for (_, x, y), n in zip(frame_ends, counts)], clk_freq)


def _replay_on_board(job, registers, *, clk_freq, mo_lead, correction, progress, backend,
                     say):
    from ..client import HostClient
    from ..jobs.stream import JobStreamer
    from .board import SimTransport, SimulatedBoard
    board = SimulatedBoard(clk_freq=clk_freq, backend=backend, say=say, mo_lead=mo_lead,
                           settings=ScanSettings(mode="vector", run=False),
                           correction=correction)
    try:
        client = HostClient(SimTransport(board))
        streamer = JobStreamer(client, poll_s=0)
        if progress is not None:
            seen = [0]

            def frames_so_far(_done):
                progress(len(board.frames) - seen[0])
                seen[0] = len(board.frames)
            streamer.progress = frames_so_far
        report = streamer.run_vector(list(job), registers, timeout_s=1e9)
        board.run_for(50e-6)                     # the last frames reach the head
        if report.counters.get("errors") or report.counters.get("vec_rejected"):
            raise RuntimeError(f"the board refused {report.counters.get('errors')} frames "
                               f"({report.counters.get('vec_rejected')} segments)")
        counts = [0] * len(board.frames)
        for k, _ in frame_of_each_pulse(board.sync_rises, board.pulses, len(board.frames)):
            counts[k] += 1
        return JobResult([(x, y, n) for (_, x, y), n in zip(board.frames, counts)], clk_freq)
    finally:
        board.close()
