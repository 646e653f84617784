"""The galvoscan system, independent of any board (README "What it does").

Its ports are plain one-bit wires with fixed names, so the exported Verilog drops into other
designs: ``clk``, ``rst`` (synchronous, active high), the scan head bus ``xy2_clk``,
``xy2_sync``, ``xy2_x``, ``xy2_y``, the host link ``spi_sck``, ``spi_cs_n``, ``spi_copi``,
``spi_cipo``, ``uart_rx``, ``uart_tx``, and the laser's DB25 signals ``laser_power[7:0]``,
``laser_latch``, ``laser_mo``, ``laser_am``, ``laser_prr``, the buffers' ``laser_enable``,
the guide laser's ``laser_guide``,
and the inputs ``interlock_open`` and ``laser_alarm[n-1:0]`` (``n`` = ``laser_alarms``);
with the job player, the configuration flash's ``flash_cs_n``, ``flash_clk``, ``flash_copi``,
``flash_cipo``, the start inputs ``start_n[1:0]`` and the outputs ``busy``, ``ready`` and
``player_led``; with the head status receiver, the head's ``xy2_status``; with marking on the
fly, the encoders' ``encoder_x_a``, ``encoder_x_b``, ``encoder_y_a``, ``encoder_y_b``; with
the Z channel, its data line ``xy2_z``; with I/O in the queue, ``io_in[1:0]`` and
``io_out[1:0]``.
"""

from amaranth.hdl import Cat, Const, Module, Mux, ResetInserter, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out, connect

from .build_config import MODES, BuildConfig
from .field.correction import FieldCorrection
from .field.correction_table import CorrectionTable
from .field.scale import ScaleOffset
from .flash.spi_flash import SPIFlashReader
from .host.bus_arbiter import BusArbiter
from .host.command import CommandDecoder
from .host.frames import PAYLOAD_BITS
from .host.progress import ProgressFeed
from .host.registers import RegisterFile
from .host.regmap import (DEFAULT_CORRECTION_NODES, VECTOR_QUEUE_DEPTH, FlyControl, HeadStatus,
                          Mode,
                          PlayerResult, PlayerState, PlayerStatus)
from .host.spi_target import SPITarget
from .host.status import StatusBlock
from .host.uart_port import UARTCommandPort
from .laser.controller import LaserController
from .laser.marking_select import MarkingSelect
from .phy.xy2_100 import FRAME_BITS, XY2Transmitter
from .phy.xy2_status import XY2StatusReceiver
from .fly.encoder import QuadratureDecoder, SimulatedEncoder
from .fly.offset import ClippedOnWires, FlyOffset
from .fly.scale import FlyScale
from .player.player import JobPlayer
from .player.start_input import StartInput
from .settings import ScanSettings
from .sources.raster import RasterSequencer
from .sources.select import SourceSelect
from .sources.spiral import SpiralSequencer
from .sources.spiral_table import SpiralTable
from .sources.laser_delays import LaserDelays
from .sources.vector import DirectedVectorSequencer, VectorSequencer
from .sources.vector_queue import VectorQueue
from .sources.queue_io import IO_INPUTS, IO_OUTPUTS, QueueIO
from .sources.wobble import Wobble


__all__ = ["GalvoScanTop", "BuildConfig", "ScanSettings", "MODES", "VECTOR_QUEUE_DEPTH",
           "DEFAULT_CORRECTION_NODES"]


# The correction stage finishes a point within the shortest possible frame (two clocks per
# bit), so a point taken at a frame boundary is always ready for the next one.
assert FieldCorrection.CLOCKS + 1 < 2 * FRAME_BITS
# So does a vector point the wobble stage has offset.
assert Wobble.CLOCKS + FieldCorrection.CLOCKS + 1 < 2 * FRAME_BITS


