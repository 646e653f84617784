"""One build of the system: its options, their defaults, the rules they must keep, and what
they imply (the ``caps`` register's bits, the register map).

A :class:`BuildConfig` is what :class:`~.top.GalvoScanTop` is built from, and what the boards
(``galvoscan.platforms``), ``galvoscan build`` and its presets, and the simulated board take:
a simulated board is so always one configuration a bitstream can be built with. The boards add
their own fit rules (what their FPGA holds) on top of the rules here, which hold for any FPGA.

Only options live here; contents the build starts with (the spiral table, the correction
table's values, the scan settings) are the top's arguments.
"""

from dataclasses import dataclass, fields as dataclass_fields

from .clocking import XY2_100_BIT_RATE, check_clocks, default_baud
from .fields import Capabilities, Mode, pack
from .host.regmap import register_map
from .laser.controller import MAX_ALARMS
from .limits import DEFAULT_CLOCK_HZ, DEFAULT_CORRECTION_NODES, DEFAULT_TABLE_POINTS, \
    VECTOR_QUEUE_DEPTH
from .phy.xy2_100 import FRAME_BITS
from .player.start_input import DEFAULT_DEBOUNCE_MS, debounce_ticks
from .sources.wobble import Wobble


__all__ = ["BuildConfig", "MODES", "LINKS"]


#: Names of the scan modes, in the order of their ``mode`` register values (:class:`Mode`).
MODES = tuple(mode.label for mode in Mode)
#: Host links a build may have.
LINKS = ("spi", "uart")


def _whole(value):
    return isinstance(value, int) and not isinstance(value, bool)


