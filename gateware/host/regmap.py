"""The register map: every register declared once (in :mod:`.register_list`, what the values
mean in :mod:`..fields`; both re-exported here), and the map of one build made from them. The
gateware, the host client, ``galvoscan regs`` and the README's table are all made from (or
checked against) it.

Some facts depend on how the gateware is built: the spiral table's size bounds the ROM address
registers, the correction table's size bounds ``cor_node``, and a build without a scan mode,
the laser or the correction stage has no registers for it. :func:`register_map` gives the map
of one build; the register file and the system top take every register fact from it. The
module-level :data:`REGISTERS`, :data:`BY_NAME` and :data:`BY_ADDRESS` are the host's view (see
:data:`HOST_MAP`).

The frames that carry writes and reads, their CRC and sequence numbers, are in
:mod:`.frames`. A write is taken only if its address is known, the access is allowed (no
writes to read-only registers, read requests carry zero data) and the value is in range;
anything else changes nothing and counts in ``errors``.

Access: ``rw`` registers hold what was written; ``ro`` ones report state; a ``strobe`` register
acts on a write of 1 (a write of 0 does nothing) and always reads 0; a ``queue`` register
pushes each write into a queue (the vector FIFO) and reads back the last value written: a
write when the queue is full is refused (counted in ``errors`` and in the queue's own counter).
"""

from dataclasses import replace

from ..field.correction_table import TABLE_SIZES
# The map's two parts, re-exported here: what the values mean, and every register.
from .. import limits
from ..limits import (CORNER_FRAMES_MAX, DEFAULT_CLOCK_HZ, DEFAULT_CORRECTION_NODES,
                      DEFAULT_TABLE_POINTS, FRAME_US, LASER_DELAY_MAX_US, LASER_ON_LEAD_US,
                      MAX_TABLE_POINTS, MIN_TABLE_POINTS,
                      SCANNER_DELAY_MAX_US, VECTOR_QUEUE_DEPTH, WOBBLE_MAX_AMPLITUDE,
                      WOBBLE_MAX_HZ, WORD_MAX)
from .. import fields
from . import register_list
from ..fields import (STATUS_BITS, Capabilities, FlyControl, HeadState, HeadStatus, IOKind,
                      IOState, Mode,
                      PlayerResult,
                      PlayerState, PlayerStatus, Status, VectorOp, WobbleShape, pack)
from .register_list import (CORRECTION_REGISTERS, DELAY_REGISTERS, FLY_REGISTERS, HEAD_REGISTERS,
                            Z_REGISTERS, IO_REGISTERS,
                            INTERPOLATION_REGISTERS,
                            LASER_REGISTERS, MODE_REGISTERS, PLAYER_REGISTERS,
                            WOBBLE_REGISTERS, Register,
                            all_registers)


__all__ = ["READ_FLAG", "RegisterMap", "register_map",
           "HOST_MAP", "REGISTERS", "BY_NAME", "BY_ADDRESS", *fields.__all__, *limits.__all__,
           *(name for name in register_list.__all__ if name != "all_registers")]



