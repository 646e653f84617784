"""The register map: declared once, here. The gateware, the host client, ``galvoscan regs`` and
the README's table are all made from (or checked against) it.

Some facts depend on how the gateware is built: the spiral table's size bounds the ROM address
registers, the correction table's size bounds ``cor_node``, and a build without a scan mode,
the laser or the correction stage has no registers for it. :func:`register_map` gives the map
of one build; the register file and the system top take every register fact from it. The
module-level :data:`REGISTERS`, :data:`BY_NAME` and :data:`BY_ADDRESS` are the host's view (see
:data:`HOST_MAP`).

A command frame is four bytes, most significant first (as Dai & Tang's decoder takes them)::

    address | data[15:8] | data[7:0] | 0x64

Bit 7 of the address byte selects a read: ``0x80 | address, 0x00, 0x00, 0x64`` asks for a
register, and the answer is a frame in the same format, ``address, data_hi, data_lo, 0x64``.
A frame is accepted only if its check byte is 0x64, its address is known, the access is allowed
(no writes to read-only registers, read requests carry zero data) and the value is in range;
anything else changes nothing and counts in ``errors``.

Access: ``rw`` registers hold what was written; ``ro`` ones report state; a ``strobe`` register
acts on a write of 1 (a write of 0 does nothing) and always reads 0; a ``queue`` register
pushes each write into a queue (the vector FIFO) and reads back the last value written: a
write when the queue is full is refused (counted in ``errors`` and in the queue's own counter).
"""

from dataclasses import dataclass, replace

from amaranth.hdl import Shape
from amaranth.lib import data, enum

from ..field.correction_table import TABLE_SIZES
from ..field.scale import AMP_ONE
from ..points import FIELD_CENTRE, FIELD_MAX
from ..sources.spiral_table import DEFAULT_POINTS, MAX_POINTS


__all__ = ["CHECK_BYTE", "READ_FLAG", "Mode", "VectorOp", "Status", "STATUS_BITS", "Register", "RegisterMap",
           "register_map", "DEFAULT_TABLE_POINTS", "DEFAULT_CORRECTION_NODES", "MAX_TABLE_POINTS",
           "HOST_MAP",
           "REGISTERS", "BY_NAME", "BY_ADDRESS", "MODE_REGISTERS", "CORRECTION_REGISTERS",
           "LASER_REGISTERS", "WOBBLE_REGISTERS", "WobbleShape", "WOBBLE_MAX_AMPLITUDE",
           "WOBBLE_MAX_HZ", "INTERPOLATION_REGISTERS", "DELAY_REGISTERS", "LASER_ON_LEAD_US",
           "LASER_DELAY_MAX_US", "SCANNER_DELAY_MAX_US", "CORNER_FRAMES_MAX", "encode_frame",
           "decode_frame", "FrameError"]


#: The last byte of every frame.
CHECK_BYTE = 0x64
#: Set in the address byte of a read request.
READ_FLAG = 0x80
#: Largest value a frame's data field carries.
WORD_MAX = 0xFFFF
#: The vector sequencer decides a frame's laser two 10 µs frames before that frame's point
#: reaches the head: how far ahead a negative ``laser_on_delay`` can reach, plus one µs.
LASER_ON_LEAD_US = 20
#: Largest laser-on and laser-off delays, in µs.
LASER_DELAY_MAX_US = 1023
#: Largest mark and polygon delays, in µs.
SCANNER_DELAY_MAX_US = 4095
#: Largest scaled corner hold a mark carries (``vec_op`` bits 7:1), in frames.
CORNER_FRAMES_MAX = 127

#: Samples per axis of the default spiral table (the paper's 128).
DEFAULT_TABLE_POINTS = DEFAULT_POINTS
#: Nodes per axis of the default (identity) correction table.
DEFAULT_CORRECTION_NODES = 17


