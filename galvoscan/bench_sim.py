"""What ``galvoscan bench`` measures in simulation: the XY2-100 PHY's frame rate, the host
link's command rate and latency, vector segments streamed end to end, and the full spiral
replay (see :mod:`galvoscan.bench`)."""

from pathlib import Path
import time

from amaranth.sim import Simulator
import numpy as np

from .sim.link import Timed, spi_transfer


__all__ = ["phy_rate", "link_figures", "stream_figures", "real_time_figures", "PHOTO_GALVO",
           "shaded_picture", "photo_profile", "photo_figures", "replay_figures", "backend_figures"]


# --- XY2-100 -------------------------------------------------------------------------------------

def phy_rate(*, clk_freq=12e6, bit_rate=2e6, frames=30):
    """Frames per second and idle clocks between frames of the PHY, read off its wires.

    A source offers a new position on every frame; the receiver decodes each one (checking
    SYNC, control bits and parity) and the positions must be the ones offered.
    """
    from .gateware.phy.xy2_100 import XY2Transmitter, clocks_per_bit
    from .sim.xy2_receiver import XY2Receiver
    phy = XY2Transmitter(clk_freq=clk_freq, bit_rate=bit_rate)
    counted = Timed(phy)
    sim = Simulator(counted)
    sim.add_clock(1 / clk_freq)
    sent, received, starts = [], [], []

    async def source(ctx):
        for k in range(frames + 2):
            position = (1000 * k + 17, 65535 - 900 * k)
            ctx.set(phy.position.payload.x, position[0])
            ctx.set(phy.position.payload.y, position[1])
            ctx.set(phy.position.valid, 1)
            await ctx.tick().until(phy.position.ready)
            sent.append(position)

    async def head(ctx):
        receiver = XY2Receiver()
        async for _, sync, x, y in ctx.negedge(phy.xy2_clk).sample(phy.xy2_sync, phy.xy2_x,
                                                                   phy.xy2_y):
            frame = receiver.sample(sync, x, y)
            if frame is not None:
                received.append((frame.x, frame.y))

    async def sync_rises(ctx):
        async for _, cycles in ctx.posedge(phy.xy2_sync).sample(counted.cycles):
            starts.append(cycles)

    sim.add_testbench(source)
    sim.add_testbench(head, background=True)
    sim.add_testbench(sync_rises, background=True)
    sim.run()
    # The PHY takes a position at each frame start: the frames are the positions offered.
    if received != sent[:len(received)]:
        raise RuntimeError("the PHY's frames are not the positions offered")
    periods = {b - a for a, b in zip(starts, starts[1:])}
    bit_clocks = clocks_per_bit(clk_freq, bit_rate) * 20
    period = max(periods)
    return {"frames_per_s": clk_freq / period, "idle_clocks": period - bit_clocks,
            "frame_clocks": period, "period_jitter_clocks": max(periods) - min(periods)}


# --- host link -----------------------------------------------------------------------------------

