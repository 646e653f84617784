"""Every register a build may have, declared once: address, access, reset, range, unit and
what it does (part of the register map, :mod:`.regmap`, which picks a build's registers from
these and re-exports them), and which registers come only with a mode or a build option."""

from dataclasses import dataclass

from amaranth.hdl import Shape

from ..field.correction_table import TABLE_SIZES
from ..field.scale import AMP_ONE
from ..points import FIELD_CENTRE, FIELD_MAX
from ..limits import (LASER_DELAY_MAX_US, LASER_ON_LEAD_US, SCANNER_DELAY_MAX_US,
                      WOBBLE_MAX_AMPLITUDE, WOBBLE_MAX_HZ, WORD_MAX)
from ..fields import Capabilities, HeadState, HeadStatus, Mode, PlayerStatus, Status, WobbleShape


__all__ = ["Register", "all_registers", "MODE_REGISTERS", "WOBBLE_REGISTERS",
           "INTERPOLATION_REGISTERS", "DELAY_REGISTERS", "LASER_REGISTERS",
           "CORRECTION_REGISTERS", "PLAYER_REGISTERS", "HEAD_REGISTERS",
           "FLY_REGISTERS", "Z_REGISTERS", "IO_REGISTERS"]


@dataclass(frozen=True)
class Register:
    name: str
    address: int
    access: str          # "rw", "ro", "strobe" or "queue"
    reset: int
    low: int             # smallest value a write may carry
    high: int            # largest value a write may carry
    unit: str
    description: str
    width: int = 16      # bits that hold state; the frame always carries 16
    #: A strobe the block it acts on can refuse while busy: the register file then refuses
    #: (and the decoder counts) a write of 1 (``<name>_ready`` low).
    refusable: bool = False
    #: The value is two's complement: ``low`` and ``high`` are signed, the frame carries the
    #: value modulo 65536 and the register holds its low ``width`` bits.
    signed: bool = False
    #: A read-only value fixed when the bitstream is built (``reset``, given by the build's
    #: map): the register file reads it from the block RAM that holds the reset values, with
    #: no input and no logic of its own (what a bitstream holds: ``caps``, ``vec_depth``).
    fixed: bool = False
    #: The build options it comes with (all of them): scan modes (``"spiral"``, ``"raster"``,
    #: ``"vector"``) and stages (``"interpolation"``, ``"delays"``, ``"wobble"``,
    #: ``"correction"``, ``"laser"``, ``"player"``, ``"head"``, ``"fly"``); a build without one
    #: answers its address
    #: as unknown.
    needs: tuple = ()

    def encode(self, value):
        """The 16-bit frame data of ``value`` (two's complement for a signed register)."""
        return value & 0xFFFF

    def decode(self, data):
        """The value of 16-bit frame data read back."""
        return data - 0x10000 if self.signed and data & 0x8000 else data

    def as_dict(self):
        return {"name": self.name, "address": self.address, "width": self.width,
                "access": self.access, "reset": self.reset, "min": self.low, "max": self.high,
                "unit": self.unit, "description": self.description}


def _width(high):
    """Bits that hold every value from 0 to ``high``."""
    return max(1, high.bit_length())


