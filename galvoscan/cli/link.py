"""``galvoscan regs``, ``encode``, ``send`` and ``read``: the register map, and registers
written and read over the serial port or SPI."""

import json

from .args import add_link_options, fail, failed, open_link, table_points


__all__ = ["add_parsers", "register_table"]


def register_table(registers=None):
    """The register map as a Markdown table (``galvoscan regs``; docs/reference/registers.md
    carries the host's view, the default)."""
    from ..gateware.host.regmap import REGISTERS
    lines = ["| address | name | access | reset | range | unit | description |",
             "|---|---|---|---|---|---|---|"]
    for r in REGISTERS if registers is None else registers:
        span = f"{r.low}…{r.high}" if r.access in ("rw", "queue") else "—"
        reset = "the build's" if r.fixed else r.reset
        lines.append(f"| 0x{r.address:02X} | `{r.name}` | {r.access} | {reset} | {span} | "
                     f"{r.unit} | {r.description} |")
    return "\n".join(lines)


def _cmd_regs(args):
    from ..gateware.host.regmap import REGISTERS, register_map
    registers = REGISTERS
    if args.table_points is not None or args.correction_nodes is not None:
        # One build's map: its own ranges and resets (the board refuses anything else).
        from ..gateware.host.regmap import DEFAULT_CORRECTION_NODES, DEFAULT_TABLE_POINTS
        nodes = args.correction_nodes or DEFAULT_CORRECTION_NODES
        try:
            registers = list(register_map(
                table_points=args.table_points or DEFAULT_TABLE_POINTS,
                correction_nodes=None if nodes == "none" else int(nodes)))
        except ValueError as error:
            fail(error)
    if args.json:
        print(json.dumps([r.as_dict() for r in registers], indent=2, ensure_ascii=False))
    else:
        print(register_table(registers))
    return 0


def _assignments(items):
    """``[(name, value)]`` of NAME=VALUE items, every one checked against the map first."""
    from ..link.client import ClientError, encode_write, parse_assignment
    try:
        assignments = [parse_assignment(item) for item in items]
        for name, value in assignments:
            encode_write(name, value)            # the name, the access and the range
            if name == "vec_op":
                raise ClientError("vec_op queues a segment, its end point in the same frame: "
                                  "galvoscan send does not (galvoscan mark queues them)")
    except ClientError as error:
        fail(error)
    return assignments


def _cmd_encode(args):
    from cobs import cobs
    from ..link.client import ClientError, encode_read, encode_write
    try:
        if args.read:
            frames = [encode_read(name, tag=(args.seq + k) & 0xFF)
                      for k, name in enumerate(args.items)]
        else:
            frames = [encode_write(name, value, seq=(args.seq + k) & 0xFF)
                      for k, (name, value) in enumerate(_assignments(args.items))]
    except ClientError as error:
        fail(error)
    for frame in frames:
        print((cobs.encode(frame) + b"\0" if args.uart else frame).hex(" "))
    return 0


def _cmd_send(args):
    from ..link.client import ClientError, HostClient
    # Every assignment is checked before the link is even opened: a typo in the last one must
    # not leave the first ones (arm=1, say) written.
    assignments = _assignments(args.items)
    with open_link(args) as link:
        board = HostClient(link)
        try:
            for name, value in assignments:
                if args.verify:
                    board.write_verified(name, value)
                else:
                    board.write(name, value)
                print(f"{name} = {value}{' (read back)' if args.verify else ''}")
        except ClientError as error:           # the board or the link, once opened
            failed(error)
    return 0


def _cmd_read(args):
    from ..link.client import ClientError, HostClient
    from ..gateware.host.regmap import BY_NAME
    unknown = [name for name in args.names if name not in BY_NAME]
    if unknown:
        fail(f"no register named {', '.join(unknown)} (galvoscan regs lists them)")
    with open_link(args) as link:
        board = HostClient(link)
        try:
            values = {name: board.read(name) for name in args.names}
        except ClientError as error:           # the board or the link, once opened
            failed(error)
    if args.json:
        print(json.dumps(values))
    else:
        for name, value in values.items():
            print(f"{name} = {value} ({BY_NAME[name].unit})")
    return 0


def _cmd_status(args):
    from ..link.client import ClientError, HostClient
    from ..outputs.board_state import read_board_state
    with open_link(args) as link:
        try:
            state = read_board_state(HostClient(link))
        except ClientError as error:           # the board or the link, once opened
            failed(error)
    if args.json:
        print(json.dumps(state.as_dict()))
    else:
        print("\n".join(state.lines()))
    return 0