def link_figures(*, clk_freq=12e6, baud=115_200, frames=24):
    """Command throughput over SPI and UART (write frames with their answers), and
    command → XY2 latency for a vector jump (one segment frame)."""
    from cobs import cobs
    from .link.client import encode_command
    from .gateware.host.regmap import BY_NAME
    from .gateware.top import GalvoScanTop, ScanSettings
    from .sim.xy2_receiver import XY2Receiver
    top = GalvoScanTop(clk_freq=clk_freq, baud=baud,
                       settings=ScanSettings(mode="vector", run=True))
    counted = Timed(top)
    sim = Simulator(counted)
    sim.add_clock(1 / clk_freq)
    bit_time = 1 / baud
    results = {}
    frame_ends = []                                  # (cycle, x, y) of each XY2 frame

    async def spi_frame(ctx, frame):
        return await spi_transfer(ctx, top, frame, clk_freq)

    async def uart_frame(ctx, frame):
        for byte in cobs.encode(frame) + b"\0":
            for level in [0, *((byte >> i) & 1 for i in range(8)), 1]:
                ctx.set(top.uart_rx, level)
                await ctx.delay(bit_time)

    seq = 0

    def write(name, value, x=0, y=0):
        nonlocal seq
        seq = (seq + 1) & 0xFF
        return encode_command(seq - 1 & 0xFF, BY_NAME[name].address, value, x, y)

    async def jump_latency(ctx, send, x, y):
        """Queue a jump to (x, y); clocks from the end of the last frame to the XY2 frame."""
        await send(ctx, write("vec_op", 0, x, y))
        sent_at = ctx.get(counted.cycles)
        while not any(c > sent_at and (fx, fy) == (x, y) for c, fx, fy in frame_ends):
            await ctx.delay(10e-6)
        arrived = min(c for c, fx, fy in frame_ends if c > sent_at and (fx, fy) == (x, y))
        return (arrived - sent_at) / clk_freq

    async def host(ctx):
        ctx.set(top.spi_cs_n, 1)
        ctx.set(top.uart_rx, 1)
        ctx.set(top.interlock_open, 0)
        if hasattr(top, "laser_alarm"):
            ctx.set(top.laser_alarm, 0)     # the laser reports no alarm
        await ctx.delay(20e-6)
        # Jumps held one frame, so that each jump's latency is its own.
        await spi_frame(ctx, write("jump_delay", 10))
        for name, send in (("spi", spi_frame), ("uart", uart_frame)):
            start = ctx.get(counted.cycles)
            for k in range(frames):
                await send(ctx, write("pitch", 60 + k))
            seconds = (ctx.get(counted.cycles) - start) / clk_freq
            results[f"{name}_frames_per_s"] = frames / seconds
            latencies = [await jump_latency(ctx, send, 20000 + 5000 * k, 40000 - 3000 * k)
                         for k in range(3)]
            results[f"{name}_latency_us"] = 1e6 * sum(latencies) / len(latencies)
            results[f"{name}_latency_max_us"] = 1e6 * max(latencies)
        errors = encode_command(0, 0x80 | BY_NAME["errors"].address)
        await spi_frame(ctx, errors)
        # The answer's data: bytes 2 and 3 of the six that come back first.
        results["errors"] = (await spi_frame(ctx, errors) >> 8 * (10 - 4)) & 0xFFFF

    async def head(ctx):
        receiver = XY2Receiver()
        async for _, sync, x, y, cycles in ctx.negedge(top.xy2_clk).sample(
                top.xy2_sync, top.xy2_x, top.xy2_y, counted.cycles):
            frame = receiver.sample(sync, x, y)
            if frame is not None:
                frame_ends.append((cycles, frame.x, frame.y))

    sim.add_testbench(host)
    sim.add_testbench(head, background=True)
    sim.run()
    if results.pop("errors"):
        raise RuntimeError("the simulated board refused some of the bench's command frames")
    return results


# --- simulator -----------------------------------------------------------------------------------

def stream_figures(*, segments=600, baud=None, clk_freq=12e6, backend="python", config=None,
                   **top_kwargs):
    """Vector segments a second streamed end to end: ``JobStreamer`` (batches of segment
    frames, each answered with the queue's free places) through the UART pins of the simulated board at the default baud, one-point
    marks that the board takes faster than the link brings them (so each one finds the queue
    empty: ``underruns`` counts them all, by design); in the board's own time.

    The rate is the link's: any clock that carries the baud gives it to within the few clocks
    a ``fifo_free`` answer takes (``clk_freq``: 12 MHz, the board's; the quick bench's 8 MHz,
    the slowest that carries 1 Mbaud, is two thirds of the clocks to simulate). ``config``: a
    bitstream's :class:`~galvoscan.gateware.build_config.BuildConfig` (its clock and baud), in
    place of ``clk_freq`` and ``baud``."""
    from .link.client import HostClient
    from .gateware.clocking import DEFAULT_BAUD
    from .outputs.stream import JobStreamer
    from .sim.board import SimTransport, SimulatedBoard
    if config is None:
        board = SimulatedBoard(clk_freq=clk_freq, baud=baud or DEFAULT_BAUD, backend=backend,
                               **top_kwargs)
    else:
        board = SimulatedBoard(config=config, backend=backend, **top_kwargs)
    client = HostClient(SimTransport(board))
    streamer = JobStreamer(client, poll_s=0)
    streamer.setup({"run": 1, "mode": 2, "pitch": 1000, "pulses_per_point": 1,
                    "laser_prr": 1000, "jump_delay": 10})
    job = [("mark", 30000 + 100 * (k % 2), 30000) for k in range(segments)]
    start = board.now
    streamer.stream(job, start=lambda: None, timeout_s=1e9)
    seconds = board.now - start
    return {"segments_per_s": segments / seconds, "baud": board.baud,
            "segments": segments, "clock_mhz": board.clk_freq / 1e6,
            "underruns": client.read("vec_underruns"), "errors": client.read("errors"),
            "backend": board.backend}