def all_registers(table_points, correction_nodes):
    """Every register a build may have, for tables of those sizes."""
    last_address = table_points - 1
    last_node = correction_nodes ** 2 - 1
    address_width = _width(last_address)
    return [
        # --- read-only --------------------------------------------------------------------------
        Register("status", 0x00, "ro", 0, 0, 0, "flags",
                 "bit 0 running (the selected mode), bit 1 a point was clamped at the field edge (by the scale or "
                 "the correction stage) since the last read of status (cleared by reading), bit 2 armed, bit 3 interlock fault (latched), "
                 "bit 4 watchdog fault (latched), bit 5 MO on, bit 6 emitting, bit 7 interlock "
                 "open now, bit 8 vector mode busy (segments queued or points still to mark), "
                 "bit 9 alarm fault (latched), bit 10 a laser alarm input active now, bit 11 "
                 "laser_enable (the laser's buffers enabled), bit 12 laser ready (armed and MO "
                 "on for the MO lead: a job may start), bit 13 the job player busy, bit 14 the "
                 "player refused the flash's job at the last start, bit 15 link fault (latched: the host "
                 "link refused a frame while armed)",
                 width=Status.size),
        Register("errors", 0x01, "ro", 0, 0, 0, "frames",
                 "refused command frames since power-up (a CRC that fails, cut short or run over, "
                 "a UART framing error, a write out of sequence, an unknown address, a write to "
                 "a read-only register, a value out of range, the queue full); stops at 65535"),
        Register("link_seq", 0x18, "ro", 0, 0, 0, "frame",
                 "the sequence number the next write frame must carry (a write with another is "
                 "refused); goes up by one, modulo 256, with each write taken", width=8),
        Register("keepalive", 0x19, "strobe", 0, 0, 1, "write 1",
                 "feeds the watchdog while armed: a host that waits on an armed board (the MO "
                 "lead, the queue emptying, a spiral) writes it; reads do not feed it",
                 width=1, needs=('laser',)),
        Register("soft_reset", 0x1A, "strobe", 0, 0, 1, "write 1",
                 "returns every writable register to its power-up value (arm = 0: the laser "
                 "off), empties the vector queue and stops vector mode, and clears the "
                 "counters; keeps latched faults (fault_clear clears them), errors and "
                 "link_seq (the link's own record)", width=1),
        Register("caps", 0x0E, "ro", 0, 0, 0, "flags",
                 "what this bitstream holds, a bit each (1: built): " + ", ".join(
                     f"bit {field.offset} {name}" for name, field in Capabilities) +
                 "; the host reads it instead of trying writes; fixed when it is built",
                 width=Capabilities.size, fixed=True),
        Register("vec_depth", 0x0F, "ro", 0, 0, 0, "segments",
                 "segments this bitstream's vector queue holds (0: no vector mode); fixed when "
                 "it is built", fixed=True),
        # --- galvo group ------------------------------------------------------------------------
        Register("mode", 0x02, "rw", Mode.SPIRAL.value, 0, len(Mode) - 1, "enum",
                 "scan mode: 0 = spiral, 1 = raster (line-by-line fill), 2 = vector (queued "
                 "jump/mark segments)", width=Shape.cast(Mode).width),
        Register("run", 0x03, "rw", 1, 0, 1, "bool",
                 "1 = sweep; 0 = stop (the mirrors hold the last point; the next start begins the "
                 "spiral or raster again; the vector queue is kept)", width=1),
        Register("dwell", 0x04, "rw", 3, 1, WORD_MAX, "frames (10 µs)",
                 "frames each spiral point is held; 3 = 30 µs, the paper's figure",
                 needs=('spiral',)),
        Register("amp_x", 0x05, "rw", AMP_ONE, 0, WORD_MAX, "Q1.15 (32768 = 1.0)",
                 "X amplitude: 32768 makes the table's full swing reach the field edge"),
        Register("amp_y", 0x06, "rw", AMP_ONE, 0, WORD_MAX, "Q1.15 (32768 = 1.0)",
                 "Y amplitude"),
        Register("center_x", 0x07, "rw", FIELD_CENTRE, 0, FIELD_MAX, "galvo units",
                 "X centre of the pattern (32768 = field centre)"),
        Register("center_y", 0x08, "rw", FIELD_CENTRE, 0, FIELD_MAX, "galvo units",
                 "Y centre of the pattern"),
        Register("x_first", 0x09, "rw", 0, 0, last_address, "ROM address",
                 "first X table address walked (inclusive); if above x_last, X holds x_first; "
                 "the four address registers go up to the build's table points - 1 (127 by "
                 "default, `--table-points`)",
                 width=address_width,
                 needs=('spiral',)),
        Register("x_last", 0x0A, "rw", last_address, 0, last_address, "ROM address",
                 "last X table address walked (inclusive)", width=address_width,
                 needs=('spiral',)),
        Register("y_first", 0x0B, "rw", 1, 0, last_address, "ROM address",
                 "first Y table address walked (inclusive); the paper's 1…126 against X's 0…127 "
                 "makes the ellipse precess", width=address_width,
                 needs=('spiral',)),
        Register("y_last", 0x0C, "rw", last_address - 1, 0, last_address, "ROM address",
                 "last Y table address walked (inclusive)", width=address_width,
                 needs=('spiral',)),
        Register("spiral_interp", 0x0D, "rw", 1, 0, 1, "enum",
                 "between spiral points: 0 = hold each point for dwell frames, then jump; 1 = "
                 "linear, every frame moves part of the way to the next point (same points at "
                 "the same times; dwells over 255 frames are held); see README \"Held points\"",
                 width=1,
                 needs=('spiral', 'interpolation')),
        # --- vector group -----------------------------------------------------------------------
        Register("vec_x", 0x20, "rw", FIELD_CENTRE, 0, FIELD_MAX, "galvo units",
                 "X of the next segment's end point (offset binary, 32768 = centre)",
                 needs=('vector',)),
        Register("vec_y", 0x21, "rw", FIELD_CENTRE, 0, FIELD_MAX, "galvo units",
                 "Y of the next segment's end point",
                 needs=('vector',)),
        Register("vec_op", 0x22, "queue", 0, 0, 255, "enum + factor",
                 "writing queues a segment to (vec_x, vec_y): bit 0: 0 = jump (laser off, then "
                 "jump_delay), 1 = mark (laser on, points every pitch); bits 7:1 of a mark: the hold "
                 "in 10 µs frames of the corner it leaves, if polygon_scaled; refused if the "
                 "queue is full", width=8,
                 needs=('vector',)),
        Register("fifo_free", 0x23, "ro", 0, 0, 0, "segments",
                 "free places in the vector queue",
                 needs=('vector',)),
        Register("pitch", 0x24, "rw", 60, 1, WORD_MAX, "galvo units",
                 "distance between marked points; 60 ≈ 0.1 mm on a 110 mm field, the pitch of Wan et al.",
                 needs=('vector',)),
        Register("pulses_per_point", 0x25, "rw", 1, 1, 255, "laser pulses",
                 "pulses each marked point gets; the line speed is pitch × PRR / pulses_per_point"
                 , width=8,
                 needs=('vector',)),
        Register("jump_delay", 0x26, "rw", 500, 0, WORD_MAX, "µs",
                 "laser-off wait after a jump for the mirrors to settle, before marking resumes; "
                 "rounded up to whole 10 µs frames, at least one",
                 needs=('vector',)),
        Register("vec_rejected", 0x27, "ro", 0, 0, 0, "writes",
                 "vec_op writes refused because the queue was full; stops at 65535",
                 needs=('vector',)),
        Register("vec_underruns", 0x28, "ro", 0, 0, 0, "times",
                 "times the queue ran empty in the middle of marking (the laser stopped and the "
                 "mirrors held until more segments came); stops at 65535",
                 needs=('vector',)),
        Register("vec_stalls", 0x29, "ro", 0, 0, 0, "frames",
                 "frames a marked line waited, laser off, for the next segment to be set up (140 "
                 "clocks: at 12 MHz only after two one-point segments in a row); stops at 65535",
                 needs=('vector',)),
        # The RTC's delays (SCANLAB RTC5/6 manuals; EzCad's start/end/corner TC): the laser
        # ones move the modulation edges to the clock, the scanner ones hold the mirrors for
        # whole frames.
        Register("laser_on_delay", 0x2A, "rw", 100, -LASER_ON_LEAD_US + 1, LASER_DELAY_MAX_US,
                 "µs, two's complement",
                 "laser (DB25 modulation, pin 19) on this long after a mark's first point reaches "
                 "the head; negative switches it on that much earlier, down to -19 µs (the "
                 "sequencer decides two frames ahead); placed to the clock on the modulation edge",
                 width=11, signed=True,
                 needs=('vector', 'delays')),
        Register("laser_off_delay", 0x2B, "rw", 50, 0, LASER_DELAY_MAX_US, "µs",
                 "laser stays on this long after a mark's last point reaches the head (the mirror "
                 "still lags it); placed to the clock on the modulation edge", width=10,
                 needs=('vector', 'delays')),
        Register("mark_delay", 0x2C, "rw", 100, 0, SCANNER_DELAY_MAX_US, "µs",
                 "after a mark followed by a jump, the mirrors hold its end point this long, laser "
                 "off (after laser_off_delay runs out), before the jump; whole 10 µs frames, "
                 "rounded up", width=12,
                 needs=('vector', 'delays')),
        Register("polygon_delay", 0x2D, "rw", 0, 0, SCANNER_DELAY_MAX_US, "µs",
                 "between two marks, the mirrors hold the corner this long with the laser on; "
                 "whole 10 µs frames, rounded up", width=12,
                 needs=('vector', 'delays')),
        Register("polygon_scaled", 0x2E, "rw", 0, 0, 1, "bool",
                 "1 = hold each corner for the frames sent with the mark that leaves it (vec_op "
                 "bits 7:1: the host's polygon delay × (1 - cos φ), RTC's variable polygon "
                 "delay); 0 = polygon_delay at every corner", width=1,
                 needs=('vector', 'delays')),
        Register("vec_taken", 0x1B, "ro", 0, 0, 0, "segments",
                 "segments the vector sequencer has taken from the queue since reset, modulo "
                 "65536: with vector busy clear, every one is marked to its end; while busy, all "
                 "but the last two at most. The sequencer takes none while a fault is latched",
                 needs=('vector',)),
        Register("vec_flush", 0x2F, "strobe", 0, 0, 1, "write 1",
                 "empties the vector queue and stops vector mode where it is (the sequencer, the "
                 "wobble and the laser delays start afresh): a job left half-queued no longer "
                 "refuses the next (galvoscan reset)", width=1,
                 needs=('vector',)),
        # --- wobble group (built with GalvoScanTop(wobble=True)) -------------------------------
        Register("wob_shape", 0x50, "rw", WobbleShape.OFF.value, 0, len(WobbleShape) - 1, "enum",
                 "figure laid over every marked vector point, a new position each frame while "
                 "the point is held: 0 = off, 1 = ellipse (wob_along × wob_across; a circle when "
                 "equal)", width=Shape.cast(WobbleShape).width,
                 needs=('vector', 'wobble')),
        Register("wob_along", 0x51, "rw", 30, 0, WOBBLE_MAX_AMPLITUDE, "galvo units",
                 "wobble amplitude along the line (half the figure's length; the host converts "
                 "µm through the field size: 30 ≈ 50 µm on a 110 mm field)",
                 width=_width(WOBBLE_MAX_AMPLITUDE),
                 needs=('vector', 'wobble')),
        Register("wob_across", 0x52, "rw", 30, 0, WOBBLE_MAX_AMPLITUDE, "galvo units",
                 "wobble amplitude across the line (half the track's added width)",
                 width=_width(WOBBLE_MAX_AMPLITUDE),
                 needs=('vector', 'wobble')),
        Register("wob_freq", 0x53, "rw", 1000, 1, WOBBLE_MAX_HZ, "Hz",
                 "turns of the figure per second (at most a quarter of the 100 kHz frame rate); "
                 "each mark starts at the figure's first point", width=_width(WOBBLE_MAX_HZ),
                 needs=('vector', 'wobble')),
        # --- raster group -----------------------------------------------------------------------
        Register("ras_x", 0x30, "rw", 28768, 0, WORD_MAX, "galvo units",
                 "raster rectangle: X of its lower-left corner",
                 needs=('raster',)),
        Register("ras_y", 0x31, "rw", 28768, 0, WORD_MAX, "galvo units",
                 "raster rectangle: Y of its lower-left corner",
                 needs=('raster',)),
        Register("ras_w", 0x32, "rw", 8000, 0, WORD_MAX, "galvo units",
                 "raster rectangle: width (positions past 65535 are clamped)",
                 needs=('raster',)),
        Register("ras_h", 0x33, "rw", 8000, 0, WORD_MAX, "galvo units",
                 "raster rectangle: height",
                 needs=('raster',)),
        Register("ras_spacing", 0x34, "rw", 30, 1, WORD_MAX, "galvo units",
                 "line spacing; 30 ≈ 0.05 mm on a 110 mm field",
                 needs=('raster',)),
        Register("ras_step", 0x35, "rw", 30, 1, WORD_MAX, "galvo units per frame",
                 "distance along a line per 10 µs frame: the line speed; 30 ≈ 5 m/s on a 110 mm "
                 "field",
                 needs=('raster',)),
        Register("ras_flags", 0x36, "rw", 0, 0, 3, "flags",
                 "bit 0: lines along Y (else X); bit 1: every line in the same direction, with a "
                 "jump back (else serpentine)", width=2,
                 needs=('raster',)),
        Register("ras_turn_gate", 0x37, "rw", 0, 0, WORD_MAX, "frames (10 µs)",
                 "laser off for this many frames at the start of each line but the first, while the "
                 "mirrors turn; 0 keeps it on, as the paper's raster does",
                 needs=('raster',)),
        # --- distortion correction group ------------------------------------------------------
        Register("cor_enable", 0x40, "rw", 1, 0, 1, "bool",
                 "1 = add the correction table's interpolated offset to every point (the identity "
                 "table changes nothing); 0 = positions pass unchanged", width=1,
                 needs=('correction',)),
        Register("cor_node", 0x41, "rw", 0, 0, last_node, "node index",
                 "table node the next cor_write stores: iy × n + ix, n = cor_nodes (node (ix, iy) "
                 "sits at galvo position (ix, iy) × 65536 / (n - 1)); up to n × n - 1",
                 width=_width(last_node),
                 needs=('correction',)),
        Register("cor_dx", 0x42, "rw", 0, 0, WORD_MAX, "galvo units, two's complement",
                 "X offset for cor_write (65535 = -1): added to positions at that node",
                 needs=('correction',)),
        Register("cor_dy", 0x43, "rw", 0, 0, WORD_MAX, "galvo units, two's complement",
                 "Y offset for cor_write",
                 needs=('correction',)),
        Register("cor_write", 0x44, "strobe", 0, 0, 1, "write 1",
                 "stores (cor_dx, cor_dy) at node cor_node, both at once and between two points, so "
                 "no point is made from a half-written node; the values are those of the moment "
                 "of the write. Refused (counted in errors) while the last write still waits for "
                 "a point to finish (at most 16 clocks)", width=1, refusable=True,
                 needs=('correction',)),
        Register("cor_nodes", 0x45, "ro", 0, 0, 0, "nodes",
                 "correction table nodes per axis in this build (5, 9, 17, 33 or 65); fixed "
                 "when it is built", width=_width(max(TABLE_SIZES)), fixed=True,
                 needs=('correction',)),
        # --- laser group ------------------------------------------------------------------------
        Register("arm", 0x10, "rw", 0, 0, 1, "bool",
                 "1 = arm the laser: laser_enable on, latch power, MO on, modulation after the "
                 "MO lead (5 ms) while the spiral runs; 0 = laser_enable and every laser "
                 "output off", width=1,
                 needs=('laser',)),
        Register("laser_power", 0x11, "rw", 0, 0, 255, "1/255 of full power",
                 "laser power on DB25 pins 1-8, latched by pin 9 on arming and on every change "
                 "while armed", width=8,
                 needs=('laser',)),
        Register("laser_prr", 0x12, "rw", 500, 200, 2000, "100 Hz",
                 "pulse repetition rate on DB25 pin 20, 20.0 … 200.0 kHz (500 = 50 kHz), 50 % duty",
                 width=11,
                 needs=('laser',)),
        Register("watchdog", 0x13, "rw", 200, 1, 60000, "ms",
                 "while armed, no progress for this long switches the laser off and latches a "
                 "watchdog fault: progress is a segment queued, a keepalive written or the job "
                 "player's next word; reading registers is none",
                 needs=('laser',)),
        Register("fault_clear", 0x14, "strobe", 0, 0, 1, "write 1",
                 "clears latched faults if the interlock is closed and no alarm is active; the "
                 "laser then stays off until arm is written 0 and 1 again", width=1,
                 needs=('laser',)),
        Register("pulses", 0x15, "ro", 0, 0, 0, "pulses",
                 "laser pulses emitted (PRR rising edges while modulating) since reset, modulo "
                 "65536",
                 needs=('laser',)),
        Register("guide", 0x16, "rw", 0, 0, 1, "bool",
                 "1 = guide (red pointer) laser on, to frame a job with the mirrors; it is off "
                 "whenever arm is set, whatever this holds", width=1,
                 needs=('laser',)),
        # --- job player group (built with GalvoScanTop(player=True)) -------------------------
        Register("player", 0x17, "ro", 0, 0, 0, "fields",
                 "the job player: " + "; ".join(
                     f"bits {field.offset + field.width - 1}:{field.offset} {name}" +
                     (f" ({', '.join(f'{v.value} {v.label}' for v in field.shape)})"
                      if name != "refused" else " (images refused since reset, stops at "
                      "255)")
                     for name, field in PlayerStatus), width=PlayerStatus.size,
                 needs=('player',)),
        # --- scan head status -------------------------------------------------------------------
        Register("head", 0x1C, "ro", 0, 0, 0, "flags",
                 "the scan head's status word off its STATUS line, as RTC5/RTC6's "
                 "get_head_status reads it: " + ", ".join(
                     f"bit {field.offset} {name}" for name, field in HeadStatus
                     if not name.startswith("_")) + "; 0 while no head answers",
                 needs=('head',)),
        Register("head_state", 0x1D, "ro", 0, 0, 0, "flags",
                 "bit 0 missing (no good status frame in the last 8), bit 1 head fault "
                 "(latched: with head_check on, Temp OK or Power OK low, or no head, while "
                 "armed; it disarms as the interlock does, and fault_clear clears it once the "
                 "head is fit)", width=HeadState.size, needs=('head', 'laser')),
        Register("head_check", 0x1E, "rw", 0, 0, 1, "bool",
                 "1 = the laser obeys the head: Temp OK or Power OK low, or no head, keeps "
                 "every laser output off and, while armed, latches the head fault; 0 (for a "
                 "head without a STATUS line) = the head's word is only reported",
                 width=1, needs=('head', 'laser')),
        Register("head_bad", 0x1F, "ro", 0, 0, 0, "frames",
                 "status frames refused (a code other than 001, odd parity, or no head) since "
                 "reset; stops at 65535", needs=('head',)),
        # --- marking on the fly ---------------------------------------------------------------
        Register("fly_ctrl", 0x60, "rw", 0, 0, 15, "flags",
                 "marking on the fly: bit 0 on (each point moved by scale × count on each "
                 "axis, before the correction; 0 = RTC's fly_return: no offset), bit 1 the X "
                 "count from the simulated encoder instead of ENCODER X, bit 2 likewise Y, "
                 "bit 3 the simulated encoder counts down", width=4, needs=('fly',)),
        Register("fly_clear", 0x61, "strobe", 0, 0, 1, "write 1",
                 "zeroes both encoder counts and their illegal-step counts (a part's start: "
                 "RTC's set_fly resets its counter)", width=1, needs=('fly',)),
        Register("fly_scale_x", 0x62, "rw", 0, 0, WORD_MAX, "2^-16 units/count",
                 "the X fly scale's low 16 bits: galvo units a count, 16 fraction bits "
                 "(65536 = one unit a count); its top 8 bits are fly_scale_x_hi",
                 needs=('fly',)),
        Register("fly_scale_x_hi", 0x63, "rw", 0, -128, 127, "2^0 units/count",
                 "the X fly scale's top 8 bits, two's complement (the sign: the belt's "
                 "direction on the field); write it after fly_scale_x, with the fly off",
                 width=8, signed=True, needs=('fly',)),
        Register("fly_scale_y", 0x64, "rw", 0, 0, WORD_MAX, "2^-16 units/count",
                 "the Y fly scale's low 16 bits (as fly_scale_x)", needs=('fly',)),
        Register("fly_scale_y_hi", 0x65, "rw", 0, -128, 127, "2^0 units/count",
                 "the Y fly scale's top 8 bits, two's complement (as fly_scale_x_hi)",
                 width=8, signed=True, needs=('fly',)),
        Register("fly_sim_period", 0x66, "rw", 0, 0, WORD_MAX, "clocks/count",
                 "the simulated encoder (RTC's simulate_encoder, for trials without a belt): "
                 "a count every this many clocks; 0 = stopped", needs=('fly',)),
        Register("enc_x", 0x67, "ro", 0, 0, 0, "counts",
                 "ENCODER X's count, bits 15:0 (every edge counts; stops at its 32-bit ends, "
                 "never wraps)", needs=('fly',)),
        Register("enc_x_hi", 0x68, "ro", 0, 0, 0, "counts",
                 "ENCODER X's count, bits 31:16 (two's complement with enc_x; read hi, lo, hi "
                 "again while the belt moves)", needs=('fly',)),
        Register("enc_y", 0x69, "ro", 0, 0, 0, "counts",
                 "ENCODER Y's count, bits 15:0", needs=('fly',)),
        Register("enc_y_hi", 0x6A, "ro", 0, 0, 0, "counts",
                 "ENCODER Y's count, bits 31:16", needs=('fly',)),
        Register("enc_x_bad", 0x6B, "ro", 0, 0, 0, "steps",
                 "ENCODER X's illegal steps (both lines changed at once: noise, or a belt too "
                 "fast), never counted as a move; stops at 65535", needs=('fly',)),
        Register("enc_y_bad", 0x6C, "ro", 0, 0, 0, "steps",
                 "ENCODER Y's illegal steps", needs=('fly',)),
        Register("fly_clipped", 0x6D, "ro", 0, 0, 0, "points",
                 "points the fly offset pushed off the field, held at its edge with the laser "
                 "off, since reset; stops at 65535", needs=('fly',)),
        # --- Z channel --------------------------------------------------------------------------
        Register("z", 0x70, "rw", FIELD_CENTRE, 0, FIELD_MAX, "galvo units",
                 "the XY2-100 Z channel (a focus shifter such as varioSCAN), sent in every "
                 "frame on its own data line: 32768 = the middle of its range (no focus "
                 "shift); taken with each frame's position", needs=('z',)),
        # --- I/O in the queue -------------------------------------------------------------------
        Register("io", 0x71, "ro", 0, 0, 0, "flags",
                 "I/O in the queue: bits 1:0 the inputs io_in now, 3:2 the outputs io_out, bit "
                 "4 an I/O word holds the queue, bit 5 a wait for an input timed out "
                 "(latched until vec_flush; the job stopped)", needs=('io',)),
    ]