#: Set in the address byte of a read request.
READ_FLAG = 0x80


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
    pixel_lines : bool
    head : bool
    fly : bool
    z : bool
    queue_io : bool
    """

    def __init__(self, registers, *, choices, table_points, correction_nodes, modes, laser,
                 wobble=False, vector_delays=False, pixel_lines=False, head=False, fly=False,
                 z=False, queue_io=False):
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
        self.pixel_lines = pixel_lines
        self.head = head
        self.fly = fly
        self.z = z
        self.queue_io = queue_io

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
                 vector_delays=False, pixel_lines=False, player=False, head=False, fly=False,
                 z=False, queue_io=False,
                 resets=None, fixed=None):
    """The register map of a build (by default, the default build's: the same defaults as
    :class:`~galvoscan.gateware.top.GalvoScanTop`).

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
    pixel_lines : bool
        The build has pixel lines (and the delays): ``vec_op`` takes bit 8, ``pixels``.
    player : bool
        The build has the job player (else its ``player`` register is left out).
    head : bool
        The build has the head status receiver (else its ``head*`` registers are left out;
        ``head_state`` and ``head_check`` also need the laser).
    fly : bool
        The build marks on the fly (else its ``fly_*`` and ``enc_*`` registers are left out).
    z : bool
        The build drives the Z channel (else its ``z`` register is left out).
    queue_io : bool
        The build has I/O in the queue (and pixel lines): ``vec_op`` takes bit 9, ``io``, and
        the ``io`` register is built.
    resets : dict of str to int, optional
        Reset values of ``rw`` registers that differ from the defaults (the scan settings a build
        starts with); each must lie in its register's range. Those of registers the build
        leaves out are skipped: scan settings name every scan register, whatever is built.
    fixed : dict of str to int, optional
        The values of the registers fixed when the bitstream is built (``caps``,
        ``vec_depth``: the system top gives them); each must fit its register's width.

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
    if wobble and Mode.VECTOR not in modes:
        raise ValueError("the wobble stage works on vector points: it needs vector mode")
    if player and not (Mode.VECTOR in modes and laser):
        raise ValueError("the job player plays vector jobs: it needs vector mode and the laser")
    # The build's options, and the registers that come with them (each register's needs).
    options = {mode.label for mode in modes}
    options |= {name for name, built in (
        ("correction", correction_nodes is not None), ("laser", laser), ("wobble", wobble),
        ("interpolation", spiral_interpolation), ("delays", vector_delays),
        ("player", player), ("head", head), ("fly", fly), ("z", z),
        ("io", queue_io and pixel_lines and vector_delays)) if built}
    every = {r.name: r for r in all_registers(table_points, correction_nodes or 2)}
    leave_out = {name for name, reg in every.items() if not set(reg.needs) <= options}
    if not vector_delays:
        every["vec_op"] = replace(every["vec_op"], high=1, width=1, unit="enum", description=(
            "writing queues a segment to (vec_x, vec_y): 0 = jump (laser off, then jump_delay), "
            "1 = mark (laser on, points every pitch); refused if the queue is full"))
    if pixel_lines and vector_delays:
        every["vec_op"] = replace(every["vec_op"], high=511, width=9, description=(
            every["vec_op"].description.replace("; refused if", "; bit 8 (pixels): a mark with "
                                                "it is a pixel line, each point lit only if "
                                                "its bit in the pixel words queued after it is "
                                                "1; a jump with it is a pixel word, 32 bits in "
                                                "vec_x (pixels 0-15, bit 0 first) and vec_y "
                                                "(16-31), which moves nothing; refused if")))
    if queue_io and pixel_lines and vector_delays:
        every["vec_op"] = replace(every["vec_op"], high=1023, width=10, description=(
            every["vec_op"].description.replace("; refused if", "; bit 9 (io): an I/O word "
                                                "(bits 2:0 what it does: 0 wait for an input, "
                                                "1 set an output, 2/3 wait for an encoder's "
                                                "count up/down, 4/5 fly start/end; bit 3 which "
                                                "input, output or encoder, bit 4 the level, "
                                                "bit 5 wait for an edge; vec_x, vec_y its "
                                                "arguments); refused if")))
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
    for name, value in (fixed or {}).items():
        if name not in by_name or not by_name[name].fixed:
            raise ValueError(f"{name!r} is not a register fixed by the build")
        if isinstance(value, bool) or not isinstance(value, int) or \
                not 0 <= value < 1 << by_name[name].width:
            raise ValueError(f"{name} = {value!r} does not fit its {by_name[name].width} bits")
        by_name[name] = replace(by_name[name], reset=value)
    if by_name["mode"].reset not in (mode.value for mode in modes):
        raise ValueError(f"the build starts in mode {Mode(by_name['mode'].reset).label}, "
                         f"which it does not have")
    return RegisterMap(by_name.values(), choices={"mode": [mode.value for mode in modes]},
                       table_points=table_points, correction_nodes=correction_nodes,
                       modes=modes, laser=bool(laser), wobble=bool(wobble),
                       vector_delays=bool(vector_delays) and Mode.VECTOR in modes,
                       pixel_lines=bool(pixel_lines and vector_delays) and Mode.VECTOR in modes,
                       head=bool(head), fly=bool(fly), z=bool(z),
                       queue_io=bool(queue_io and pixel_lines and vector_delays) and
                       Mode.VECTOR in modes)


def _host_map():
    """The host's view: every register, the resets of the default build, and the ranges that
    depend on a build open to the largest one (the ROM addresses to the largest spiral table,
    ``cor_node`` to the largest correction table). The host cannot know a board's tables, and
    the board itself refuses, and counts, a value outside its own."""
    default = register_map()
    return register_map(table_points=MAX_TABLE_POINTS, correction_nodes=max(TABLE_SIZES),
                        wobble=True, vector_delays=True, pixel_lines=True, player=True, head=True, fly=True, z=True, queue_io=True,
                        resets={name: default[name].reset
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
           WOBBLE_REGISTERS + DELAY_REGISTERS + PLAYER_REGISTERS + HEAD_REGISTERS + FLY_REGISTERS +
           Z_REGISTERS + IO_REGISTERS)