#: The bench's machine for a photo through the link: quick mirrors (100 µs after a jump, 50 µs
#: after a mark), so that a photo's short marks and gaps ask more segments a second of the
#: link than 1 Mbaud carries. (The default profile's 500 µs jumps ask fewer: either rate
#: keeps up.)
PHOTO_GALVO = {"jump_delay_us": 100, "mark_delay_us": 50}


def shaded_picture(path, rows=300, columns=400):
    """A grey photograph's stand-in, written to ``path`` (PNG): smooth shading from black to
    white in two directions, so that once dithered it has as many dark cells alone as in
    runs. 400 × 300 pixels make some 58,000 marks at 24 mm wide."""
    from PIL import Image
    y, x = np.mgrid[0:rows, 0:columns]
    grey = 128 + 100 * np.sin(x / 23) * np.cos((y + 100) / 17)
    Image.fromarray(grey.clip(0, 255).astype(np.uint8)).save(path)
    return path


def photo_profile():
    """The default machine profile with :data:`PHOTO_GALVO`'s quick mirrors."""
    from dataclasses import replace
    from .profile.machine import default_profile
    profile = default_profile()
    return replace(profile, galvo=replace(profile.galvo, **PHOTO_GALVO))


def photo_figures(folder, *, rows=300, width_mm=24, speed_mm_s=1000, lines="runs"):
    """A photo through the link: :func:`shaded_picture` ``width_mm`` wide at ``speed_mm_s``,
    planned for a machine with :data:`PHOTO_GALVO`'s quick mirrors, the underruns foretold at
    1 and 3 Mbaud (:func:`~galvoscan.outputs.link_budget.expected_underruns`), and streamed whole
    on the compiled board: its marks, segments, underruns and the board's and the wall's
    seconds. ``lines``: ``"runs"`` (a mark a run of dark cells) through the ULX3S bitstream's
    UART at 3 Mbaud, or ``"pixels"`` (pixel lines) through the engraver's at 1 Mbaud."""
    from .api import Job, Photo, plan, run
    from .build import board_config, simulated_bitstream, starting_table
    from .outputs.link_budget import expected_underruns
    from .sim.board import SimulatedBoard
    profile = photo_profile()
    picture = shaded_picture(Path(folder) / "photo.png", rows=rows)
    planned = plan(Job(photos=[Photo(str(picture), width_mm=width_mm, lines=lines)],
                       speed_mm_s=speed_mm_s), profile)
    job = planned.vector_job
    foretold = {f"{baud / 1e6:g}": sum(count for _, count in expected_underruns(job, baud))
                for baud in (1_000_000, 3_000_000)}
    if lines == "pixels":
        config, contents = simulated_bitstream("icebreaker", preset="engraver")
        board = SimulatedBoard(config=config, backend="compiled", **contents)
    else:
        board = SimulatedBoard(config=board_config("ulx3s"), backend="compiled",
                               correction=starting_table("ulx3s"))
    started = time.perf_counter()
    report = run(planned, board)
    wall = time.perf_counter() - started
    board_s = board.now
    board.close()
    return {"width_mm": width_mm, "speed_mm_s": speed_mm_s, **PHOTO_GALVO, "lines": lines,
            "marks": len(job.paths_mm),
            "pixel_lines": sum(1 for op, *_ in job.segments if op == "line"),
            "pulses": report.pulses, "pulses_per_point": job.registers["pulses_per_point"],
            "segments": report.segments, "estimate_s": job.estimate_s,
            "foretold_underruns": foretold, "underruns": report.counters["vec_underruns"],
            "rejected": report.counters["vec_rejected"], "errors": report.counters["errors"],
            "board_s": board_s, "wall_s": wall, "baud": board.baud}