class Mode(enum.Enum, shape=2):
    """Values of the ``mode`` register: the scan modes."""
    SPIRAL = 0      #: the precessing spiral fill
    RASTER = 1      #: line-by-line fill of a rectangle
    VECTOR = 2      #: queued jump / mark segments

    @classmethod
    def named(cls, name):
        """The mode called ``name`` (``"spiral"``, ``"raster"`` or ``"vector"``)."""
        if isinstance(name, cls):
            return name
        if not isinstance(name, str) or name.upper() not in cls.__members__:
            raise ValueError(f"mode must be one of {', '.join(m.label for m in cls)}, "
                             f"not {name!r}")
        return cls[name.upper()]

    @property
    def label(self):
        """The name the host and the command line use."""
        return self.name.lower()


class VectorOp(enum.Enum, shape=1):
    """Values of the ``vec_op`` register: what a queued segment does."""
    JUMP = 0        #: move with the laser off, then wait ``jump_delay``
    MARK = 1        #: step a line at ``pitch`` with the laser on

    @property
    def label(self):
        """The word a job file uses."""
        return self.name.lower()


class WobbleShape(enum.Enum, shape=1):
    """Values of the ``wob_shape`` register: the figure laid over marked vector points."""
    OFF = 0         #: marked points as the line gives them
    ELLIPSE = 1     #: an ellipse (a circle when both amplitudes are equal) around each point

    @property
    def label(self):
        """The word the command line uses."""
        return self.name.lower()


#: Largest wobble amplitude, galvo units (≈ 6.9 mm on a 110 mm field): the figure's products
#: stay within 12 bits.
WOBBLE_MAX_AMPLITUDE = 4095
#: Highest wobble frequency, Hz: a quarter of the XY2-100 frame rate, so a turn of the figure
#: has at least four points.
WOBBLE_MAX_HZ = 25_000


#: Bits of the ``status`` register, bit 0 first.
Status = data.StructLayout({
    "running": 1,           # the selected scan mode is running
    "clipped": 1,           # a point was clamped at the field edge (scale or correction) since read
    "armed": 1,             # the arm register is set
    "fault_interlock": 1,   # latched: the interlock opened
    "fault_watchdog": 1,    # latched: no valid command for the watchdog time while armed
    "mo_on": 1,             # the master oscillator is on
    "emitting": 1,          # modulation is on: the laser is firing
    "interlock_open": 1,    # the interlock is open now
    "vector_busy": 1,       # vector mode has segments queued or points still to mark
    "fault_alarm": 1,       # latched: a laser alarm input was active while armed
    "alarm": 1,             # a laser alarm input is active now
    "laser_enable": 1,      # the laser buffers are enabled (armed, no fault, closed, no alarm)
    "laser_ready": 1,       # armed and MO has led for the MO lead: marking now emits
})

#: Bit number of each :data:`Status` flag, for host code that tests bits of a value read.
STATUS_BITS = {name: field.offset for name, field in Status}


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


