"""Bitstream builds with the YoWASP toolchain, and what nextpnr measured of them."""

from dataclasses import asdict, dataclass, replace
import json
import os
from pathlib import Path
import shlex
import subprocess
import sys
import time

from .gateware.clocking import DEFAULT_BAUD
from .placer import placed_by
from .gateware.field.correction_table import CorrectionTable
from .gateware.limits import DEFAULT_CORRECTION_NODES
from .gateware.settings import ScanSettings
from .platforms.icebreaker import ICEBreakerScanner, icebreaker_platform
from .platforms.icestick import ICEStickScanner, icestick_platform
from .platforms.ulx3s import ULX3S_CORRECTION_NODES, ULX3SScanner, ulx3s_platform
from .toolchain import tool_env


__all__ = ["BOARDS", "PRESETS", "SIMULATED_BOARDS", "BuildReport", "build_bitstream",
           "board_config", "starting_table", "simulated_bitstream", "preset_register_map",
           "preset_settings"]


@dataclass(frozen=True)
class Board:
    """What ``galvoscan build`` needs to know of a board: its platform and top-level, the
    options for Yosys' synthesis, and the FPGA family's tools and cell names.

    The top-level's ``config(...)`` makes a build's configuration with the board's fit rules.
    """
    platform: object            # () -> the Amaranth platform
    top: type                   # the top-level Elaboratable, with its config(...)
    synth_opts: str             # options for Yosys' synth_ice40 / synth_ecp5
    family: str                 # "ice40" or "ecp5"
    bitstream_suffix: str       # what the programmer takes: ".bin" (iCE40), ".bit" (ECP5)
    #: nextpnr's cell names: (logic cells or LUT4s, block RAMs, DSPs).
    cells: tuple
    correction: bool = True     # the top takes a correction table
    #: Nodes per axis of the identity table a build starts with where given none.
    correction_nodes: int = DEFAULT_CORRECTION_NODES


#: Boards ``galvoscan build`` knows. The UP5K has DSP blocks: ``-dsp`` puts the scale stage's
#: multipliers there instead of in logic cells. (``-dff``, ABC optimising the logic with its
#: flip-flops, saves some 200 cells but overflows the WebAssembly build of ABC's stack on this
#: design.) On the ECP5 synth_ecp5 maps the multipliers to MULT18X18D blocks by itself; its
#: cells are counted as LUT4s (TRELLIS_COMB), not slices.
BOARDS = {
    "icebreaker": Board(icebreaker_platform, ICEBreakerScanner, "-dsp", "ice40", ".bin",
                        ("ICESTORM_LC", "ICESTORM_RAM", "ICESTORM_DSP")),
    "icestick": Board(icestick_platform, ICEStickScanner, "-dffe_min_ce_use 8", "ice40", ".bin",
                      ("ICESTORM_LC", "ICESTORM_RAM", "ICESTORM_DSP"), correction=False),
    "ulx3s": Board(ulx3s_platform, ULX3SScanner, "", "ecp5", ".bit",
                   ("TRELLIS_COMB", "DP16KD", "MULT18X18D"),
                   correction_nodes=ULX3S_CORRECTION_NODES),
}


def starting_table(board):
    """The correction table ``board``'s bitstream starts with where given none: the identity
    of :attr:`Board.correction_nodes` nodes (what a simulated board of it starts with too)."""
    return CorrectionTable.identity(BOARDS[board].correction_nodes)


def board_config(board="icebreaker", **options):
    """The :class:`~galvoscan.gateware.build_config.BuildConfig` of ``board``'s bitstream with
    ``options`` (those of :func:`build_bitstream`: ``modes``, ``correction``, ``clock``,
    ``bit_rate``, ``baud``, ``wobble``, ``interpolation``, ``delays``, ``player``,
    ``head_status``); a
    ``ValueError`` for what the board cannot hold. With no options, the board's default
    bitstream: on the iCEBreaker all three modes with the correction stage (the fit figures in
    the benchmarks, docs/bench.json)."""
    if board not in BOARDS:
        raise ValueError(f"unknown board {board!r}; known: {', '.join(BOARDS)}")
    return BOARDS[board].top.config(**options)


