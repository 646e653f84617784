"""What the registers' values mean: the scan modes, vector operations and wobble shapes as
enums, the ``status`` and ``caps`` bits as layouts, and :func:`pack`, the host's side of a
word read through a layout (part of the register map, :mod:`.host.regmap`, which re-exports
them with the limits of :mod:`.limits`). Imports nothing of the project's: the datapath cores
(:mod:`.sources`, :mod:`.player`) take their enums from here without the map, so no package
below gateware reaches into another's for them."""

from enum import Enum

from amaranth.lib import data, enum


__all__ = ["Mode", "VectorOp", "WobbleShape", "Status", "STATUS_BITS", "Capabilities",
           "HeadStatus", "HeadState", "FlyControl", "IOKind", "IOState",
           "PlayerState", "PlayerResult", "PlayerStatus", "pack"]


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
    "player_busy": 1,       # the job player is checking or playing the flash's job
    "job_refused": 1,       # the player refused the flash's job at the last start
    "fault_link": 1,        # latched: the host link refused a frame while armed
})

#: Bit number of each :data:`Status` flag, for host code that tests bits of a value read.
STATUS_BITS = {name: field.offset for name, field in Status}


#: Bits of the ``caps`` register, bit 0 first: what this bitstream holds, so that the host
#: asks instead of trying writes the board would refuse (and count in ``errors``).
Capabilities = data.StructLayout({
    "spiral": 1,            # the spiral mode
    "raster": 1,            # the raster mode
    "vector": 1,            # the vector mode
    "laser": 1,             # the laser controller
    "correction": 1,        # the correction stage (its table's nodes: cor_nodes)
    "wobble": 1,            # the wobble stage on vector points
    "delays": 1,            # vector mode's laser and scanner delays
    "interpolation": 1,     # the spiral's interpolator
    "uart": 1,              # the UART link
    "spi": 1,               # the SPI link
    "player": 1,            # the job player, its flash reader and start input
    "pixel_lines": 1,       # vector mode's pixel lines (vec_op bit 8)
    "head": 1,              # the head status receiver (the head, head_state, head_check registers)
    "fly": 1,               # marking on the fly: two encoder inputs, the fly offset
    "z": 1,                 # the XY2-100 Z channel (a focus shifter) and its z register
    "io": 1,                # I/O in the queue (vec_op bit 9): inputs io_in, outputs io_out
})


#: Bits of the ``fly_ctrl`` register, bit 0 first.
FlyControl = data.StructLayout({
    "on": 1,                # the fly offset applied (0: RTC's fly_return)
    "x_simulated": 1,       # the X count from the simulated encoder
    "y_simulated": 1,       # the Y count from the simulated encoder
    "reverse": 1,           # the simulated encoder counts down
})


class IOKind(enum.Enum, shape=3):
    """What a queued I/O word (``vec_op`` bit 9, ``io``) does, in its bits 2:0. Each waits
    until every segment before it is marked (the vector sequencer idle) and holds the queue
    until it is done."""
    WAIT_INPUT = 0      #: wait for input ``index`` at ``level`` (``edge``: for it to come to it); ``vec_x``: timeout, ms (0: none)
    SET_OUTPUT = 1      #: set output ``index`` to ``level``; ``vec_x``: for that many 10 µs frames, then back (0: until changed)
    WAIT_COUNT_UP = 2   #: wait for encoder ``index`` (0 X, 1 Y) to reach ``vec_y:vec_x`` (signed) or more
    WAIT_COUNT_DOWN = 3 #: wait for it to reach ``vec_y:vec_x`` or less
    FLY_START = 4       #: clear both encoders' counts and turn the fly offset on (RTC's set_fly)
    FLY_END = 5         #: turn the fly offset off (RTC's fly_return)

    @property
    def label(self):
        return self.name.lower()


#: Bits of the ``io`` register, bit 0 first.
IOState = data.StructLayout({
    "inputs": 2,            # the inputs io_in now (after the synchroniser)
    "outputs": 2,           # the outputs io_out now
    "waiting": 1,           # an I/O word holds the queue: a wait, or segments still marking before it
    "timed_out": 1,         # latched until vec_flush: a wait for an input ran out of time; the queue holds
})


#: The status word of the scan head (the ``head`` register), as RTC5/RTC6's
#: ``get_head_status`` has it, bit 0 first; a missing head reads 0.
HeadStatus = data.StructLayout({
    "one": 1,               # always 1 in a frame taken: tells a head that answers from none
    "zero": 1,              # always 0
    "_2": 1,
    "pos_ack_x": 1,         # the X mirror is within the PosAck window of its set position
    "pos_ack_y": 1,         # likewise Y
    "_5": 1,
    "temp_ok": 1,           # the head's temperature is in range
    "power_ok": 1,          # the head's supply is in range
    "_8": 8,
})

#: Bits of the ``head_state`` register, bit 0 first: what the receiver and the laser made of
#: the head's words.
HeadState = data.StructLayout({
    "missing": 1,           # no good status frame in the last 8 (80 µs): no head answers
    "fault": 1,             # latched: with head_check on, Temp OK or Power OK low (or no head) while armed
})


class PlayerState(enum.Enum, shape=2):
    """What the job player is doing (the ``player`` register's bits 1:0)."""
    IDLE = 0        #: waiting for a start
    CHECKING = 1    #: reading the image through, checking it
    RUNNING = 2     #: playing it (or stopping)

    @property
    def label(self):
        return self.name.lower()


class PlayerResult(enum.Enum, shape=4):
    """How the job player's last start ended (the ``player`` register's bits 5:2)."""
    NONE = 0            #: no start yet, or one under way
    DONE = 1            #: played through, every repeat
    NO_IMAGE = 2        #: no image: the magic is missing (an erased flash reads all 0xFF)
    BAD_VERSION = 3     #: an image of another format version
    BAD_HEADER = 4      #: the length (odd, too short, past the flash, not whole segments) or repeats (0)
    BAD_CRC = 5         #: the CRC-32 does not match: a corrupt or truncated image
    BAD_SETTING = 6     #: a setting addresses a register the player drives itself
    REFUSED = 7         #: the register file refused a write (a setting or segment out of range)
    FAULT = 8           #: the laser faulted (interlock, alarm, watchdog) while armed
    HOST = 9            #: a host wrote arm, run or mode

    @property
    def label(self):
        return self.name.lower().replace("_", " ")

    @property
    def refused(self):
        """The image was refused in the check, before any write."""
        return self in (PlayerResult.NO_IMAGE, PlayerResult.BAD_VERSION,
                        PlayerResult.BAD_HEADER, PlayerResult.BAD_CRC,
                        PlayerResult.BAD_SETTING)


#: Bits of the ``player`` register.
PlayerStatus = data.StructLayout({
    "state": PlayerState,
    "result": PlayerResult,
    "refused": 8,           # images refused since reset (stops at 255)
})


def pack(layout, **fields):
    """The integer whose bits hold ``fields`` where ``layout`` (a flat
    :class:`~amaranth.lib.data.StructLayout`) puts them: the host's side of a word the
    gateware reads through that layout (``vec_op``, a queued segment). Fields left out are 0;
    a value that does not fit its field raises :class:`ValueError`."""
    word = 0
    for name, value in fields.items():
        field = layout[name]
        if isinstance(value, Enum):
            value = value.value
        if isinstance(value, bool) or not isinstance(value, int) or \
                not 0 <= value < 1 << field.width:
            raise ValueError(f"{name} = {value!r} does not fit its {field.width} bits")
        word |= value << field.offset
    return word