def _all_registers(table_points, correction_nodes):
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
                 "on for the MO lead: a job may start)",
                 width=Status.size),
        Register("errors", 0x01, "ro", 0, 0, 0, "frames",
                 "rejected command frames since reset (bad check byte, unknown address, write to "
                 "a read-only register, value out of range, cut short, UART framing error); "
                 "stops at 65535"),
        # --- galvo group ------------------------------------------------------------------------
        Register("mode", 0x02, "rw", Mode.SPIRAL.value, 0, len(Mode) - 1, "enum",
                 "scan mode: 0 = spiral, 1 = raster (line-by-line fill), 2 = vector (queued "
                 "jump/mark segments)", width=Shape.cast(Mode).width),
        Register("run", 0x03, "rw", 1, 0, 1, "bool",
                 "1 = sweep; 0 = stop (the mirrors hold the last point; the next start begins the "
                 "spiral or raster again; the vector queue is kept)", width=1),
        Register("dwell", 0x04, "rw", 3, 1, WORD_MAX, "frames (10 µs)",
                 "frames each spiral point is held; 3 = 30 µs, the paper's figure"),
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
                 width=address_width),
        Register("x_last", 0x0A, "rw", last_address, 0, last_address, "ROM address",
                 "last X table address walked (inclusive)", width=address_width),
        Register("y_first", 0x0B, "rw", 1, 0, last_address, "ROM address",
                 "first Y table address walked (inclusive); the paper's 1…126 against X's 0…127 "
                 "makes the ellipse precess", width=address_width),
        Register("y_last", 0x0C, "rw", last_address - 1, 0, last_address, "ROM address",
                 "last Y table address walked (inclusive)", width=address_width),
        Register("spiral_interp", 0x0D, "rw", 1, 0, 1, "enum",
                 "between spiral points: 0 = hold each point for dwell frames, then jump; 1 = "
                 "linear, every frame moves part of the way to the next point (same points at "
                 "the same times; dwells over 255 frames are held); see README \"Held points\"",
                 width=1),
        # --- vector group -----------------------------------------------------------------------
        Register("vec_x", 0x20, "rw", FIELD_CENTRE, 0, FIELD_MAX, "galvo units",
                 "X of the next segment's end point (offset binary, 32768 = centre)"),
        Register("vec_y", 0x21, "rw", FIELD_CENTRE, 0, FIELD_MAX, "galvo units",
                 "Y of the next segment's end point"),
        Register("vec_op", 0x22, "queue", 0, 0, 255, "enum + factor",
                 "writing queues a segment to (vec_x, vec_y): bit 0: 0 = jump (laser off, then "
                 "jump_delay), 1 = mark (laser on, points every pitch); bits 7:1 of a mark: the hold "
                 "in 10 µs frames of the corner it leaves, if polygon_scaled; refused if the "
                 "queue is full", width=8),
        Register("fifo_free", 0x23, "ro", 0, 0, 0, "segments",
                 "free places in the vector queue"),
        Register("pitch", 0x24, "rw", 60, 1, WORD_MAX, "galvo units",
                 "distance between marked points; 60 ≈ 0.1 mm on a 110 mm field, the pitch of Wan et al."),
        Register("pulses_per_point", 0x25, "rw", 1, 1, 255, "laser pulses",
                 "pulses each marked point gets; the line speed is pitch × PRR / pulses_per_point"
                 , width=8),
        Register("jump_delay", 0x26, "rw", 500, 0, WORD_MAX, "µs",
                 "laser-off wait after a jump for the mirrors to settle, before marking resumes; "
                 "rounded up to whole 10 µs frames, at least one"),
        Register("vec_rejected", 0x27, "ro", 0, 0, 0, "writes",
                 "vec_op writes refused because the queue was full; stops at 65535"),
        Register("vec_underruns", 0x28, "ro", 0, 0, 0, "times",
                 "times the queue ran empty in the middle of marking (the laser stopped and the "
                 "mirrors held until more segments came); stops at 65535"),
        Register("vec_stalls", 0x29, "ro", 0, 0, 0, "frames",
                 "frames a marked line waited, laser off, for the next segment to be set up (140 "
                 "clocks: at 12 MHz only after two one-point segments in a row); stops at 65535"),
        # The RTC's delays (SCANLAB RTC5/6 manuals; EzCad's start/end/corner TC): the laser
        # ones move the modulation edges to the clock, the scanner ones hold the mirrors for
        # whole frames.
        Register("laser_on_delay", 0x2A, "rw", 100, -LASER_ON_LEAD_US + 1, LASER_DELAY_MAX_US,
                 "µs, two's complement",
                 "laser (DB25 modulation, pin 19) on this long after a mark's first point reaches "
                 "the head; negative switches it on that much earlier, down to -19 µs (the "
                 "sequencer decides two frames ahead); placed to the clock on the modulation edge",
                 width=11, signed=True),
        Register("laser_off_delay", 0x2B, "rw", 50, 0, LASER_DELAY_MAX_US, "µs",
                 "laser stays on this long after a mark's last point reaches the head (the mirror "
                 "still lags it); placed to the clock on the modulation edge", width=10),
        Register("mark_delay", 0x2C, "rw", 100, 0, SCANNER_DELAY_MAX_US, "µs",
                 "after a mark followed by a jump, the mirrors hold its end point this long, laser "
                 "off (after laser_off_delay runs out), before the jump; whole 10 µs frames, "
                 "rounded up", width=12),
        Register("polygon_delay", 0x2D, "rw", 0, 0, SCANNER_DELAY_MAX_US, "µs",
                 "between two marks, the mirrors hold the corner this long with the laser on; "
                 "whole 10 µs frames, rounded up", width=12),
        Register("polygon_scaled", 0x2E, "rw", 0, 0, 1, "bool",
                 "1 = hold each corner for the frames sent with the mark that leaves it (vec_op "
                 "bits 7:1: the host's polygon delay × (1 - cos φ), RTC's variable polygon "
                 "delay); 0 = polygon_delay at every corner", width=1),
        # --- wobble group (built with GalvoScanTop(wobble=True)) -------------------------------
        Register("wob_shape", 0x50, "rw", WobbleShape.OFF.value, 0, len(WobbleShape) - 1, "enum",
                 "figure laid over every marked vector point, a new position each frame while "
                 "the point is held: 0 = off, 1 = ellipse (wob_along × wob_across; a circle when "
                 "equal)", width=Shape.cast(WobbleShape).width),
        Register("wob_along", 0x51, "rw", 30, 0, WOBBLE_MAX_AMPLITUDE, "galvo units",
                 "wobble amplitude along the line (half the figure's length; the host converts "
                 "µm through the field size: 30 ≈ 50 µm on a 110 mm field)",
                 width=_width(WOBBLE_MAX_AMPLITUDE)),
        Register("wob_across", 0x52, "rw", 30, 0, WOBBLE_MAX_AMPLITUDE, "galvo units",
                 "wobble amplitude across the line (half the track's added width)",
                 width=_width(WOBBLE_MAX_AMPLITUDE)),
        Register("wob_freq", 0x53, "rw", 1000, 1, WOBBLE_MAX_HZ, "Hz",
                 "turns of the figure per second (at most a quarter of the 100 kHz frame rate); "
                 "each mark starts at the figure's first point", width=_width(WOBBLE_MAX_HZ)),
        # --- raster group -----------------------------------------------------------------------
        Register("ras_x", 0x30, "rw", 28768, 0, WORD_MAX, "galvo units",
                 "raster rectangle: X of its lower-left corner"),
        Register("ras_y", 0x31, "rw", 28768, 0, WORD_MAX, "galvo units",
                 "raster rectangle: Y of its lower-left corner"),
        Register("ras_w", 0x32, "rw", 8000, 0, WORD_MAX, "galvo units",
                 "raster rectangle: width (positions past 65535 are clamped)"),
        Register("ras_h", 0x33, "rw", 8000, 0, WORD_MAX, "galvo units",
                 "raster rectangle: height"),
        Register("ras_spacing", 0x34, "rw", 30, 1, WORD_MAX, "galvo units",
                 "line spacing; 30 ≈ 0.05 mm on a 110 mm field"),
        Register("ras_step", 0x35, "rw", 30, 1, WORD_MAX, "galvo units per frame",
                 "distance along a line per 10 µs frame: the line speed; 30 ≈ 5 m/s on a 110 mm "
                 "field"),
        Register("ras_flags", 0x36, "rw", 0, 0, 3, "flags",
                 "bit 0: lines along Y (else X); bit 1: every line in the same direction, with a "
                 "jump back (else serpentine)", width=2),
        Register("ras_turn_gate", 0x37, "rw", 0, 0, WORD_MAX, "frames (10 µs)",
                 "laser off for this many frames at the start of each line but the first, while the "
                 "mirrors turn; 0 keeps it on, as the paper's raster does"),
        # --- distortion correction group ------------------------------------------------------
        Register("cor_enable", 0x40, "rw", 1, 0, 1, "bool",
                 "1 = add the correction table's interpolated offset to every point (the identity "
                 "table changes nothing); 0 = positions pass unchanged", width=1),
        Register("cor_node", 0x41, "rw", 0, 0, last_node, "node index",
                 "table node the next cor_write stores: iy × n + ix, n = cor_nodes (node (ix, iy) "
                 "sits at galvo position (ix, iy) × 65536 / (n - 1)); up to n × n - 1",
                 width=_width(last_node)),
        Register("cor_dx", 0x42, "rw", 0, 0, WORD_MAX, "galvo units, two's complement",
                 "X offset for cor_write (65535 = -1): added to positions at that node"),
        Register("cor_dy", 0x43, "rw", 0, 0, WORD_MAX, "galvo units, two's complement",
                 "Y offset for cor_write"),
        Register("cor_write", 0x44, "strobe", 0, 0, 1, "write 1",
                 "stores (cor_dx, cor_dy) at node cor_node, both at once and between two points, so "
                 "no point is made from a half-written node; the values are those of the moment "
                 "of the write. Refused (counted in errors) while the last write still waits for "
                 "a point to finish (at most 16 clocks)", width=1, refusable=True),
        Register("cor_nodes", 0x45, "ro", 0, 0, 0, "nodes",
                 "correction table nodes per axis in this build (5, 9, 17, 33 or 65)",
                 width=_width(max(TABLE_SIZES))),
        # --- laser group ------------------------------------------------------------------------
        Register("arm", 0x10, "rw", 0, 0, 1, "bool",
                 "1 = arm the laser: laser_enable on, latch power, MO on, modulation after the "
                 "MO lead (5 ms) while the spiral runs; 0 = laser_enable and every laser "
                 "output off", width=1),
        Register("laser_power", 0x11, "rw", 0, 0, 255, "1/255 of full power",
                 "laser power on DB25 pins 1-8, latched by pin 9 on arming and on every change "
                 "while armed", width=8),
        Register("laser_prr", 0x12, "rw", 500, 200, 2000, "100 Hz",
                 "pulse repetition rate on DB25 pin 20, 20.0 … 200.0 kHz (500 = 50 kHz), 50 % duty",
                 width=11),
        Register("watchdog", 0x13, "rw", 1000, 1, 60000, "ms",
                 "while armed, no accepted command frame for this long switches the laser off and "
                 "latches a watchdog fault"),
        Register("fault_clear", 0x14, "strobe", 0, 0, 1, "write 1",
                 "clears latched faults if the interlock is closed and no alarm is active; the "
                 "laser then stays off until arm is written 0 and 1 again", width=1),
        Register("pulses", 0x15, "ro", 0, 0, 0, "pulses",
                 "laser pulses emitted (PRR rising edges while modulating) since reset, modulo "
                 "65536"),
        Register("guide", 0x16, "rw", 0, 0, 1, "bool",
                 "1 = guide (red pointer) laser on, to frame a job with the mirrors; it is off "
                 "whenever arm is set, whatever this holds", width=1),
    ]


