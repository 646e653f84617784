"""The galvoscan system, independent of any board (SPEC §3).

Its ports are plain one-bit wires with fixed names, so the exported Verilog drops into other
designs: ``clk``, ``rst`` (synchronous, active high), the scan head bus ``xy2_clk``,
``xy2_sync``, ``xy2_x``, ``xy2_y``, the host link ``spi_sck``, ``spi_cs_n``, ``spi_copi``,
``spi_cipo``, ``uart_rx``, ``uart_tx``, and the laser's DB25 signals ``laser_power[7:0]``,
``laser_latch``, ``laser_mo``, ``laser_am``, ``laser_prr`` with the ``interlock_open`` input.
"""

from amaranth.hdl import Cat, Module, Signal
from amaranth.lib import wiring
from amaranth.lib.fifo import SyncFIFOBuffered
from amaranth.lib.wiring import In, Out, connect

from .field.correction import FieldCorrection
from .field.correction_table import CorrectionTable
from .field.scale import AMP_ONE, ScaleOffset
from .host.command import CommandDecoder
from .host.registers import RegisterFile
from .host.regmap import BY_NAME, CORRECTION_REGISTERS, LASER_REGISTERS, MODE_REGISTERS, \
    STATUS_BITS
from .host.spi_target import SPITarget
from .host.uart import uart_divisor
from .host.uart_port import REPLY_QUEUE_DEPTH, UARTCommandPort
from .laser.controller import FAULT_BITS, LaserController
from .phy.xy2_100 import FRAME_BITS, XY2Transmitter, clocks_per_bit
from .points import FIELD_CENTRE
from .sources.raster import RasterSequencer
from .sources.spiral import SpiralSequencer
from .sources.spiral_table import SpiralTable
from .sources.vector import VectorCommand, VectorSequencer


__all__ = ["GalvoScanTop", "ScanSettings", "MODES", "VECTOR_QUEUE_DEPTH",
           "DEFAULT_CORRECTION_NODES"]


#: Values of the ``mode`` register.
MODES = {"spiral": 0, "raster": 1, "vector": 2}

#: Segments the vector queue holds (block RAM).
VECTOR_QUEUE_DEPTH = 512

#: Nodes per axis of the default (identity) correction table.
DEFAULT_CORRECTION_NODES = 17

# The correction stage finishes a point within the shortest possible frame (two clocks per
# bit), so a point taken at a frame boundary is always ready for the next one.
assert FieldCorrection.CLOCKS + 1 < 2 * FRAME_BITS


def _check_int(name, value, low, high, unit=""):
    if not isinstance(value, int) or isinstance(value, bool) or not low <= value <= high:
        raise ValueError(f"{name} must be an integer from {low} to {high}{unit}, not {value!r}")


class ScanSettings:
    """The scan settings the system starts with: what the host-writable registers reset to
    (the register map's defaults unless given).

    Parameters
    ----------
    dwell : int
        Frames each spiral point is held, 1 … 65535. At 2 Mbit/s a frame is 10 µs, so the
        default 3 gives the paper's 30 µs between points.
    amp_x, amp_y : int
        Amplitude, unsigned Q1.15 (32768 = the table's full swing reaches the field edge).
    center_x, center_y : int
        Pattern centre in galvo units (32768 = field centre).
    x_range, y_range : tuple of int
        ``(first, last)`` ROM addresses walked by each axis, inclusive. The paper's
        ``(0, 127)`` and ``(1, 126)`` make the ellipse precess.
    run : bool
        Start sweeping out of reset.
    mode : str
        Scan mode out of reset: ``"spiral"``, ``"raster"`` or ``"vector"``.
    """

    def __init__(self, *, dwell=3, amp_x=AMP_ONE, amp_y=AMP_ONE,
                 center_x=FIELD_CENTRE, center_y=FIELD_CENTRE,
                 x_range=(0, 127), y_range=(1, 126), run=True, mode="spiral"):
        if mode not in MODES:
            raise ValueError(f"mode must be one of {', '.join(MODES)}, not {mode!r}")
        self.mode = mode
        _check_int("dwell", dwell, 1, 0xFFFF, " frames")
        for name, value in (("amp_x", amp_x), ("amp_y", amp_y)):
            _check_int(name, value, 0, 0xFFFF, " (Q1.15, 32768 = 1.0)")
        for name, value in (("center_x", center_x), ("center_y", center_y)):
            _check_int(name, value, 0, 0xFFFF, " galvo units")
        self.dwell = dwell
        self.amp_x, self.amp_y = amp_x, amp_y
        self.center_x, self.center_y = center_x, center_y
        self.x_range = tuple(x_range)
        self.y_range = tuple(y_range)
        self.run = bool(run)

    def register_resets(self):
        """Reset values of the registers these settings set."""
        return {
            "mode": MODES[self.mode], "run": int(self.run), "dwell": self.dwell,
            "amp_x": self.amp_x, "amp_y": self.amp_y,
            "center_x": self.center_x, "center_y": self.center_y,
            "x_first": self.x_range[0], "x_last": self.x_range[1],
            "y_first": self.y_range[0], "y_last": self.y_range[1],
        }

    def check_ranges(self, points):
        """Raise if the address ranges do not fit a table of ``points`` samples."""
        for name, rng in (("x_range", self.x_range), ("y_range", self.y_range)):
            if len(rng) != 2 or not all(isinstance(v, int) for v in rng) or \
                    not 0 <= rng[0] <= rng[1] < points:
                raise ValueError(f"{name} must be (first, last) with 0 <= first <= last < "
                                 f"{points} (the table size), not {rng!r}")