def _needing(option, *, also=None):
    """The registers declared with ``option`` among their needs (and ``also``, if given)."""
    return tuple(reg.name for reg in all_registers(2, 2) if option in reg.needs and
                 (also is None or also in reg.needs))


#: Registers that only a build with that scan mode has (see ``GalvoScanTop(modes=...)``); a
#: build without the mode answers their addresses as unknown.
MODE_REGISTERS = {mode.label: _needing(mode.label) for mode in Mode}

#: Registers only a build with the wobble stage has (``GalvoScanTop(wobble=True)``, vector mode).
WOBBLE_REGISTERS = _needing("wobble")

#: Registers only a build with the spiral's interpolation has.
INTERPOLATION_REGISTERS = _needing("interpolation")

#: Registers of vector mode's RTC delays (``GalvoScanTop(vector_delays=True)``).
DELAY_REGISTERS = _needing("delays")

#: Registers only a build with the laser controller has.
LASER_REGISTERS = _needing("laser")

#: Registers only a build with the distortion correction stage has.
CORRECTION_REGISTERS = _needing("correction")

#: Registers only a build with the job player has.
PLAYER_REGISTERS = _needing("player")

#: Registers only a build with the head status receiver has.
HEAD_REGISTERS = _needing("head")

#: Registers only a build with marking on the fly has.
FLY_REGISTERS = _needing("fly")

#: Registers only a build with the Z channel has.
Z_REGISTERS = _needing("z")
#: Registers of builds with I/O in the queue.
IO_REGISTERS = _needing("io")