#: Registers that only a build with that scan mode has (see ``GalvoScanTop(modes=...)``); a
#: build without the mode answers their addresses as unknown.
MODE_REGISTERS = {
    Mode.SPIRAL.label: ("dwell", "x_first", "x_last", "y_first", "y_last", "spiral_interp"),
    Mode.RASTER.label: ("ras_x", "ras_y", "ras_w", "ras_h", "ras_spacing", "ras_step",
                        "ras_flags", "ras_turn_gate"),
    Mode.VECTOR.label: ("vec_x", "vec_y", "vec_op", "fifo_free", "pitch", "pulses_per_point",
                        "jump_delay", "vec_rejected", "vec_underruns", "vec_stalls",
                        "laser_on_delay", "laser_off_delay", "mark_delay", "polygon_delay",
                        "polygon_scaled"),
}

#: Registers only a build with the wobble stage has (``GalvoScanTop(wobble=True)``, vector mode).
WOBBLE_REGISTERS = ("wob_shape", "wob_along", "wob_across", "wob_freq")

#: Registers only a build with the spiral's interpolation has.
INTERPOLATION_REGISTERS = ("spiral_interp",)

#: Registers of vector mode's RTC delays (``GalvoScanTop(vector_delays=True)``).
DELAY_REGISTERS = ("laser_on_delay", "laser_off_delay", "mark_delay", "polygon_delay",
                   "polygon_scaled")