class GalvoScanTop(wiring.Component):
    """The scan head controller under host control.

    ::

                                                 ┌─▶ spiral sequencer (ROMs) ─┐  source
        SPI ─┐                                   ├─▶ raster fill              ├─▶ select ─▶ scale ─▶ correction ─▶ XY2-100
        UART ┴▶ command decoder ─▶ register file ┴─▶ vector queue ─▶ DDA ────┘  (mode)     /offset   (n×n table)   PHY
                           status block (flags, counters) ◀─┘  laser controller ◀── marking select (per mode), pulse timing

    Every option of the build (and the rules they keep) is its :attr:`config`; every register
    fact (which registers, their ranges and resets) comes from :attr:`regmap`, the
    configuration's :meth:`~.build_config.BuildConfig.register_map`.

    Parameters
    ----------
    config : :class:`~.build_config.BuildConfig`, optional
        The build's options (modes, clock, links, laser, player …), checked there. None: one
        made of ``options``.
    table : :class:`SpiralTable`
        Spiral angle tables (default: 128 Gaussian-sampled points).
    settings : :class:`ScanSettings`
        What the scan registers reset to.
    correction : :class:`CorrectionTable` or str or None
        Distortion correction table the RAM starts with (``"identity"``, the default: the
        identity on :data:`DEFAULT_CORRECTION_NODES` nodes per axis). Without ``config``,
        ``None`` builds no correction stage; with one, the table is used only if the
        configuration has the stage.
    options
        Without ``config``: :class:`~.build_config.BuildConfig`'s options (``clk_freq``,
        ``modes`` …), for a top built here and there in tests and simulations.

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
    laser_enable : ``Out(1)``
        High only while armed with no fault, the interlock closed and no alarm: the output
        enable of those buffers (pulled down on the board: off before configuration). Every
        laser output is low while it is low.
    laser_guide : ``Out(1)``
        The guide (red pointer) laser, from the ``guide`` register; off while armed. Which
        DB25 pin takes it differs between lasers.
    interlock_open : ``In(1, init=1)``
        1 = interlock open (give the pin a pull-up, so a broken loop reads open).
    laser_alarm : ``In(laser_alarms, init=all ones)``, when ``laser_alarms`` > 0
        The laser's alarm outputs, 1 = alarm (give the pins pull-ups, so an unconnected one
        reads as an alarm).
    flash_cs_n, flash_clk, flash_copi : ``Out(1)``; flash_cipo : ``In(1)``, with the player
        The configuration flash, read after configuration.
    start_n : ``In(2, init=0b11)``, with the player
        Start inputs (a foot switch, the board's button), 0 = pressed; give them pull-ups.
    busy, ready : ``Out(1)``, with the player
        For a PLC: the player is checking or playing its job; armed and past the MO lead (a
        host's job too).
    player_led : ``Out(1)``, with the player
        On while the player is busy; blinking while the last start's image was refused.
    encoder_x_a, encoder_x_b, encoder_y_a, encoder_y_b : ``In(1)``, with marking on the fly
        The belt's quadrature encoders (ENCODER X and Y, through RS-422 receivers).
    xy2_status : ``In(1)``, with the head status receiver
        The scan head's STATUS line (through an RS-422 receiver; low with no head, which then
        reads as missing).
    xy2_z : ``Out(1)``, with the Z channel
        XY2-100's Z data line (a focus shifter), in the same frames as X and Y.
    io_in : ``In(2)``, with I/O in the queue
        Inputs the queue waits on (a part sensor; through optocouplers), 1 = high.
    io_out : ``Out(2)``, with I/O in the queue
        Outputs the queue sets (to a PLC; through optocouplers); low from power-up.

    Attributes
    ----------
    config : :class:`~.build_config.BuildConfig`
        This build's options.
    regmap : :class:`~.host.regmap.RegisterMap`
        This build's registers.
    """

    def __init__(self, config=None, *, table=None, settings=None, correction="identity",
                 **options):
        if config is None:
            config = BuildConfig(correction=correction is not None, **options)
        elif options:
            raise TypeError(f"give the build's options in its BuildConfig, not as "
                            f"{', '.join(options)}")
        if not isinstance(config, BuildConfig):
            raise TypeError(f"config must be a BuildConfig, not {config!r}")
        self.config = config
        self.table = SpiralTable() if table is None else table
        self.settings = ScanSettings() if settings is None else settings
        if not isinstance(self.table, SpiralTable):
            raise TypeError(f"table must be a SpiralTable, not {self.table!r}")
        if not isinstance(self.settings, ScanSettings):
            raise TypeError(f"settings must be ScanSettings, not {self.settings!r}")
        self.settings.check_ranges(self.table.points)
        if self.settings.mode not in config.modes:
            raise ValueError(f"the settings start in {self.settings.mode} mode, which modes "
                             f"{config.modes!r} leaves out")
        if not config.correction:
            correction = None
        elif isinstance(correction, str) and correction == "identity":
            correction = CorrectionTable.identity(DEFAULT_CORRECTION_NODES)
        elif not isinstance(correction, CorrectionTable):
            raise TypeError(f"correction must be a CorrectionTable or None, not {correction!r}")
        self.correction = correction
        #: This build's registers: what the register file holds and the host may write.
        self.regmap = config.register_map(
            table_points=self.table.points,
            correction_nodes=None if correction is None else correction.n,
            resets=self.settings.register_resets())
        members = {
            "xy2_clk": Out(1), "xy2_sync": Out(1), "xy2_x": Out(1), "xy2_y": Out(1),
            "spi_sck": In(1), "spi_cs_n": In(1, init=1), "spi_copi": In(1), "spi_cipo": Out(1),
            "uart_rx": In(1, init=1), "uart_tx": Out(1, init=1),
            "laser_power": Out(8), "laser_latch": Out(1), "laser_mo": Out(1),
            "laser_am": Out(1), "laser_prr": Out(1), "laser_enable": Out(1),
            "laser_guide": Out(1),
            "interlock_open": In(1, init=1),
        }
        if self.config.laser_alarms:
            alarms = self.config.laser_alarms
            members["laser_alarm"] = In(alarms, init=2 ** alarms - 1)
        if self.config.player:
            members.update({"flash_cs_n": Out(1, init=1), "flash_clk": Out(1),
                            "flash_copi": Out(1), "flash_cipo": In(1, init=1),
                            "start_n": In(2, init=0b11), "busy": Out(1), "ready": Out(1),
                            "player_led": Out(1)})
        if self.config.head_status:
            members["xy2_status"] = In(1)
        if self.config.fly:
            members.update({f"encoder_{axis}_{line}": In(1) for axis in "xy" for line in "ab"})
        if self.config.z_axis:
            members["xy2_z"] = Out(1)
        if self.config.queue_io:
            members.update({"io_in": In(IO_INPUTS), "io_out": Out(IO_OUTPUTS)})
        super().__init__(members)

    def elaborate(self, platform):
        m = Module()
        self._queue_io = None

        # --- host link ----------------------------------------------------------------------
        m.submodules.decoder = decoder = self._decoder = CommandDecoder()
        regs = RegisterFile(self.regmap, reads_from_ram=self.config.register_reads == "ram")
        # `soft_reset` returns the registers (and below, the vector path and the counters) to
        # their power-up values; the link's own state (its sequence number, its error count)
        # and the laser's latched faults stay.
        m.submodules.registers = ResetInserter(regs.soft_reset)(regs)
        # A segment's end point is all a build without vector mode would not use of a frame.
        kept_bytes = PAYLOAD_BITS // 8 if "vector" in self.config.modes else 4
        # A link left out of the build: its pins are unused (the outputs idle) and the decoder
        # never hears from it.
        if "spi" in self.config.links:
            m.submodules.spi = spi = SPITarget(kept_bits=kept_bytes * 8)
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
        if "uart" in self.config.links:
            m.submodules.uart = uart = UARTCommandPort(
                divisor=self.config.clocking.uart_divisor,
                kept_bytes=kept_bytes)
            m.d.comb += [uart.rx.eq(self.uart_rx), self.uart_tx.eq(uart.tx)]
            connect(m, uart.frames, decoder.uart_frames)
            connect(m, decoder.uart_replies, uart.replies)
        else:
            m.d.comb += [decoder.uart_replies.ready.eq(1), self.uart_tx.eq(1)]
        if self.config.player:
            # The player writes registers on the clocks without a host frame.
            m.submodules.arbiter = arbiter = BusArbiter()
            connect(m, decoder.bus, arbiter.host)
            connect(m, arbiter.bus, regs.bus)
            m.d.comb += arbiter.host_given.eq(decoder.given)
        else:
            connect(m, decoder.bus, regs.bus)

        # Counters the host reads: those of the vector queue stop at their top, the laser's
        # pulses wrap (the host counts by differences).
        status = StatusBlock(
            saturating=[name for name in ("vec_rejected", "vec_underruns", "vec_stalls",
                                          "head_bad", "fly_clipped") if name in self.regmap],
            wrapping=[name for name in ("pulses", "vec_taken") if name in self.regmap])
        m.submodules.status = ResetInserter(regs.soft_reset)(status)
        m.d.comb += [
            regs.link_seq.eq(decoder.seq),
            status.status_read.eq(decoder.status_read),
            status.flags.interlock_open.eq(self.interlock_open),
            regs.status.eq(status.status),
            regs.errors.eq(decoder.errors),
        ]
        for name in status.saturating + status.wrapping:
            m.d.comb += getattr(regs, name).eq(status.counts[name])

        # --- scan ---------------------------------------------------------------------------
        # With a correction stage, it holds the point between frames, and the scale stage is
        # combinational in front of it: either way one point waits for the PHY, never two.
        m.submodules.scale = scale = ScaleOffset(buffered=self.correction is None,
                                                 multiplier=self.config.multiplier)
        m.submodules.phy = phy = self._phy = XY2Transmitter(clk_freq=self.config.clk_freq,
                                                bit_rate=self.config.bit_rate,
                                                z=self.config.z_axis)
        if self.config.z_axis:
            m.d.comb += [phy.z.eq(regs.z), self.xy2_z.eq(phy.xy2_z)]
        for name in ("amp_x", "amp_y", "center_x", "center_y"):
            m.d.comb += getattr(scale, name).eq(getattr(regs, name))

        sources = {}
        if "spiral" in self.config.modes:
            m.submodules.spiral = sources[Mode.SPIRAL] = spiral = SpiralSequencer(
                self.table, interpolation=self.config.spiral_interpolation)
            # Registers and ports of the same name.
            for name in ("dwell", "x_first", "x_last", "y_first", "y_last"):
                m.d.comb += getattr(spiral, name).eq(getattr(regs, name))
            if self.config.spiral_interpolation:
                m.d.comb += spiral.interpolate.eq(regs.spiral_interp)
        if "raster" in self.config.modes:
            m.submodules.raster = sources[Mode.RASTER] = raster = RasterSequencer()
            m.d.comb += [
                raster.x.eq(regs.ras_x), raster.y.eq(regs.ras_y),
                raster.width.eq(regs.ras_w), raster.height.eq(regs.ras_h),
                raster.spacing.eq(regs.ras_spacing), raster.step.eq(regs.ras_step),
                raster.along_y.eq(regs.ras_flags[0]), raster.one_way.eq(regs.ras_flags[1]),
                raster.turn_gate.eq(regs.ras_turn_gate),
            ]
        if "vector" in self.config.modes:
            sequencer = DirectedVectorSequencer if self.config.wobble else VectorSequencer
            vector = sources[Mode.VECTOR] = sequencer(frame_us=int(self.config.frame_us),
                                                      delays=self.config.vector_delays,
                                                      pixel_lines=self.config.pixel_lines)
            # vec_flush (and soft_reset) start the vector path afresh: queue, sequencer (and
            # the wobble and the laser delays, below).
            self._vector_flush = flush = Signal()
            m.d.comb += flush.eq(regs.vec_flush | regs.soft_reset)
            m.submodules.vector = ResetInserter(flush)(vector)
            names = ("pitch", "pulses_per_point", "jump_delay")
            if self.config.vector_delays:
                names += ("mark_delay", "polygon_delay", "polygon_scaled")
            for name in names:
                m.d.comb += getattr(vector, name).eq(getattr(regs, name))
            self._elaborate_vector_queue(m, regs, vector, status)

        m.submodules.select = select = SourceSelect(sources)
        # A latched laser fault stops the scan where it is (the mirrors hold): the segments
        # taken (vec_taken) then say how far a job got.
        self._fault_latched = Signal()
        m.d.comb += [select.mode.eq(regs.mode), select.run.eq(regs.run & ~self._fault_latched)]
        # Each mode's points: the vector sequencer's through the wobble stage, if built.
        streams = {mode: source.points for mode, source in sources.items()}
        clipped = scale.clipped
        if self.config.wobble:
            wobble = Wobble(frame_rate=self.config.bit_rate / FRAME_BITS)
            m.submodules.wobble = ResetInserter(self._vector_flush)(wobble)
            connect(m, vector.points, wobble.line_points)
            m.d.comb += [
                wobble.direction.eq(vector.direction),
                wobble.marking.eq(vector.laser),
                wobble.frame_strobe.eq(phy.frame_strobe),
                wobble.shape.eq(regs.wob_shape),
                wobble.along.eq(regs.wob_along),
                wobble.across.eq(regs.wob_across),
                wobble.frequency.eq(regs.wob_freq),
            ]
            streams[Mode.VECTOR] = wobble.points
            clipped = clipped | wobble.clipped
        for index, (mode, source) in enumerate(sources.items()):
            connect(m, streams[mode], select.sources[index])
            m.d.comb += [
                source.run.eq(select.source_run[index]),
                source.frame_strobe.eq(phy.frame_strobe),
            ]
        connect(m, select.points, scale.offsets)
        m.d.comb += status.flags.running.eq(select.running)

        # Marking on the fly moves each point after the scale (and the wobble) and before the
        # correction, as RTC's does.
        positions = scale.positions
        self._fly_on_wires = Const(0, 1)
        if self.config.fly:
            positions = self._elaborate_fly(m, regs, status, scale.positions)
        if self.correction is None:
            connect(m, positions, phy.position)
            m.d.comb += status.flags.clipped.eq(clipped)
        else:
            m.submodules.correction = correction = FieldCorrection(self.correction)
            connect(m, positions, correction.positions_in)
            connect(m, correction.positions_out, phy.position)
            m.d.comb += [
                correction.enable.eq(regs.cor_enable),
                correction.write_node.eq(regs.cor_node),
                correction.write_dx.eq(regs.cor_dx),
                correction.write_dy.eq(regs.cor_dy),
                correction.write_en.eq(regs.cor_write),
                # A write asked for now, or one still waiting for a point: refuse the next
                # (the stage keeps one write's values).
                regs.cor_write_ready.eq(~regs.cor_write & ~correction.write_pending),
                status.flags.clipped.eq(clipped | correction.clipped),
            ]

        for name in ("xy2_clk", "xy2_sync", "xy2_x", "xy2_y"):
            m.d.comb += getattr(self, name).eq(getattr(phy, name))
        if self.config.fly:
            # The fly's clipped point, followed to the wires (the correction stage holds one
            # point at most): the laser is off while it is sent.
            m.submodules.fly_clipped = clipped_on_wires = ClippedOnWires(
                held=self.correction is not None)
            m.d.comb += [
                clipped_on_wires.entering.eq(self._fly.positions_out.valid &
                                             self._fly.positions_out.ready),
                clipped_on_wires.clipped.eq(self._fly.clipped),
                clipped_on_wires.taken.eq(phy.position.valid & phy.position.ready),
            ]
            self._fly_on_wires = clipped_on_wires.on_wires

        # --- scan head status ---------------------------------------------------------------
        self._head = None
        if self.config.head_status:
            m.submodules.head = head = self._head = XY2StatusReceiver(
                clocks_per_bit=self.config.clocking.clocks_per_bit)
            m.d.comb += [
                head.status_line.eq(self.xy2_status),
                head.frame_strobe.eq(phy.frame_strobe),
                regs.head.eq(head.status),
                status.events.head_bad.eq(head.bad),
            ]

        # --- laser --------------------------------------------------------------------------
        # A build without the laser controller (the smallest boards) leaves the laser pins
        # low: nothing can switch a laser on.
        self._player_alive = Signal()
        if self.config.laser:
            laser = self._elaborate_laser(m, decoder, regs, phy, sources, select, status)
        if self.config.player:
            self._elaborate_player(m, arbiter, regs, phy, sources[Mode.VECTOR], laser, status)
        return m

    def _elaborate_fly(self, m, regs, status, positions):
        """The encoders, the simulated encoder, the fly offset; returns the moved points."""
        control = FlyControl(regs.fly_ctrl)
        # The queue's fly start and end (I/O in the queue), beside the host's fly_ctrl.
        queue_clear, queue_on = Const(0, 1), Const(0, 1)
        if self._queue_io is not None:
            queue_clear, queue_on = self._queue_io.fly_clear, self._queue_io.fly_on
        m.submodules.fly_simulated = simulated = SimulatedEncoder()
        m.d.comb += [simulated.enable.eq(regs.fly_sim_period != 0),
                     simulated.reverse.eq(control.reverse),
                     simulated.period.eq(regs.fly_sim_period)]
        decoders = {}
        for axis in "xy":
            decoders[axis] = decoder = QuadratureDecoder()
            m.submodules[f"encoder_{axis}"] = decoder
            from_simulated = control[f"{axis}_simulated"]
            m.d.comb += [
                decoder.a.eq(Mux(from_simulated, simulated.a, getattr(self, f"encoder_{axis}_a"))),
                decoder.b.eq(Mux(from_simulated, simulated.b, getattr(self, f"encoder_{axis}_b"))),
                decoder.clear.eq(regs.fly_clear | regs.soft_reset | queue_clear),
                getattr(regs, f"enc_{axis}").eq(decoder.count[:16]),
                getattr(regs, f"enc_{axis}_hi").eq(decoder.count[16:]),
                getattr(regs, f"enc_{axis}_bad").eq(decoder.illegal),
            ]
        m.submodules.fly_scale = scale = FlyScale()
        m.d.comb += [
            scale.count_x.eq(decoders["x"].count), scale.count_y.eq(decoders["y"].count),
            scale.scale_x.eq(Cat(regs.fly_scale_x, regs.fly_scale_x_hi)),
            scale.scale_y.eq(Cat(regs.fly_scale_y, regs.fly_scale_y_hi)),
            scale.enable.eq(control.on | queue_on),
        ]
        if self._queue_io is not None:
            m.d.comb += [self._queue_io.count_x.eq(decoders["x"].count),
                         self._queue_io.count_y.eq(decoders["y"].count)]
        m.submodules.fly = fly = self._fly = FlyOffset()
        connect(m, positions, fly.positions_in)
        m.d.comb += [fly.offset_x.eq(scale.offset_x), fly.offset_y.eq(scale.offset_y),
                     ]
        # Counted a clock after the point goes on (the count's clock enable would otherwise end
        # the path from the source select through the scale's multiplier and this stage's sum).
        m.d.sync += status.events.fly_clipped.eq(fly.positions_out.valid &
                                                 fly.positions_out.ready & fly.clipped)
        return fly.positions_out

    def _elaborate_player(self, m, arbiter, regs, phy, vector, laser, status):
        """The job player, its flash reader and start input, and the PLC's lines."""
        m.submodules.flash = flash = SPIFlashReader(clk_freq=self.config.clk_freq)
        m.submodules.start = start = StartInput(inputs=2,
                                                debounce_ms=self.config.start_debounce_ms,
                                                tick_us=int(self.config.frame_us))
        m.submodules.player = player = JobPlayer()
        # What the player hears of the laser and the host, and what it tells the flash
        # reader, a clock late: it waits on all of them anyway, and the flip-flops take the
        # laser's fault logic and the register file's checks off the paths into the reader.
        fault, took_over, laser_ready = Signal(), Signal(), Signal()
        read_start, read_stop = Signal(), Signal()
        m.d.sync += [
            # (A wait for an input that timed out stops a job as a fault does.)
            fault.eq(laser.faults.as_value().any() |
                     (self._queue_io.timed_out if self._queue_io is not None else 0)),
            took_over.eq(arbiter.host_took_over),
            laser_ready.eq(laser.mo_ready & laser.laser_enable),
            read_start.eq(player.read_start), read_stop.eq(player.read_stop),
        ]
        player_status = Signal(PlayerStatus)
        m.d.comb += [player_status.state.eq(player.state),
                     player_status.result.eq(player.result),
                     player_status.refused.eq(player.refused)]
        m.d.comb += [
            self.flash_cs_n.eq(flash.cs_n), self.flash_clk.eq(flash.sck),
            self.flash_copi.eq(flash.copi), flash.cipo.eq(self.flash_cipo),
            flash.address.eq(player.read_address), flash.start.eq(read_start),
            flash.stop.eq(read_stop), player.read_idle.eq(flash.idle),
            start.start_n.eq(self.start_n), start.tick.eq(phy.frame_strobe),
            player.start.eq(start.pressed),
            player.grant.eq(arbiter.grant),
            player.host_took_over.eq(took_over),
            player.queue_ready.eq(self._queue.ready),
            player.queue_empty.eq(self._queue.empty),
            player.vector_busy.eq(self._vector_busy),
            player.laser_ready.eq(laser_ready),
            player.fault.eq(fault),
            self._player_alive.eq(player.alive),
            regs.player.eq(player_status),
            status.flags.player_busy.eq(player.state != PlayerState.IDLE),
            status.flags.job_refused.eq(Cat(player.result == result for result in PlayerResult
                                            if result.refused).any()),
            self.busy.eq(player.state != PlayerState.IDLE),
            self.ready.eq(status.flags.laser_ready),
        ]
        connect(m, flash.data, player.read_data)
        connect(m, player.bus, arbiter.player)
        # The LED: on while busy, blinking (about 3 Hz) after a refused image.
        blink = Signal(15)
        with m.If(phy.frame_strobe):
            m.d.sync += blink.eq(blink + 1)
        m.d.comb += self.player_led.eq(Mux(status.flags.job_refused, blink[-1],
                                           status.flags.player_busy))

    def _elaborate_vector_queue(self, m, regs, vector, status):
        """The queue between the ``vec_op`` register and the vector sequencer."""
        queue = VectorQueue(depth=self.config.vector_queue_depth,
                            delays=self.config.vector_delays,
                            pixel_lines=self.config.pixel_lines,
                            queue_io=self.config.queue_io)
        m.submodules.queue = ResetInserter(self._vector_flush)(queue)
        decoder = self._decoder
        m.d.comb += [
            queue.vec_op.eq(regs.vec_op),
            queue.push.eq(regs.vec_op_push),
            queue.segment.eq(decoder.segment),
            queue.segment_x.eq(decoder.segment_x),
            queue.segment_y.eq(decoder.segment_y),
            queue.vec_x.eq(regs.vec_x),
            queue.vec_y.eq(regs.vec_y),
            regs.vec_op_ready.eq(queue.ready),
            regs.fifo_free.eq(queue.free),
            status.events.vec_rejected.eq(regs.vec_op_refused),
            status.events.vec_stalls.eq(vector.stall),
            # Every command the queue hands on (an I/O word too): how far a job got.
            status.events.vec_taken.eq(queue.commands.valid & queue.commands.ready),
        ]
        # Vector mode is busy while the sequencer marks, or an I/O word holds the queue.
        self._vector_busy = Signal()
        if self.config.queue_io:
            # Its outputs keep their level through a flush (a PLC may be reading them): a
            # soft reset alone clears them.
            self._queue_io = queue_io = QueueIO(frame_us=int(self.config.frame_us),
                                                encoders=self.config.fly)
            m.submodules.queue_io = ResetInserter(regs.soft_reset)(queue_io)
            connect(m, queue.commands, queue_io.commands_in)
            connect(m, queue_io.commands_out, vector.commands)
            m.d.comb += [
                queue_io.sequencer_busy.eq(vector.busy),
                queue_io.frame_strobe.eq(self._phy.frame_strobe),
                queue_io.flush.eq(self._vector_flush),
                queue_io.io_in.eq(self.io_in),
                self.io_out.eq(queue_io.io_out),
                regs.io.eq(queue_io.state),
                self._vector_busy.eq(vector.busy | queue_io.holding),
                # The queue looks empty to the sequencer while an I/O word waits: no underrun.
                status.events.vec_underruns.eq(vector.underrun & ~queue_io.holding),
            ]
        else:
            connect(m, queue.commands, vector.commands)
            m.d.comb += [self._vector_busy.eq(vector.busy),
                         status.events.vec_underruns.eq(vector.underrun)]
        m.d.comb += status.flags.vector_busy.eq(self._vector_busy)
        self._queue = queue

    def _elaborate_laser(self, m, decoder, regs, phy, sources, select, status):
        """The laser controller, its marking signal, pulse counter and status flags."""
        # Pulse-synchronous sources count the PRR clock ahead by the two frames a point takes
        # to reach the head (into the scale stage's buffer, then onto the wires), plus the
        # clock modulation takes to follow `marking`.
        frame_clocks = FRAME_BITS * self.config.clocking.clocks_per_bit
        lookahead = 2 * frame_clocks + 1 if Mode.VECTOR in sources else 0
        m.submodules.laser = laser = LaserController(clk_freq=self.config.clk_freq,
                                                     mo_lead=self.config.mo_lead,
                                                     lookahead=lookahead,
                                                     alarms=self.config.laser_alarms,
                                                     head=self.config.head_status)
        if self.config.head_status:
            # With the check on, a head that says it is too hot or without power, or says
            # nothing, is as an open interlock: the laser off, and latched while armed.
            word = HeadStatus(self._head.status)
            m.d.comb += [
                laser.head_fault.eq(regs.head_check &
                                    (self._head.missing | ~word.temp_ok | ~word.power_ok)),
                regs.head_state.eq(Cat(self._head.missing, laser.faults.head)),
            ]
        # The watchdog is fed by progress only: a segment the host queued, its keepalive, the
        # player's next word; reading registers is no sign that a job goes on. It hears a
        # clock later: that takes the register file's checks off the path into the laser's
        # timers. A frame the link refused latches a link fault while armed.
        m.submodules.progress = progress = ProgressFeed()
        m.d.comb += [progress.segment.eq(decoder.segment), progress.keepalive.eq(regs.keepalive),
                     progress.player.eq(self._player_alive)]
        if "vector" in self.config.modes:
            m.d.comb += progress.pushed.eq(regs.vec_op_push)
        if Mode.VECTOR in sources:
            m.d.comb += sources[Mode.VECTOR].pulse_ahead.eq(laser.pulse_ahead)
        m.submodules.marking = marking = MarkingSelect(modes=sources,
                                                       vector_delays=self.config.vector_delays)
        m.d.comb += [marking.mode.eq(select.mode), marking.frame_strobe.eq(phy.frame_strobe)]
        for mode, selected in zip(sources, select.selected):
            m.d.comb += getattr(marking, f"{mode.label}_selected").eq(selected)
        if Mode.SPIRAL in sources:
            spiral = sources[Mode.SPIRAL]
            m.d.comb += [marking.spiral_run.eq(spiral.run),
                         marking.spiral_point.eq(spiral.points.valid & spiral.points.ready)]
        for mode in marking.framed:
            m.d.comb += getattr(marking, f"{mode.label}_laser").eq(sources[mode].laser)
        if self.config.vector_delays:
            # Vector mode's laser through its delays: the frames' decisions moved by
            # laser_on_delay and laser_off_delay.
            vector = sources[Mode.VECTOR]
            delays = LaserDelays(clocks_per_us=int(self.config.clk_freq / 1e6),
                                 lead_us=2 * int(self.config.frame_us))
            m.submodules.laser_delays = ResetInserter(self._vector_flush)(delays)
            m.d.comb += [
                delays.frame_strobe.eq(phy.frame_strobe),
                delays.run.eq(vector.run),
                delays.decision.eq(vector.laser),
                delays.on_delay.eq(regs.laser_on_delay.as_signed()),
                delays.off_delay.eq(regs.laser_off_delay),
                marking.vector_delayed.eq(delays.marking),
            ]
        m.d.comb += [
            laser.arm.eq(regs.arm),
            laser.power.eq(regs.laser_power),
            laser.prr.eq(regs.laser_prr),
            laser.watchdog_ms.eq(regs.watchdog),
            laser.alive.eq(progress.alive),
            laser.link_fault.eq(decoder.refused),
            self._fault_latched.eq(laser.faults.as_value().any()),
            laser.fault_clear.eq(regs.fault_clear),
            # (A point the fly offset held at the field's edge is never marked.)
            laser.marking.eq(marking.marking & ~self._fly_on_wires),
            laser.interlock_open.eq(self.interlock_open),
            laser.guide.eq(regs.guide),
        ]
        if self.config.laser_alarms:
            m.d.comb += [laser.alarm.eq(self.laser_alarm),
                         status.flags.alarm.eq(self.laser_alarm.any())]
        for name in ("laser_power", "laser_latch", "laser_mo", "laser_am", "laser_prr",
                     "laser_enable", "laser_guide"):
            m.d.comb += getattr(self, name).eq(getattr(laser, name))
        m.d.comb += [
            status.events.pulses.eq(laser.pulse),
            status.flags.armed.eq(regs.arm),
            status.flags.fault_interlock.eq(laser.faults.interlock),
            status.flags.fault_watchdog.eq(laser.faults.watchdog),
            status.flags.fault_alarm.eq(laser.faults.alarm),
            status.flags.fault_link.eq(laser.faults.link),
            status.flags.laser_enable.eq(laser.laser_enable),
            status.flags.laser_ready.eq(laser.mo_ready & laser.laser_enable),
            status.flags.mo_on.eq(laser.laser_mo),
            status.flags.emitting.eq(laser.laser_am),
        ]
        return laser