@dataclass(frozen=True)
class BuildConfig:
    """The options of one build, checked at construction (a ``ValueError`` or ``TypeError``
    naming the option).

    The defaults are the whole system on the iCEBreaker's crystal: every mode, the correction
    stage, the spiral's interpolator, both links and two alarm inputs. A board's bitstream
    leaves some out to fit (``galvoscan.platforms``).

    Parameters
    ----------
    modes : tuple of str
        Scan modes built (some of ``"spiral"``, ``"raster"``, ``"vector"``; a :class:`Mode`
        is taken for its name).
    clk_freq : int or float
        Frequency of the system clock, Hz.
    bit_rate : int or float
        XY2 bit rate in Hz (2 MHz: XY2-100). ``clk_freq / bit_rate`` must be an even integer.
    baud : int or None
        UART rate (8N1). None: 1 Mbaud (the boards' default), or on a clock too slow for it
        (a simulation's few MHz) the fastest standard rate it carries
        (:func:`~.clocking.default_baud`); the configuration holds the rate chosen.
    correction : bool
        Build the correction stage (its table's size is the table's, the top's argument).
    multiplier : str
        The scale stage's products: ``"dsp"`` (one DSP block per axis) or ``"serial"``
        (shift-and-add, for FPGAs without DSPs; needs ``correction=False``).
    links : tuple of str
        Host links built: ``"spi"`` and/or ``"uart"``. The pins of a link left out do nothing.
    laser : bool
        Build the laser controller. Without it the laser pins stay low, its registers are
        unknown addresses, and vector mode (timed by the laser's pulses) cannot be built.
    laser_alarms : int
        Laser alarm inputs, 0 … 4 (each latches an alarm fault while armed); 0 without the
        laser.
    register_reads : str
        How the register file reads back what it holds: ``"ram"``, from a copy in block RAM
        (two RAMs, some 90 cells fewer on the full build), or ``"mux"``, through a multiplexer
        (the smallest boards).
    vector_queue_depth : int
        Segments the vector queue holds (:data:`~.limits.VECTOR_QUEUE_DEPTH`, the boards').
        A simulation may build a shorter queue, so that filling it costs a few dozen
        segments; the host learns the depth from ``fifo_free`` while the queue is empty.
    wobble : bool
        Build the wobble stage on vector mode's marked points (:class:`~.sources.wobble.Wobble`)
        and its ``wob_*`` registers; needs vector mode.
    spiral_interpolation : bool
        Build the spiral's linear interpolation between points and its ``spiral_interp``
        register (about 280 cells on the UP5K); False without the spiral.
    vector_delays : bool
        Build vector mode's RTC delays (laser-on, laser-off, mark, polygon). Without them
        their registers are left out and ``vec_op`` takes only 0 and 1. They need a clock of
        a whole number of MHz; False without vector mode.
    pixel_lines : bool
        Build vector mode's pixel lines (:class:`~.sources.vector.VectorSequencer`): a line
        swept at one speed, each point lit or not by a bit of the pixel words queued after
        it, for photos and dense fills. Needs the vector delays (their ``vec_op`` word).
    player : bool
        Build the job player (:class:`~.player.player.JobPlayer`), its flash reader and start
        input: a press of ``start_n`` plays the job image in the flash, with no host. Needs
        vector mode and the laser.
    start_debounce_ms : int
        How long a change of ``start_n`` must last, ms.
    mo_lead : float
        Seconds the laser's master oscillator leads emission (5 ms, as the paper).
    head_status : bool
        Build the receiver of the scan head's STATUS line (``xy2_status``) and its ``head``,
        ``head_state``, ``head_check`` and ``head_bad`` registers.
    head_check : bool
        What ``head_check`` resets to: 1 = the laser obeys the head from power-up (a head
        that reports Temp OK or Power OK low, or none, keeps the laser off). Needs the
        receiver and the laser. Off by default: a head without a STATUS line reads as missing.
    fly : bool
        Build marking on the fly: two quadrature encoder inputs (``encoder_x_a`` …), a
        simulated encoder, the fly offset before the correction, and the ``fly_*`` and
        ``enc_*`` registers.
    z_axis : bool
        Drive XY2-100's Z channel (``xy2_z``, a focus shifter) in every frame, from the ``z``
        register.
    queue_io : bool
        Build I/O in the queue (:class:`~.sources.queue_io.QueueIO`): two inputs ``io_in``
        (a part sensor) and two outputs ``io_out`` (to a PLC), waits and outputs queued as
        ``vec_op`` words (bit 9), and the ``io`` register. Needs pixel lines (their
        ``vec_op`` word); with marking on the fly, also waits for an encoder's count and the
        fly's start and end in the queue.
    """

    modes: tuple = MODES
    clk_freq: float = DEFAULT_CLOCK_HZ
    bit_rate: float = XY2_100_BIT_RATE
    baud: int = None
    correction: bool = True
    multiplier: str = "dsp"
    links: tuple = LINKS
    laser: bool = True
    laser_alarms: int = 2
    register_reads: str = "ram"
    vector_queue_depth: int = VECTOR_QUEUE_DEPTH
    wobble: bool = False
    spiral_interpolation: bool = True
    vector_delays: bool = False
    pixel_lines: bool = False
    player: bool = False
    start_debounce_ms: int = DEFAULT_DEBOUNCE_MS
    mo_lead: float = 5e-3
    head_status: bool = False
    head_check: bool = False
    fly: bool = False
    z_axis: bool = False
    queue_io: bool = False

    def __post_init__(self):
        def put(name, value):       # (frozen: the normalised values are set once, here)
            object.__setattr__(self, name, value)

        modes = tuple(mode.label if isinstance(mode, Mode) else mode for mode in self.modes)
        if not modes or any(mode not in MODES for mode in modes) or len(set(modes)) != len(modes):
            raise ValueError(f"modes must be some of {', '.join(MODES)}, each once, not {modes!r}")
        put("modes", modes)
        # Checked here so that a bad clock shows at construction, not deep in elaboration.
        put("baud", default_baud(self.clk_freq) if self.baud is None else self.baud)
        check_clocks(self.clk_freq, self.bit_rate, self.baud)
        put("correction", bool(self.correction))
        if self.multiplier not in ("dsp", "serial"):
            raise ValueError(f"multiplier must be dsp or serial, not {self.multiplier!r}")
        if self.multiplier == "serial" and self.correction:
            raise ValueError("the serial multiplier is for FPGAs without DSP blocks, where the "
                             "correction stage does not fit: build it with correction=None")
        links = tuple(self.links)
        if not links or any(link not in LINKS for link in links) or len(set(links)) != len(links):
            raise ValueError(f"links must be some of spi, uart, each once, not {links!r}")
        put("links", links)
        put("laser", bool(self.laser))
        if self.register_reads not in ("ram", "mux"):
            raise ValueError(f"register_reads must be ram or mux, not {self.register_reads!r}")
        if not self.laser and "vector" in modes:
            raise ValueError("vector mode times its points by the laser's pulses: it needs the "
                             "laser controller")
        put("fly", bool(self.fly))
        put("z_axis", bool(self.z_axis))
        put("head_status", bool(self.head_status))
        put("head_check", bool(self.head_check))
        if self.head_check and not (self.head_status and self.laser):
            raise ValueError("head_check makes the laser obey the head's status: it needs "
                             "head_status=True and the laser controller")
        if self.head_status and self.clocking.clocks_per_bit < 4:
            raise ValueError(f"the head status receiver samples a bit 2 clocks after its "
                             f"middle: it needs 4 clocks a bit or more, not "
                             f"{self.clocking.clocks_per_bit}")
        if not self.mo_lead > 0:
            raise ValueError(f"mo_lead must be a positive time in seconds, not {self.mo_lead!r}")
        if not _whole(self.laser_alarms) or not 0 <= self.laser_alarms <= MAX_ALARMS:
            raise ValueError(f"laser_alarms must be a whole number from 0 to {MAX_ALARMS}, "
                             f"not {self.laser_alarms!r}")
        put("laser_alarms", self.laser_alarms if self.laser else 0)
        if not _whole(self.vector_queue_depth) or \
                not 2 <= self.vector_queue_depth <= VECTOR_QUEUE_DEPTH:
            raise ValueError(f"vector_queue_depth must be a whole number from 2 to "
                             f"{VECTOR_QUEUE_DEPTH}, not {self.vector_queue_depth!r}")
        put("wobble", bool(self.wobble))
        if self.wobble and "vector" not in modes:
            raise ValueError("the wobble stage works on vector points: it needs vector mode")
        if self.wobble:
            Wobble.check_frame_rate(self.bit_rate / FRAME_BITS)
        put("spiral_interpolation", bool(self.spiral_interpolation) and "spiral" in modes)
        put("vector_delays", bool(self.vector_delays) and "vector" in modes)
        put("pixel_lines", bool(self.pixel_lines) and "vector" in modes)
        if self.pixel_lines and not self.vector_delays:
            raise ValueError("pixel lines come with vector mode's delays (their vec_op word): "
                             "build them with vector_delays=True")
        put("queue_io", bool(self.queue_io) and "vector" in modes)
        if self.queue_io and not self.pixel_lines:
            raise ValueError("I/O in the queue comes with pixel lines (their vec_op word): "
                             "build it with pixel_lines=True")
        put("player", bool(self.player))
        if self.player and not ("vector" in modes and self.laser):
            raise ValueError("the job player plays vector jobs: it needs vector mode and the "
                             "laser controller")
        if self.player:
            debounce_ticks(self.start_debounce_ms, self.frame_us)       # (checked now)
        if self.vector_delays:
            clocks_per_us = self.clk_freq / 1e6
            if self.frame_us != int(self.frame_us) or clocks_per_us != int(clocks_per_us):
                raise ValueError(f"the vector delays count whole µs: they need a clock of a "
                                 f"whole number of MHz and frames of whole µs, not "
                                 f"{self.clk_freq:g} Hz and {self.frame_us:g} µs (build with "
                                 f"vector_delays=False)")

    @classmethod
    def options(cls):
        """The names of the options, in declaration order."""
        return tuple(field.name for field in dataclass_fields(cls))

    @property
    def frame_us(self):
        """µs an XY2 frame lasts (10 at XY2-100)."""
        return FRAME_BITS * 1e6 / self.bit_rate

    @property
    def clocking(self):
        """The :class:`~.clocking.ClockPlan`: clocks per XY2 bit and per UART bit."""
        return check_clocks(self.clk_freq, self.bit_rate, self.baud)

    def capabilities(self):
        """What this build holds, as the ``caps`` register reports it (a dict of the
        :data:`~.fields.Capabilities` flags)."""
        return {"spiral": "spiral" in self.modes, "raster": "raster" in self.modes,
                "vector": "vector" in self.modes, "laser": self.laser,
                "correction": self.correction, "wobble": self.wobble,
                "delays": self.vector_delays, "interpolation": self.spiral_interpolation,
                "uart": "uart" in self.links, "spi": "spi" in self.links,
                "player": self.player, "pixel_lines": self.pixel_lines,
                "head": self.head_status, "fly": self.fly, "z": self.z_axis,
                "io": self.queue_io}

    def register_map(self, *, table_points=DEFAULT_TABLE_POINTS,
                     correction_nodes=DEFAULT_CORRECTION_NODES, resets=None):
        """This build's :class:`~.host.regmap.RegisterMap`, with a spiral table of
        ``table_points`` samples per axis and (with the correction stage) a correction table
        of ``correction_nodes`` nodes per axis; ``resets`` as for
        :func:`~.host.regmap.register_map`. Its read-only ``caps``, ``vec_depth`` and
        ``cor_nodes`` hold what this configuration built."""
        correction_nodes = correction_nodes if self.correction else None
        return register_map(
            table_points=table_points, correction_nodes=correction_nodes,
            modes=self.modes, laser=self.laser, wobble=self.wobble,
            spiral_interpolation=self.spiral_interpolation, vector_delays=self.vector_delays,
            pixel_lines=self.pixel_lines, player=self.player, head=self.head_status, fly=self.fly,
            z=self.z_axis, queue_io=self.queue_io,
            resets={**(resets or {}), **({"head_check": 1} if self.head_check else {})},
            fixed={"caps": pack(Capabilities, **{name: int(built) for name, built
                                                 in self.capabilities().items()}),
                   "vec_depth": self.vector_queue_depth if "vector" in self.modes else 0,
                   **({} if correction_nodes is None else {"cor_nodes": correction_nodes})})

    def summary(self):
        """One line a person reads: the clock, the modes and what else is built."""
        built = [name for name, on in (("correction", self.correction),
                                       ("interpolation", self.spiral_interpolation),
                                       ("delays", self.vector_delays),
                                       ("pixel lines", self.pixel_lines), ("wobble", self.wobble),
                                       ("player", self.player), ("head status", self.head_status),
                                       ("marking on the fly", self.fly), ("Z", self.z_axis),
                                       ("I/O in the queue", self.queue_io),
                                       ("laser", self.laser)) if on]
        return (f"{self.clk_freq / 1e6:g} MHz, XY2 {self.bit_rate / 1e6:g} Mbit/s, "
                f"{self.baud:,} baud; modes {','.join(self.modes)}; links "
                f"{','.join(self.links)}; with {', '.join(built) if built else 'nothing else'}")