#: Registers only a build with the laser controller has.
LASER_REGISTERS = ("arm", "laser_power", "laser_prr", "watchdog", "fault_clear", "pulses",
                   "guide")

#: Registers only a build with the distortion correction stage has.
CORRECTION_REGISTERS = ("cor_enable", "cor_node", "cor_dx", "cor_dy", "cor_write", "cor_nodes")


class RegisterMap:
    """The registers of one build, with the ranges and resets that build gives them.

    Made by :func:`register_map`. Iterating gives the :class:`Register` entries in map order;
    ``regmap["dwell"]`` is one by name.

    Attributes
    ----------
    registers : tuple of :class:`Register`
    by_name, by_address : dict
    choices : dict of str to tuple of int
        Registers that take only some values of their range (``mode``: the modes built).
    table_points : int
    correction_nodes : int or None
    modes : tuple of :class:`Mode`
    laser : bool
    wobble : bool
    vector_delays : bool
    """

    def __init__(self, registers, *, choices, table_points, correction_nodes, modes, laser,
                 wobble=False, vector_delays=False):
        self.registers = tuple(registers)
        self.by_name = {r.name: r for r in self.registers}
        self.by_address = {r.address: r for r in self.registers}
        if not len(self.by_name) == len(self.by_address) == len(self.registers):
            raise ValueError("register names and addresses must be unique")
        self.choices = {name: tuple(values) for name, values in choices.items()}
        self.table_points = table_points
        self.correction_nodes = correction_nodes
        self.modes = tuple(modes)
        self.laser = laser
        self.wobble = wobble
        self.vector_delays = vector_delays

    def __iter__(self):
        return iter(self.registers)

    def __len__(self):
        return len(self.registers)

    def __contains__(self, name):
        return name in self.by_name

    def __getitem__(self, name):
        return self.by_name[name]

    def __repr__(self):
        return (f"register_map(table_points={self.table_points}, "
                f"correction_nodes={self.correction_nodes}, "
                f"modes={tuple(m.label for m in self.modes)}, laser={self.laser}, "
                f"wobble={self.wobble})")


