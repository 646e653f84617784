"""Random, truncated, corrupted and misaligned command streams (hypothesis) against a model of
the command rules written here: no register changes except by a valid frame, every
rejected frame is counted, and the next valid frame after any garbage is accepted."""

from hypothesis import HealthCheck, given, settings, strategies as st

from galvoscan.client import FTDISPITransport, HostClient
from galvoscan.gateware.host.regmap import decode_frame

from sim_board import SimBoard, SimSPITransport, SimUARTTransport


# The simulated board is the default build (128-point spiral table, 17 x 17 correction table,
# every mode and the laser, none of the build options): its own map bounds what it takes, not
# the host's wider view (a read of a register it was not built with is refused, unanswered).
BUILD_MAP = SimBoard.powered_up(backend="compiled").top.regmap
REGISTERS = list(BUILD_MAP)
BY_ADDRESS = BUILD_MAP.by_address
# Writable registers that read back what was written (a queue register reads its last write).
RW = [r for r in REGISTERS if r.access in ("rw", "queue")]
STROBES = [r for r in REGISTERS if r.access == "strobe"]
# Largest value each register takes in the simulated build.
HIGH = {r.name: r.high for r in REGISTERS}
CHECK = 0x64


class CommandModel:
    """What the board must do with each complete 4-byte frame."""

    def __init__(self):
        self.values = {r.name: r.reset for r in RW}
        self.errors = 0
        self.replies = []            # (address, value or None for read-only registers)

    def frame(self, frame):
        address, data, check = frame[0], (frame[1] << 8) | frame[2], frame[3]
        reg = BY_ADDRESS.get(address & 0x7F)
        if check != CHECK or reg is None:
            self.errors += 1
        elif address & 0x80:
            if data != 0:
                self.errors += 1
            elif reg.access == "strobe":
                self.replies.append((reg.address, 0))      # strobes read 0
            else:
                self.replies.append((reg.address, self.values.get(reg.name)))
        elif reg.access == "ro" or not reg.low <= data <= HIGH[reg.name]:
            self.errors += 1
        elif reg.access in ("rw", "queue"):
            # (A queue write is refused only when the vector queue is full: never here, where
            # streams carry far fewer than its 512 places.)
            self.values[reg.name] = data

    def cut_short(self):
        self.errors += 1


def frame_bytes(address, data, check=CHECK):
    return bytes([address, data >> 8, data & 0xFF, check])


rw_regs = st.sampled_from(RW + STROBES)
valid_write = rw_regs.flatmap(
    lambda r: st.integers(r.low, HIGH[r.name]).map(lambda v: frame_bytes(r.address, v)))
valid_read = st.sampled_from(REGISTERS).map(lambda r: frame_bytes(0x80 | r.address, 0))
bad_check = st.tuples(valid_write, st.integers(0, 255).filter(lambda c: c != CHECK)).map(
    lambda t: t[0][:3] + bytes([t[1]]))
out_of_range = st.sampled_from([r for r in RW + STROBES if HIGH[r.name] < 0xFFFF or r.low > 0]).flatmap(
    lambda r: st.one_of(st.integers(HIGH[r.name] + 1, 0xFFFF) if HIGH[r.name] < 0xFFFF
                        else st.nothing(),
                        st.integers(0, r.low - 1) if r.low > 0 else st.nothing())
    .map(lambda v: frame_bytes(r.address, v)))
read_only_write = st.sampled_from([r for r in REGISTERS if r.access == "ro"]).flatmap(
    lambda r: st.integers(0, 0xFFFF).map(lambda v: frame_bytes(r.address, v)))
unknown = st.integers(0, 0xFF).filter(lambda a: (a & 0x7F) not in BY_ADDRESS).map(
    lambda a: frame_bytes(a, 0))
read_with_data = st.tuples(st.sampled_from(REGISTERS), st.integers(1, 0xFFFF)).map(
    lambda t: frame_bytes(0x80 | t[0].address, t[1]))
truncated = st.tuples(st.one_of(valid_write, valid_read), st.integers(1, 3)).map(
    lambda t: t[0][:t[1]])
noise = st.binary(min_size=1, max_size=9)

pieces = st.one_of(valid_write, valid_read, bad_check, out_of_range, read_only_write, unknown,
                   read_with_data, truncated, noise)


def read_back(link, regs):
    """Each of ``regs`` read by a valid frame, the frames back to back (the host does not wait
    for one answer before it sends the next read): ``{name: value}``, each answer checked to
    be for the register asked for, as :meth:`HostClient.read` checks it."""
    if not regs:
        return {}
    frames = [frame_bytes(0x80 | reg.address, 0) for reg in regs]
    board = link.board
    if isinstance(link, SimUARTTransport):
        received = len(board.uart_from_board)
        link.send_bytes(b"".join(frames))
        board.run_until(lambda: len(board.uart_from_board) >= received + 4 * len(frames),
                        timeout=0.01, step=board.bit_time)
        stream = bytes(board.uart_from_board[received:received + 4 * len(frames)])
        answers = [stream[i:i + 4] for i in range(0, len(stream), 4)]
    else:
        # Over SPI the answer to a read comes out during the next frame: the next read's, and
        # after the last one a read of errors (as the client's FETCH).
        link.transfer(frames[0])            # (out comes what was there before: not ours)
        answers = [link.transfer(frame) for frame in frames[1:] + [FTDISPITransport.FETCH]]
    values = {}
    for reg, answer in zip(regs, answers):
        address, value = decode_frame(answer)
        assert address == reg.address, (reg.name, answer.hex(" "))
        values[reg.name] = value
    return values


