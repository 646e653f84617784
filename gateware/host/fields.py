"""What the registers' values mean: the scan modes, vector operations and wobble shapes as
enums, the ``status`` bits as a layout, and the limits the map's ranges come from (part of
the register map, :mod:`.regmap`, which re-exports all of it)."""

from amaranth.lib import data, enum

from ..sources.spiral_table import DEFAULT_POINTS


__all__ = ["WORD_MAX", "LASER_ON_LEAD_US", "LASER_DELAY_MAX_US", "SCANNER_DELAY_MAX_US", "CORNER_FRAMES_MAX",
           "DEFAULT_TABLE_POINTS", "DEFAULT_CORRECTION_NODES", "Mode", "VectorOp",
           "WobbleShape", "WOBBLE_MAX_AMPLITUDE", "WOBBLE_MAX_HZ", "Status", "STATUS_BITS"]


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