def real_time_figures(seconds=0.25):
    """How fast the simulated board runs each board's default bitstream, against real time:
    the compiled board, idle (the spiral running, no host, nothing recorded: what ``board
    --sim`` does between a host's frames), for ``seconds`` of its own time. ``{board:
    {"clock_mhz", "clocks_per_s", "real_time_fraction"}}``."""
    from .build import PRESETS, board_config, starting_table
    from .sim.board import SimulatedBoard
    figures = {}
    for name, config, contents in (
            ("icebreaker", PRESETS["default"], {}),
            ("ulx3s", board_config("ulx3s"), {"correction": starting_table("ulx3s")})):
        board = SimulatedBoard(config=config, backend="compiled", **contents)
        board.run_for(50e-6)            # (the first steps start the board's processes)
        started = time.perf_counter()
        board.run_for(seconds)
        wall = time.perf_counter() - started
        board.close()
        figures[name] = {"clock_mhz": config.clk_freq / 1e6,
                         "clocks_per_s": seconds * config.clk_freq / wall,
                         "real_time_fraction": seconds / wall}
    return figures


def replay_figures(points=8064, backend="python"):
    """Simulator speed and time of the full spiral replay (``galvoscan sim --points 8064``),
    on ``backend`` (its own path on Amaranth's, the simulated board on the compiled one)."""
    from .gateware.sources.spiral import PARK_FRAMES
    from .sim.spiral import SIM_CLOCKS_PER_BIT, replay_spiral
    frames = PARK_FRAMES + 3 * points
    start = time.monotonic()
    said = []
    replay_spiral(frames=frames, backend=backend, say=said.append)
    seconds = time.monotonic() - start
    cycles = frames * 20 * SIM_CLOCKS_PER_BIT
    fell_back = any("not available" in line for line in said)
    return {"replay_points": points, "replay_s": seconds, "sim_cycles_per_s": cycles / seconds,
            "backend": "python" if backend == "python" or fell_back else "compiled"}


# --- builds and proofs (in worker processes) ------------------------------------------------------


def backend_figures(*, python_s=5e-3, compiled_s=0.5, replay=True, say=None, **top_kwargs):
    """Both backends of the simulated board on the default top (12 MHz, every mode, the
    correction stage; its UART, machine pins, scan head and laser recorded), in the same run:
    system clocks simulated per second of each, over ``python_s`` and ``compiled_s`` of the
    board's time, their ratio, and (``replay``) the full spiral replayed on the compiled one's
    wires. ``top_kwargs``: another top (the quick bench's: 8 MHz, whose compiled model the
    tests' boards share)."""
    from .gateware.sources.spiral import PARK_FRAMES
    from .sim.board import SimulatedBoard
    from .sim.spiral import replay_spiral
    figures = {}
    for backend, seconds in (("compiled", compiled_s), ("python", python_s)):
        started = time.monotonic()
        board = SimulatedBoard(backend=backend, say=say, **top_kwargs)
        figures[f"{backend}_setup_s"] = time.monotonic() - started
        started = time.monotonic()
        board.run_for(seconds)
        elapsed = time.monotonic() - started
        figures[f"{backend}_clocks_per_s"] = seconds * board.clk_freq / elapsed
        board.close()
    figures["ratio"] = figures["compiled_clocks_per_s"] / figures["python_clocks_per_s"]
    figures["clock_mhz"] = board.clk_freq / 1e6
    figures["real_time_fraction"] = figures["compiled_clocks_per_s"] / board.clk_freq
    if replay:
        started = time.monotonic()
        replay_spiral(frames=PARK_FRAMES + 3 * 8064, backend="compiled", say=say)
        figures["compiled_replay_s"] = time.monotonic() - started
    return figures