def named_by(addresses, also=()):
    """The registers whose address is one of ``addresses`` (the address bytes of every frame
    the board could have taken from the stream: a decoder that took a frame from the wrong
    place in it still takes the address from the stream, so no other register can have been
    written), and ``also`` (a few more at random, as a check of that argument)."""
    addresses = {address & 0x7F for address in addresses}
    return [reg for reg in RW if reg.address in addresses or reg in also]


def bytes_at_every_bit(bits):
    """The byte that starts at each bit of an SPI transaction (a target that lost count of the
    bits takes its address from one of these)."""
    return [int("".join(map(str, bits[k:k + 8])), 2) for k in range(len(bits) - 7)]


# Registers read back besides the ones the stream could name.
others = st.lists(st.sampled_from(RW), max_size=3, unique=True)


def check_board(link, model, replies, regs=RW):
    # The model's register values, read back by valid frames (which the model then sees too):
    # every register the stream could have named (``regs``), the rest untouched by it.
    values = read_back(link, regs)
    for reg in regs:
        assert values[reg.name] == model.values[reg.name], reg.name
    for reg in regs:
        model.frame(frame_bytes(0x80 | reg.address, 0))
    assert HostClient(link).read("errors") == model.errors
    # Every answer the board gave was to a read the model accepted, in order, with its value.
    assert len(replies) == len(model.replies[:len(replies)])
    for (address, value), answer in zip(model.replies, replies):
        assert answer[0] == address and answer[3] == CHECK
        if value is not None:
            assert (answer[1] << 8) | answer[2] == value


fuzz_settings = settings(max_examples=60, deadline=None,
                         suppress_health_check=[HealthCheck.too_slow])


@fuzz_settings
@given(st.lists(st.tuples(pieces, st.booleans()), min_size=1, max_size=8), valid_write, others)
def test_uart_garbage(stream, then, also):
    board = SimBoard.powered_up(backend="compiled")
    link = SimUARTTransport(board)
    model = CommandModel()

    pending = b""
    for data, pause in stream:
        link.queue(data, pause=pause)
        for byte in data:
            pending += bytes([byte])
            if len(pending) == 4:
                model.frame(pending)
                pending = b""
        if pause and pending:
            model.cut_short()
            pending = b""
    if pending:
        link.queue(b"")                     # the pause that ends it
        model.cut_short()
    link.flush()
    # Let the answers to the reads in the stream finish going out (up to four are queued),
    # and a character more: a reply the model does not expect would have started by then.
    board.run_until(lambda: len(board.uart_from_board) >= 4 * len(model.replies),
                    timeout=5 * 4 * 10 * board.bit_time, step=10 * board.bit_time)
    board.run_for(2 * 10 * board.bit_time)
    answers_before = bytes(board.uart_from_board)

    # The next valid frame is accepted.
    link.write_frame(then)
    model.frame(then)
    replies = [answers_before[i:i + 4] for i in range(0, len(answers_before), 4)]
    assert len(answers_before) % 4 == 0 and board.uart_framing_errors == 0
    check_board(link, model, replies,
                named_by(b"".join(data for data, _ in stream) + then, also))


spi_transactions = st.one_of(
    pieces.map(lambda data: [(b >> (7 - i)) & 1 for b in data for i in range(8)]),
    st.lists(st.integers(0, 1), max_size=40),
)


@fuzz_settings
@given(st.lists(spi_transactions, min_size=1, max_size=8), valid_write, others)
def test_spi_garbage(transactions, then, also):
    board = SimBoard.powered_up(backend="compiled")
    link = SimSPITransport(board)
    model = CommandModel()
    pending_reply = None
    for bits in transactions:
        cipo = link.transfer_bits(bits)
        # CIPO carries the answer to the last accepted read (or zeros), then zeros.
        want = [0] * 32
        if pending_reply is not None:
            address, value = pending_reply
            word = (address << 24) | ((value or 0) << 8) | CHECK
            want = [(word >> (31 - i)) & 1 for i in range(32)]
        if pending_reply is not None and pending_reply[1] is None:
            # A read-only value is unknown here: check the address and the check byte, as far
            # as this transaction clocks them out.
            n = len(bits)
            assert cipo[:8] == want[:min(8, n)] and cipo[24:32] == want[24:min(32, n)]
        else:
            assert cipo == (want + [0] * len(bits))[:len(bits)]
        replies_before = len(model.replies)
        pending_reply = None
        if len(bits) == 32:
            model.frame(bytes(int("".join(map(str, bits[i:i + 8])), 2) for i in range(0, 32, 8)))
        else:
            model.cut_short()
        if len(model.replies) > replies_before:
            pending_reply = model.replies[-1]

    link.write_frame(then)
    model.frame(then)
    named = [byte for bits in transactions for byte in bytes_at_every_bit(bits)] + list(then)
    check_board(link, model, [], named_by(named, also))