#: One bitstream for each kind of machine (``galvoscan build --preset``, ``board --sim
#: --preset``), and the default one: the iCEBreaker's configurations.
PRESETS = {
    # What `galvoscan build` builds when told nothing.
    "default": board_config("icebreaker"),
    # A marking station: vector mode with the RTC delays, the correction stage, and the job
    # player (stand-alone from the flash, started by a foot switch), on the PLL's 24 MHz.
    # (The head status receiver does not fit beside them: 5,274 of 5,280 logic cells, which
    # nextpnr's static placer cannot place and HeAP places at 23.7 MHz, short of 24.)
    "marker": board_config("icebreaker", modes=("vector",), delays=True, player=True,
                           clock=24e6),
    # An engraver of photos and dense fills: vector mode with its delays and pixel lines (a
    # line swept at one speed, each point lit by a bit), the correction stage, on the crystal.
    "engraver": board_config("icebreaker", modes=("vector",), delays=True, pixel_lines=True),
    # A cleaning head: the spiral with its interpolator, the raster fill and the correction
    # stage, on the crystal.
    "cleaner": board_config("icebreaker", modes=("spiral", "raster"), interpolation=True),
}


def simulated_bitstream(board="icebreaker", *, preset="default", baud=None):
    """What a simulated board of ``board``'s bitstream is built from (``board --sim``, and
    ``mark``/``clean``/``test-grid --sim --board``): ``(config, contents)``, the
    :class:`~galvoscan.gateware.build_config.BuildConfig` (an iCEBreaker ``preset``'s; the
    ULX3S has one bitstream) at ``baud`` (default: the build's), and what its memories start
    with (the ULX3S's correction table, as :func:`build_bitstream` gives it). A ``ValueError``
    in one line for a preset the board has not."""
    if board not in SIMULATED_BOARDS:
        raise ValueError(f"the simulated board runs {' or '.join(SIMULATED_BOARDS)}'s "
                         f"bitstream, not {board!r}'s")
    if board == "ulx3s":
        if preset != "default":
            raise ValueError("--preset names an iCEBreaker bitstream; the ULX3S has one, with "
                             "every feature")
        config, contents = board_config("ulx3s"), {"correction": starting_table("ulx3s")}
    else:
        if preset not in PRESETS:
            raise ValueError(f"--preset must be one of {', '.join(PRESETS)}, not {preset!r}")
        config, contents = PRESETS[preset], {}
        settings = preset_settings(config)
        if settings is not None:        # (a build without the spiral starts in its own mode)
            contents["settings"] = settings
    if baud is not None:
        config = replace(config, baud=baud)
    return config, contents


#: The boards a simulated board can be of (the iCEstick's bitstream is the spiral alone, which
#: ``galvoscan sim`` replays).
SIMULATED_BOARDS = ("icebreaker", "ulx3s")


def preset_register_map(name):
    """The register map of preset ``name``'s bitstream: what its register file takes (a job
    image for the marker's player is checked against it)."""
    config = PRESETS[name]
    settings = preset_settings(config)
    return config.register_map(resets=settings.register_resets() if settings else None)


def preset_settings(config):
    """The scan settings a bitstream of ``config`` starts with: a build without the spiral
    starts, stopped, in its first mode (None: the defaults)."""
    if "spiral" in config.modes:
        return None
    return ScanSettings(mode=config.modes[0], run=False)