class GalvoScanTop(wiring.Component):
    """The scan head controller under host control.

    ::

                                                 ┌─▶ spiral sequencer (ROMs) ─┐
        SPI ─┐                                   ├─▶ raster fill              ├─▶ scale ─▶ correction ─▶ XY2-100
        UART ┴▶ command decoder ─▶ register file ┴─▶ vector queue ─▶ DDA ────┘  /offset   (n×n table)   PHY
                                                  laser controller ◀── marking, pulse timing

    Parameters
    ----------
    clk_freq : int or float
        Frequency of ``clk`` in Hz.
    bit_rate : int or float
        XY2 bit rate in Hz (2 MHz: XY2-100). ``clk_freq / bit_rate`` must be an even integer.
    baud : int
        UART rate (8N1).
    table : :class:`SpiralTable`
        Spiral angle tables (default: 128 Gaussian-sampled points).
    settings : :class:`ScanSettings`
        What the scan registers reset to.
    mo_lead : float
        Seconds the laser's master oscillator leads emission (5 ms, as the paper).
    modes : tuple of str
        Scan modes built in (some of ``"spiral"``, ``"raster"``, ``"vector"``).
    correction : :class:`CorrectionTable` or None
        Distortion correction table the RAM starts with (default: the identity on
        :data:`DEFAULT_CORRECTION_NODES` nodes per axis); ``None`` builds no correction stage.
    multiplier : str
        The scale stage's products: ``"dsp"`` (one DSP block per axis) or ``"serial"``
        (shift-and-add, for FPGAs without DSPs; needs ``correction=None``).
    links : tuple of str
        Host links built: ``"spi"`` and/or ``"uart"``. The pins of a link left out do nothing.
    laser : bool
        Build the laser controller. Without it the laser pins stay low, its registers are
        unknown addresses, and vector mode (timed by the laser's pulses) cannot be built.
    uart_reply_depth : int
        Read answers the UART port queues (1 on the smallest boards).

    Interface attributes
    --------------------
    xy2_clk, xy2_sync, xy2_x, xy2_y : ``Out(1)``
        XY2-100 bus to the scan head, single-ended (add an RS-422 driver).
    spi_sck, spi_cs_n, spi_copi : ``In(1)``; spi_cipo : ``Out(1)``
        SPI target, mode 0, SCK up to ``clk_freq / 12``.
    uart_rx : ``In(1)``; uart_tx : ``Out(1)``
        Serial port, 8N1 at ``baud``.
    laser_power : ``Out(8)``; laser_latch, laser_mo, laser_am, laser_prr : ``Out(1)``
        DB25 pins 1-8, 9, 18, 19, 20 of a fiber laser (through 5 V TTL buffers).
    interlock_open : ``In(1, init=1)``
        1 = interlock open (give the pin a pull-up, so a broken loop reads open).
    """

    xy2_clk: Out(1)
    xy2_sync: Out(1)
    xy2_x: Out(1)
    xy2_y: Out(1)
    spi_sck: In(1)
    spi_cs_n: In(1, init=1)
    spi_copi: In(1)
    spi_cipo: Out(1)
    uart_rx: In(1, init=1)
    uart_tx: Out(1, init=1)
    laser_power: Out(8)
    laser_latch: Out(1)
    laser_mo: Out(1)
    laser_am: Out(1)
    laser_prr: Out(1)
    interlock_open: In(1, init=1)

    def __init__(self, *, clk_freq, bit_rate=2_000_000, baud=115_200, table=None,
                 settings=None, mo_lead=5e-3, modes=tuple(MODES), correction="identity",
                 multiplier="dsp", links=("spi", "uart"), laser=True,
                 uart_reply_depth=REPLY_QUEUE_DEPTH):
        self.table = SpiralTable() if table is None else table
        self.settings = ScanSettings() if settings is None else settings
        if not isinstance(self.table, SpiralTable):
            raise TypeError(f"table must be a SpiralTable, not {self.table!r}")
        if not isinstance(self.settings, ScanSettings):
            raise TypeError(f"settings must be ScanSettings, not {self.settings!r}")
        self.settings.check_ranges(self.table.points)
        modes = tuple(modes)
        if not modes or any(mode not in MODES for mode in modes) or len(set(modes)) != len(modes):
            raise ValueError(f"modes must be some of {', '.join(MODES)}, each once, not {modes!r}")
        if self.settings.mode not in modes:
            raise ValueError(f"the settings start in {self.settings.mode} mode, which modes "
                             f"{modes!r} leaves out")
        self.modes = modes
        # Checked here so that a bad clock shows at construction, not deep in elaboration.
        clocks_per_bit(clk_freq, bit_rate)
        if isinstance(correction, str) and correction == "identity":
            correction = CorrectionTable.identity(DEFAULT_CORRECTION_NODES)
        if correction is not None and not isinstance(correction, CorrectionTable):
            raise TypeError(f"correction must be a CorrectionTable or None, not {correction!r}")
        self.correction = correction
        if multiplier not in ("dsp", "serial"):
            raise ValueError(f"multiplier must be dsp or serial, not {multiplier!r}")
        if multiplier == "serial" and correction is not None:
            raise ValueError("the serial multiplier is for FPGAs without DSP blocks, where the "
                             "correction stage does not fit: build it with correction=None")
        self.multiplier = multiplier
        links = tuple(links)
        if not links or any(link not in ("spi", "uart") for link in links) or \
                len(set(links)) != len(links):
            raise ValueError(f"links must be some of spi, uart, each once, not {links!r}")
        self.links = links
        self.laser = bool(laser)
        self.uart_reply_depth = uart_reply_depth
        if not self.laser and "vector" in modes:
            raise ValueError("vector mode times its points by the laser's pulses: it needs the "
                             "laser controller")
        self.uart_divisor = uart_divisor(clk_freq, baud)
        if not mo_lead > 0:
            raise ValueError(f"mo_lead must be a positive time in seconds, not {mo_lead!r}")
        self.mo_lead = mo_lead
        self.clk_freq = clk_freq
        self.bit_rate = bit_rate
        self.baud = baud
        super().__init__()

    def elaborate(self, platform):
        m = Module()

        # --- host link ----------------------------------------------------------------------
        m.submodules.decoder = decoder = CommandDecoder()
        last_address = self.table.points - 1
        m.submodules.registers = regs = RegisterFile(
            resets=self.settings.register_resets(),
            highs={**{name: last_address for name in ("x_first", "x_last", "y_first", "y_last")},
                   **({"cor_node": self.correction.n ** 2 - 1} if self.correction else {})},
            choices={"mode": {MODES[mode] for mode in self.modes}},
            leave_out=[name for mode, names in MODE_REGISTERS.items() if mode not in self.modes
                       for name in names] +
                      (list(CORRECTION_REGISTERS) if self.correction is None else []) +
                      ([] if self.laser else list(LASER_REGISTERS)))

        # A link left out of the build: its pins are unused (the outputs idle) and the decoder
        # never hears from it.
        if "spi" in self.links:
            m.submodules.spi = spi = SPITarget()
            m.d.comb += [
                spi.sck.eq(self.spi_sck),
                spi.cs_n.eq(self.spi_cs_n),
                spi.copi.eq(self.spi_copi),
                self.spi_cipo.eq(spi.cipo),
            ]
            connect(m, spi.frames, decoder.spi_frames)
            connect(m, decoder.spi_replies, spi.replies)
        else:
            m.d.comb += decoder.spi_replies.ready.eq(1)
        if "uart" in self.links:
            m.submodules.uart = uart = UARTCommandPort(divisor=self.uart_divisor,
                                                       reply_depth=self.uart_reply_depth)
            m.d.comb += [uart.rx.eq(self.uart_rx), self.uart_tx.eq(uart.tx)]
            connect(m, uart.frames, decoder.uart_frames)
            connect(m, decoder.uart_replies, uart.replies)
        else:
            m.d.comb += [decoder.uart_replies.ready.eq(1), self.uart_tx.eq(1)]
        connect(m, decoder.bus, regs.bus)

        # --- scan ---------------------------------------------------------------------------
        # With a correction stage, it holds the point between frames, and the scale stage is
        # combinational in front of it: either way one point waits for the PHY, never two.
        m.submodules.scale = scale = ScaleOffset(buffered=self.correction is None,
                                                 multiplier=self.multiplier)
        m.submodules.phy = phy = XY2Transmitter(clk_freq=self.clk_freq, bit_rate=self.bit_rate)
        for name in ("amp_x", "amp_y", "center_x", "center_y"):
            m.d.comb += getattr(scale, name).eq(getattr(regs, name))

        sources = {}
        if "spiral" in self.modes:
            m.submodules.spiral = spiral = SpiralSequencer(self.table)
            # Registers and ports of the same name.
            for name in ("dwell", "x_first", "x_last", "y_first", "y_last"):
                m.d.comb += getattr(spiral, name).eq(getattr(regs, name))
            sources["spiral"] = spiral
        if "raster" in self.modes:
            m.submodules.raster = raster = RasterSequencer()
            m.d.comb += [
                raster.x.eq(regs.ras_x), raster.y.eq(regs.ras_y),
                raster.width.eq(regs.ras_w), raster.height.eq(regs.ras_h),
                raster.spacing.eq(regs.ras_spacing), raster.step.eq(regs.ras_step),
                raster.along_y.eq(regs.ras_flags[0]), raster.one_way.eq(regs.ras_flags[1]),
                raster.turn_gate.eq(regs.ras_turn_gate),
            ]
            sources["raster"] = raster
        if "vector" in self.modes:
            m.submodules.vector = vector = VectorSequencer()
            for name in ("pitch", "pulses_per_point", "jump_delay"):
                m.d.comb += getattr(vector, name).eq(getattr(regs, name))
            sources["vector"] = vector

        # The selected source feeds the scale stage; the others are stopped.
        running = Signal()
        for name, source in sources.items():
            selected = regs.mode == MODES[name]
            m.d.comb += [
                source.run.eq(regs.run & selected),
                source.frame_strobe.eq(phy.frame_strobe),
            ]
            with m.If(selected):
                m.d.comb += [
                    scale.offsets.valid.eq(source.points.valid),
                    scale.offsets.payload.eq(source.points.payload),
                    source.points.ready.eq(scale.offsets.ready),
                    running.eq(source.run),
                ]
        clipped = Signal()
        if self.correction is None:
            connect(m, scale.positions, phy.position)
            m.d.comb += clipped.eq(scale.clipped)
        else:
            m.submodules.correction = correction = FieldCorrection(self.correction)
            connect(m, scale.positions, correction.positions_in)
            connect(m, correction.positions_out, phy.position)
            m.d.comb += [
                correction.enable.eq(regs.cor_enable),
                correction.write_node.eq(regs.cor_node),
                correction.write_dx.eq(regs.cor_dx),
                correction.write_dy.eq(regs.cor_dy),
                correction.write_en.eq(regs.cor_write),
                regs.cor_nodes.eq(self.correction.n),
                clipped.eq(scale.clipped | correction.clipped),
            ]

        for name in ("xy2_clk", "xy2_sync", "xy2_x", "xy2_y"):
            m.d.comb += getattr(self, name).eq(getattr(phy, name))

        # --- vector queue -------------------------------------------------------------------
        if "vector" in self.modes:
            # A write of vec_op queues (op, vec_x, vec_y); the register file refuses it when
            # the queue is full, and the refusal is counted.
            m.submodules.queue = queue = SyncFIFOBuffered(width=VectorCommand.size,
                                                          depth=VECTOR_QUEUE_DEPTH)
            m.d.comb += [
                queue.w_en.eq(regs.vec_op_push),
                queue.w_data.eq(Cat(decoder.bus.write_data[0], regs.vec_x, regs.vec_y)),
                regs.vec_op_ready.eq(queue.w_rdy),
                vector.commands.valid.eq(queue.r_rdy),
                vector.commands.payload.eq(queue.r_data),
                queue.r_en.eq(vector.commands.ready),
                regs.fifo_free.eq(VECTOR_QUEUE_DEPTH - queue.level),
                regs.status[STATUS_BITS["vector_busy"]].eq(vector.busy),
            ]
            counters = (("vec_rejected", decoder.write_refused &
                         (decoder.bus.address == BY_NAME["vec_op"].address)),
                        ("vec_underruns", vector.underrun), ("vec_stalls", vector.stall))
            for name, event in counters:
                count = Signal(16, name=name)
                with m.If(event & (count != 0xFFFF)):
                    m.d.sync += count.eq(count + 1)
                m.d.comb += getattr(regs, name).eq(count)

        # --- laser --------------------------------------------------------------------------
        # A build without the laser controller (the smallest boards) leaves the laser pins
        # low: nothing can switch a laser on.
        if self.laser:
            self._elaborate_laser(m, decoder, regs, phy, sources)

        # --- status -------------------------------------------------------------------------
        clipped_since_read = Signal()
        with m.If(clipped):
            m.d.sync += clipped_since_read.eq(1)
        with m.Elif(decoder.status_read):
            m.d.sync += clipped_since_read.eq(0)
        m.d.comb += [
            regs.status[STATUS_BITS["running"]].eq(running),
            regs.status[STATUS_BITS["clipped"]].eq(clipped_since_read),
            regs.status[STATUS_BITS["interlock_open"]].eq(self.interlock_open),
            regs.errors.eq(decoder.errors),
        ]
        return m

    def _elaborate_laser(self, m, decoder, regs, phy, sources):
        """The laser controller, its marking signal, pulse counter and status bits."""
        # Pulse-synchronous sources count the PRR clock ahead by the two frames a point takes
        # to reach the head (into the scale stage's buffer, then onto the wires), plus the
        # clock modulation takes to follow `marking`.
        frame_clocks = FRAME_BITS * clocks_per_bit(self.clk_freq, self.bit_rate)
        lookahead = 2 * frame_clocks + 1 if "vector" in self.modes else 0
        m.submodules.laser = laser = LaserController(clk_freq=self.clk_freq,
                                                     mo_lead=self.mo_lead, lookahead=lookahead)
        # The watchdog hears of an accepted frame a clock later: that takes the decoder's
        # checks off the path into the laser's timers (the longest path otherwise).
        command_seen = Signal()
        m.d.sync += command_seen.eq(decoder.accepted)
        marking = Signal()
        if "spiral" in self.modes:
            # Spiral: marking while it runs, from its first point on (not while parked).
            spiral_marking = Signal()
            spiral = sources["spiral"]
            with m.If(~spiral.run):
                m.d.sync += spiral_marking.eq(0)
            with m.Elif(spiral.points.valid & spiral.points.ready):
                m.d.sync += spiral_marking.eq(1)
            with m.If(regs.mode == MODES["spiral"]):
                m.d.comb += marking.eq(spiral_marking)
        if "vector" in self.modes:
            m.d.comb += sources["vector"].pulse_ahead.eq(laser.pulse_ahead)
        # Raster and vector: each frame's laser decision, from the moment that frame has been
        # sent: two frame strobes after it was made.
        framed = [sources[name] for name in ("raster", "vector") if name in sources]
        if framed:
            decided = Signal()
            frame_marking = Signal()
            with m.If(phy.frame_strobe):
                m.d.sync += [
                    decided.eq(Cat((regs.mode == MODES[name]) & sources[name].laser
                                   for name in ("raster", "vector") if name in sources).any()),
                    frame_marking.eq(decided),
                ]
            with m.If(regs.mode != MODES["spiral"]):
                m.d.comb += marking.eq(frame_marking)
        m.d.comb += [
            laser.arm.eq(regs.arm),
            laser.power.eq(regs.laser_power),
            laser.prr.eq(regs.laser_prr),
            laser.watchdog_ms.eq(regs.watchdog),
            laser.alive.eq(command_seen),
            laser.fault_clear.eq(regs.fault_clear),
            laser.marking.eq(marking),
            laser.interlock_open.eq(self.interlock_open),
        ]
        for name in ("laser_power", "laser_latch", "laser_mo", "laser_am", "laser_prr"):
            m.d.comb += getattr(self, name).eq(getattr(laser, name))
        pulses = Signal(16)
        with m.If(laser.pulse):
            m.d.sync += pulses.eq(pulses + 1)
        m.d.comb += [
            regs.pulses.eq(pulses),
            regs.status[STATUS_BITS["armed"]].eq(regs.arm),
            regs.status[STATUS_BITS["fault_interlock"]].eq(laser.faults[FAULT_BITS["interlock"]]),
            regs.status[STATUS_BITS["fault_watchdog"]].eq(laser.faults[FAULT_BITS["watchdog"]]),
            regs.status[STATUS_BITS["mo_on"]].eq(laser.laser_mo),
            regs.status[STATUS_BITS["emitting"]].eq(laser.laser_am),
        ]