def register_map(*, table_points=DEFAULT_TABLE_POINTS, correction_nodes=DEFAULT_CORRECTION_NODES,
                 modes=tuple(Mode), laser=True, wobble=False, spiral_interpolation=True,
                 vector_delays=True, resets=None):
    """The register map of a build.

    Parameters
    ----------
    table_points : int
        Samples per axis of the spiral table, 2 … 4096: ``x_first`` … ``y_last`` address it
        (``0 … table_points - 1``, reset to the paper's ranges ``(0, N-1)`` and ``(1, N-2)``).
    correction_nodes : int or None
        Correction table nodes per axis (one of 5, 9, 17, 33, 65): ``cor_node`` goes up to
        ``n × n - 1``. None: the build has no correction stage, nor its registers.
    modes : iterable of :class:`Mode` or str
        Scan modes built: the ``mode`` register takes only these, and the registers of the
        others are left out.
    laser : bool
        The build has the laser controller (else its registers are left out).
    wobble : bool
        The build has the wobble stage on vector points (else its registers are left out).
    spiral_interpolation : bool
        The build interpolates between spiral points (else ``spiral_interp`` is left out).
    vector_delays : bool
        The build has vector mode's laser and scanner delays (else their registers are left
        out and ``vec_op`` takes only 0 and 1).
    resets : dict of str to int, optional
        Reset values of ``rw`` registers that differ from the defaults (the scan settings a build
        starts with); each must lie in its register's range. Those of registers the build
        leaves out are skipped: scan settings name every scan register, whatever is built.

    Returns
    -------
    :class:`RegisterMap`
    """
    if not isinstance(table_points, int) or not 2 <= table_points <= MAX_TABLE_POINTS:
        raise ValueError(f"table_points must be an integer from 2 to {MAX_TABLE_POINTS}, not "
                         f"{table_points!r}")
    if correction_nodes is not None and correction_nodes not in TABLE_SIZES:
        raise ValueError(f"correction_nodes must be one of "
                         f"{', '.join(map(str, TABLE_SIZES))} or None, not {correction_nodes!r}")
    modes = tuple(sorted({Mode.named(mode) for mode in modes}, key=lambda mode: mode.value))
    if not modes:
        raise ValueError("a build needs at least one scan mode")
    leave_out = {name for mode in Mode if mode not in modes
                 for name in MODE_REGISTERS[mode.label]}
    if correction_nodes is None:
        leave_out |= set(CORRECTION_REGISTERS)
    if not laser:
        leave_out |= set(LASER_REGISTERS)
    if not wobble:
        leave_out |= set(WOBBLE_REGISTERS)
    elif Mode.VECTOR not in modes:
        raise ValueError("the wobble stage works on vector points: it needs vector mode")
    if not spiral_interpolation:
        leave_out |= set(INTERPOLATION_REGISTERS)
    every = {r.name: r for r in _all_registers(table_points, correction_nodes or 2)}
    if not vector_delays:
        leave_out |= set(DELAY_REGISTERS)
        every["vec_op"] = replace(every["vec_op"], high=1, width=1, unit="enum", description=(
            "writing queues a segment to (vec_x, vec_y): 0 = jump (laser off, then jump_delay), "
            "1 = mark (laser on, points every pitch); refused if the queue is full"))
    by_name = {name: r for name, r in every.items() if name not in leave_out}
    for name, value in (resets or {}).items():
        if name not in every or every[name].access != "rw":
            raise ValueError(f"{name!r} is not a writable register")
        if name in leave_out:
            continue
        reg = by_name[name]
        if isinstance(value, bool) or not isinstance(value, int) or \
                not reg.low <= value <= reg.high:
            raise ValueError(f"reset value {value!r} of {name} is outside {reg.low}…{reg.high}")
        by_name[name] = replace(reg, reset=value)
    if by_name["mode"].reset not in (mode.value for mode in modes):
        raise ValueError(f"the build starts in mode {Mode(by_name['mode'].reset).label}, "
                         f"which it does not have")
    return RegisterMap(by_name.values(), choices={"mode": [mode.value for mode in modes]},
                       table_points=table_points, correction_nodes=correction_nodes,
                       modes=modes, laser=bool(laser), wobble=bool(wobble),
                       vector_delays=bool(vector_delays) and Mode.VECTOR in modes)