@dataclass
class BuildReport:
    """What one build produced and what nextpnr measured."""
    board: str
    bitstream: str
    clock_mhz: float        # the board clock the design must meet
    fmax_mhz: float         # nextpnr's estimate for the system clock
    luts: int               # logic cells (iCE40: ICESTORM_LC) or LUT4s (ECP5: TRELLIS_COMB) used
    luts_available: int
    brams: int              # block RAMs used (iCE40: 4 kbit ICESTORM_RAM; ECP5: 18 kbit DP16KD)
    brams_available: int
    dsps: int               # multipliers used (iCE40: ICESTORM_DSP; ECP5: MULT18X18D)
    dsps_available: int
    seconds: float          # wall time of synthesis, place and route and packing
    modes: tuple = ()       # scan modes built
    bit_rate_mhz: float = 2.0   # XY2 bit rate (2: XY2-100, 4: XY2-200)
    baud: int = DEFAULT_BAUD    # host serial port rate
    correction_nodes: int = 0   # correction table nodes per axis (0: no correction stage)
    placer: str = "heap"        # nextpnr's placer that placed it: "static" or "heap"
    seed: int = 1               # nextpnr's seed of that placement (the next ones if one missed)
    player: bool = False        # the job player (stand-alone marking)
    links: tuple = ("spi", "uart")  # the host links built
    device: str = ""            # the FPGA, where a board comes with several (ULX3S: "25F")

    @property
    def logic_name(self):
        """What ``luts`` counts: ``"logic cells"`` (iCE40: a LUT and a flip-flop each) or
        ``"LUT4s"`` (ECP5, whose flip-flops are counted apart)."""
        return "LUT4s" if BOARDS[self.board].family == "ecp5" else "logic cells"

    @property
    def meets_timing(self):
        return self.fmax_mhz >= self.clock_mhz

    @property
    def margin(self):
        """Fmax over the required clock, as a ratio."""
        return self.fmax_mhz / self.clock_mhz

    def as_dict(self):
        return {**asdict(self), "meets_timing": self.meets_timing}


def _used(utilisation, cell):
    entry = utilisation.get(cell, {"used": 0, "available": 0})
    return entry["used"], entry["available"]


class BuildError(RuntimeError):
    """A build that ran but cannot be used: timing not met, or a tool that failed."""


class TimingError(BuildError):
    """nextpnr placed and routed the design, but its Fmax is below the system clock.

    ``report`` is the :class:`BuildReport` of the build (no bitstream was written)."""

    def __init__(self, report):
        self.report = report
        super().__init__(f"timing not met: {report.fmax_mhz:.1f} MHz < {report.clock_mhz:g} MHz "
                         f"({report.board}, {report.luts} of {report.luts_available} cells, "
                         f"{report.brams} of {report.brams_available} block RAMs)")