def _cmd_reset(args):
    from ..link.client import ClientError, HostClient
    from ..outputs.board_state import LATCHED_FAULTS
    from ..gateware.fields import Capabilities, Status
    with open_link(args) as link:
        board = HostClient(link)
        try:
            # Laser off first; then every register to its power-up value, the vector queue
            # emptied and vector mode stopped.
            board.write("arm", 0)
            board.write("soft_reset", 1)
            flags = Status.from_bits(board.read("status"))
            free = board.read("fifo_free") if Capabilities.from_bits(
                board.read("caps")).vector else None
        except ClientError as error:           # the board or the link, once opened
            failed(error)
    latched = [name for name in LATCHED_FAULTS if getattr(flags, f"fault_{name}")]
    print("reset: every register back to its power-up value (laser disarmed)" +
          (f", vector queue emptied ({free} segments free)" if free is not None else "") +
          "; kept: " +
          (f"the latched {', '.join(latched)} fault (galvoscan send fault_clear=1 clears it)"
           if latched else "no fault latched") +
          ", the link's error count and sequence number")
    return 0


def add_parsers(commands):
    from ..gateware.field.correction_table import TABLE_SIZES
    regs = commands.add_parser(
        "regs", help="print the register map",
        description="The register map: addresses, access, reset values, ranges and units. "
                    "Without options, the host's view (ranges that depend on the build open to "
                    "the largest build); with --table-points or --correction-nodes, the map of "
                    "that build, as its board checks writes.")
    regs.add_argument("--json", action="store_true",
                      help="[{name, address, width, access, reset, min, max, unit, description}]")
    regs.add_argument("--table-points", type=table_points,
                      default=None, metavar="N",
                      help="the build's spiral table size (as `build --table-points`)")
    regs.add_argument("--correction-nodes", choices=[*map(str, TABLE_SIZES), "none"],
                      default=None, metavar="N",
                      help="the build's correction table nodes per axis, or none (default 17)")
    regs.set_defaults(run=_cmd_regs)

    encode = commands.add_parser(
        "encode", help="print command frames as hex bytes",
        description="Print the command frames (hex, one frame a line: sequence number, "
                    "address, data, x, y, CRC-16) that write or read registers, for any other "
                    "tool or microcontroller to send. A board takes a write only with the "
                    "sequence number it expects (galvoscan read link_seq).")
    encode.add_argument("--read", action="store_true", help="read requests for NAMEs")
    encode.add_argument("--seq", type=int, choices=range(256), default=0, metavar="N",
                        help="the first frame's sequence number, 0 … 255 (default 0)")
    encode.add_argument("--uart", action="store_true",
                        help="the bytes on the serial line: COBS-encoded, a zero byte after")
    encode.add_argument("items", nargs="+", metavar="NAME=VALUE | NAME",
                        help="registers to write (NAME=VALUE) or, with --read, to read")
    encode.set_defaults(run=_cmd_encode)

    send = commands.add_parser("send", help="write registers on a board",
                               description="Write registers over the serial port or SPI. "
                                           "Every NAME=VALUE is checked before the first "
                                           "frame is sent.")
    send.add_argument("items", nargs="+", metavar="NAME=VALUE",
                      help="registers to write, in order")
    send.add_argument("--verify", action="store_true", help="read each value back")
    add_link_options(send)
    send.set_defaults(run=_cmd_send)

    reset = commands.add_parser(
        "reset", help="disarm and return every register to its power-up value",
        description="Make a board ready for the next job without a power cycle: arm = 0 "
                    "(laser off), then soft_reset: every register back to its power-up value, "
                    "the vector queue emptied (a job left half-queued dropped), the counters "
                    "cleared. Latched faults stay latched (fault_clear clears them), and so do "
                    "the link's error count and sequence number.")
    add_link_options(reset)
    reset.set_defaults(run=_cmd_reset)

    read = commands.add_parser("read", help="read registers from a board",
                               description="Read registers over the serial port or SPI.")
    read.add_argument("names", nargs="+", metavar="NAME", help="registers to read")
    read.add_argument("--json", action="store_true", help="print {name: value}")
    add_link_options(read)
    read.set_defaults(run=_cmd_read)

    status = commands.add_parser(
        "status", help="say the board's state and its scan head's",
        description="The board's state in words: busy or ready, armed, the interlock, an "
                    "alarm and the latched faults; with a bitstream that reads the scan "
                    "head's STATUS line, the head's bits (Power OK, Temp OK, PosAck X and Y, "
                    "as RTC's get_head_status), whether the laser obeys them (head_check), the "
                    "latched head fault and the status frames refused.")
    status.add_argument("--json", action="store_true",
                        help="print {flags, latched, head} instead")
    add_link_options(status)
    status.set_defaults(run=_cmd_status)