#: Largest spiral table a build may have (samples per axis).
MAX_TABLE_POINTS = MAX_POINTS


def _host_map():
    """The host's view: every register, the resets of the default build, and the ranges that
    depend on a build open to the largest one (the ROM addresses to the largest spiral table,
    ``cor_node`` to the largest correction table). The host cannot know a board's tables, and
    the board itself refuses, and counts, a value outside its own."""
    default = register_map()
    return register_map(table_points=MAX_TABLE_POINTS, correction_nodes=max(TABLE_SIZES),
                        wobble=True, resets={name: default[name].reset
                                for name in ("x_first", "x_last", "y_first", "y_last")})


#: The host's view of the map (see :func:`_host_map`): what the client checks a write against,
#: and what ``galvoscan regs`` and the README show.
HOST_MAP = _host_map()

REGISTERS = list(HOST_MAP)
BY_NAME = HOST_MAP.by_name
BY_ADDRESS = HOST_MAP.by_address
assert all(r.address < READ_FLAG for r in REGISTERS)
assert all(name in BY_NAME for names in MODE_REGISTERS.values() for name in names)
assert all(name in BY_NAME for name in CORRECTION_REGISTERS + LASER_REGISTERS +
           WOBBLE_REGISTERS + DELAY_REGISTERS)


class FrameError(ValueError):
    """Bytes that are not a well-formed frame, or a value a register cannot take."""


def encode_frame(address, data):
    """The four bytes of a frame."""
    if not 0 <= address <= 0xFF or not 0 <= data <= 0xFFFF:
        raise FrameError(f"address {address} or data {data} does not fit a frame")
    return bytes([address, data >> 8, data & 0xFF, CHECK_BYTE])


def decode_frame(frame):
    """``(address, data)`` of a four-byte frame with the right check byte."""
    if len(frame) != 4:
        raise FrameError(f"a frame is 4 bytes, not {len(frame)}")
    if frame[3] != CHECK_BYTE:
        raise FrameError(f"check byte {frame[3]:#04x}, not {CHECK_BYTE:#04x}")
    return frame[0], (frame[1] << 8) | frame[2]