def build_bitstream(board="icebreaker", *, config=None, build_dir="build", table=None,
                    settings=None, correction="identity", seed=1, require_timing=True,
                    device=None, **options):
    """Synthesise, place and route and pack the full system for ``board``.

    ``config`` is the build's :class:`~galvoscan.gateware.build_config.BuildConfig` (one of
    :data:`PRESETS`, or :func:`board_config`'s); None: :func:`board_config` of ``options``
    (``modes``, ``clock``, ``bit_rate``, ``baud``, ``wobble``, ``interpolation``, ``delays``,
    ``pixel_lines``, ``player``), checked against the board before anything is built. ``correction`` is the
    correction table the RAM starts with (``None``: no correction stage), ``table`` and
    ``settings`` the spiral table and the scan settings; nextpnr runs with a fixed ``seed``
    so builds are repeatable (and with the next ones where it misses the clock:
    :mod:`galvoscan.placer`).
    Returns a :class:`BuildReport`. A design that misses the clock raises
    :class:`TimingError` (with the report, and no bitstream written) unless
    ``require_timing`` is false; a tool that fails raises :class:`BuildError` naming it and the
    folder that holds its logs. ``device`` picks the FPGA of a board that comes with several
    (the ULX3S: ``"25F"``, its default, or ``"12F"``, ``"45F"``, ``"85F"``).
    """
    if board not in BOARDS:
        raise ValueError(f"unknown board {board!r}; known: {', '.join(BOARDS)}")
    target = BOARDS[board]
    make_top = target.top
    if device is not None and board != "ulx3s":
        raise ValueError(f"--device is the ULX3S's (its ECP5), not the {board}'s")
    # What the board cannot run raises here, before anything is built.
    if config is None:
        config = make_top.config(correction=correction, **options)
    elif options:
        raise TypeError(f"give the build's options in its config, not as {', '.join(options)}")
    if not config.correction:
        correction = None               # the build has no correction stage at all
    elif isinstance(correction, str) and correction == "identity":
        correction = starting_table(board)
    top_contents = {"correction": correction} if target.correction else {}
    clock = config.clk_freq
    platform = target.platform(device) if device else target.platform()
    build_dir = Path(build_dir)
    name = f"galvoscan_{board}"

    start = time.monotonic()
    plan = platform.build(make_top(config, table=table, settings=settings, **top_contents),
                          name=name,
                          build_dir=str(build_dir), do_build=False,
                          synth_opts=target.synth_opts,
                          # Timing is judged here, from the report, so that a slow design
                          # gives its figures rather than a failed subprocess.
                          nextpnr_opts=f"--seed {seed} --report {name}.report.json "
                                       f"--timing-allow-fail" +
                                       (f" --freq {clock / 1e6:g}"
                                        if clock != platform.default_clk_frequency else ""))
    env = tool_env()
    # (Amaranth's build script names nextpnr's log after the design.)
    placer_file = placed_by(build_dir / f"{name}.tim")
    placer_file.unlink(missing_ok=True)     # a former build's
    if os.name == "posix" and target.family == "ice40":
        # nextpnr through galvoscan.placer: the electrostatic placer, HeAP if it does not settle.
        build_dir.mkdir(parents=True, exist_ok=True)
        wrapper = build_dir / "nextpnr-ice40.sh"
        wrapper.write_text(f"#!/bin/sh\nexec {shlex.quote(sys.executable)} -m galvoscan.placer "
                           f"\"$@\"\n")
        wrapper.chmod(0o755)
        env["NEXTPNR_ICE40"] = str(wrapper.resolve())
    try:
        products = plan.execute_local(str(build_dir), env=env)
    except subprocess.CalledProcessError as error:
        raise BuildError(f"the {board} build failed in {error.cmd[0] if error.cmd else 'a tool'}"
                         f" (exit {error.returncode}); see the logs in {build_dir}") from None
    seconds = time.monotonic() - start

    bitstream = build_dir / f"{name}{target.bitstream_suffix}"
    report = json.loads(products.get(f"{name}.report.json", mode="t"))
    clock_mhz = clock / 1e6
    # One clock domain: the slowest achieved figure is the system's Fmax.
    fmax_mhz = min(entry["achieved"] for entry in report["fmax"].values())
    utilisation = report["utilization"]
    # (DSPs 0 / 0 on the HX1K.)
    (luts, luts_available), (brams, brams_available), (dsps, dsps_available) = (
        _used(utilisation, cell) for cell in target.cells)
    placer, seed = (placer_file.read_text().split() if placer_file.is_file()
                    else ("heap", seed))
    result = BuildReport(board=board, bitstream=str(bitstream), clock_mhz=clock_mhz,
                       fmax_mhz=round(fmax_mhz, 2), luts=luts, luts_available=luts_available,
                       brams=brams, brams_available=brams_available, dsps=dsps,
                       dsps_available=dsps_available, seconds=round(seconds, 1),
                       modes=config.modes,
                       correction_nodes=correction.n if correction else 0,
                       bit_rate_mhz=config.bit_rate / 1e6, baud=config.baud, placer=placer,
                       seed=int(seed), player=config.player, links=config.links,
                       device=device or ("25F" if board == "ulx3s" else ""))
    # The build's record beside its netlist (its clock, baud and options): what a simulation
    # of the netlist needs to know of it.
    record = {**result.as_dict(), "interpolation": config.spiral_interpolation,
              "delays": config.vector_delays, "wobble": config.wobble}
    (build_dir / f"{name}.build.json").write_text(json.dumps(record, indent=1))
    if not result.meets_timing:
        # A bitstream that misses timing is never written where a user would flash it, nor
        # the placed and routed design it would be packed from.
        bitstream.unlink(missing_ok=True)
        (build_dir / f"{name}.asc").unlink(missing_ok=True)
        if require_timing:
            raise TimingError(result)
        return result
    bitstream.write_bytes(products.get(bitstream.name))
    return result
