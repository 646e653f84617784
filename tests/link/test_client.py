"""The host drives the simulated system top through its UART and SPI pins with the real client."""

import pytest

from galvoscan.link.client import ClientError, HostClient, WriteRefused, encode_read, encode_write
from galvoscan.gateware.host.regmap import BY_NAME, STATUS_BITS
from galvoscan.gateware.sources.spiral import PARK_FRAMES
from galvoscan.gateware.sources.spiral_table import SpiralTable
from galvoscan.gateware.top import ScanSettings

from link_codec import REASON, command, parse_answer
from sim_board import SimBoard, SimSPITransport, SimUARTTransport, quick_board
from spiral_model import spiral_frames


def writable(board):
    """The board's writable registers that read back what was written, with the ranges of
    its build (vec_op, a queue, is written a segment at a time: test_segments_...)."""
    return [r for r in board.top.regmap if r.access == "rw"]


def make_link(kind, board):
    return SimUARTTransport(board) if kind == "uart" else SimSPITransport(board)


def contains_run(frames, run):
    """Whether ``run`` appears, in order and contiguous, in ``frames``."""
    n = len(run)
    return any(frames[i:i + n] == run for i in range(len(frames) - n + 1))


@pytest.mark.parametrize("kind", ["uart", "spi"])
def test_every_register_resets_and_reads_back(kind):
    # Three frames for each of some sixty registers.
    board = quick_board()
    client = HostClient(make_link(kind, board))
    for reg in writable(board):
        assert client.read(reg.name) == reg.reset, reg.name
    # Running out of reset, not armed, nothing clipped.
    assert client.read("status") == 1 << STATUS_BITS["running"]
    assert client.read("errors") == 0

    # Write a new in-range value to every writable register and read them all back.
    values = {}
    for i, reg in enumerate(writable(board)):
        values[reg.name] = reg.low + (7919 * (i + 3)) % (reg.high - reg.low + 1)
    values["run"] = 0                              # keep the scanner still meanwhile
    for name, value in values.items():
        client.write(name, value)
    for name, value in values.items():
        assert client.read(name) == value, name
    assert client.read("errors") == 0
    status = client.read("status")
    assert bool(status & (1 << STATUS_BITS["armed"])) == bool(values["arm"])
    assert not status & (1 << STATUS_BITS["running"])


@pytest.mark.parametrize("kind", ["uart", "spi"])
def test_host_starts_stops_and_reshapes_the_spiral(kind):
    table = SpiralTable()
    board = quick_board()                           # (its spiral table is this one)
    client = HostClient(make_link(kind, board))

    # Stop: the mirrors hold still.
    client.write("run", 0)
    # (Not the two frames already on their way when the write lands: the one on the wires and
    # the next, whose point was taken before.)
    board.run_for(20e-6)
    stopped_at = board.now
    board.run_for(2e-3)
    held = board.frames_after(stopped_at)
    assert len(held) > 150 and len(set(held)) == 1

    # Reshape while stopped, then start: the pattern begins again with the new settings.
    new = {"dwell": 2, "amp_x": 20000, "amp_y": 40000, "center_x": 30000, "center_y": 36000,
           "x_first": 4, "x_last": 60, "y_first": 9, "y_last": 50,
           "spiral_interp": 0}     # held points, so that a dwell shows as runs of one frame
    for name, value in new.items():
        client.write(name, value)
    started_at = board.now
    client.write("run", 1)
    board.run_for(3e-3)
    after = [f for _, f in board.xy2_frames()[-400:]]
    want = spiral_frames(table.x, table.y, 80, dwell=2, x_range=(4, 60), y_range=(9, 50),
                         gain=(20000, 40000), centre=(30000, 36000))[PARK_FRAMES:]
    assert contains_run(after, want)
    assert started_at > stopped_at

    # A dwell change on the fly takes effect from a point boundary on.
    client.write("dwell", 5)
    board.run_for(2e-3)
    recent = [f for _, f in board.xy2_frames()[-150:]]
    runs = []
    for frame in recent:
        if runs and runs[-1][0] == frame:
            runs[-1][1] += 1
        else:
            runs.append([frame, 1])
    assert [count for _, count in runs[1:-1]] == [5] * (len(runs) - 2)


def test_client_refuses_what_the_board_would_reject():
    with pytest.raises(ClientError, match="no register named"):
        encode_write("speed", 3)
    with pytest.raises(ClientError, match="read-only"):
        encode_write("status", 1)
    with pytest.raises(ClientError, match="from 1 to 65535"):
        encode_write("dwell", 0)
    # Ranges that depend on the build are checked against the largest build on the host (a
    # 4096-point table); the board refuses what its own build cannot take (below).
    with pytest.raises(ClientError, match="from 0 to 4095"):
        encode_write("x_last", 4096)
    with pytest.raises(ClientError, match="no register named"):
        encode_read("nonesuch")


def test_encoding_is_the_documented_frame():
    # seq, address, data, x, y, CRC-16/CCITT: the tests' own encoder of the host-link page's frame.
    assert encode_write("dwell", 0x1234, seq=9) == command(9, BY_NAME["dwell"].address, 0x1234)
    assert encode_read("errors", tag=3) == command(3, BY_NAME["errors"].address, read=True)
@pytest.mark.parametrize("kind", ["uart", "spi"])
def test_board_refuses_and_counts_each_bad_frame_with_its_reason(kind):
    board = quick_board()
    link = make_link(kind, board)
    client = HostClient(link)
    dwell = BY_NAME["dwell"].address
    good = command(0, dwell, 5)
    damaged = bytearray(good)
    damaged[3] ^= 0x10                                  # one bit of the value flipped
    bad = [
        (bytes(damaged), "check"),
        (good[:-1] + bytes([good[-1] ^ 1]), "check"),   # the CRC itself damaged
        (command(7, dwell, 5), "sequence"),             # not the seq the board expects
        (command(0, 0x7E, 5), "register"),              # unknown address
        (command(0, BY_NAME["status"].address, 1), "register"),     # read-only
        (command(0, dwell, 0), "register"),             # out of range
        (command(0, BY_NAME["x_last"].address, 200), "register"),   # out of the build's range
        (command(0, dwell, 1, read=True), "register"),  # a read with data
    ]
    answers = link.transact([frame for frame, _ in bad])
    for (frame, reason), packet in zip(bad, answers):
        tag, code, data = parse_answer(packet)
        assert code == 0x80 | REASON[reason], (frame.hex(" "), reason, code)
        assert data == 0                                # the seq the board expects, still 0
    assert len(answers) == len(bad)
    assert client.read("dwell") == 3
    assert client.read("errors") == len(bad)
    client.write("dwell", 9)
    assert client.read("dwell") == 9


@pytest.mark.parametrize("kind", ["uart", "spi"])
def test_writes_are_taken_in_sequence_only(kind):
    """A write lost on the line makes the next refused (the board never takes one out of
    order); the client finds out from link_seq and sends again only what was not taken."""
    board = quick_board()
    link = make_link(kind, board)
    client = HostClient(link)
    seq = client.sequence()
    dwell, amp = BY_NAME["dwell"].address, BY_NAME["amp_x"].address
    # The first of two writes lost: the second, with the next seq, is refused.
    [answer] = link.transact([command(seq + 1, amp, 1234)])
    assert parse_answer(answer) == (seq + 1, 0x80 | REASON["sequence"], seq)
    [answer] = link.transact([command(seq, dwell, 7)])
    assert parse_answer(answer) == (seq, dwell, 7)      # what dwell now holds
    assert client.read("link_seq") == (seq + 1) & 0xFF
    assert client.read("amp_x") == BY_NAME["amp_x"].reset
    # A read takes any tag and does not move the sequence.
    [answer] = link.transact([command(0xAB, dwell, read=True)])
    assert parse_answer(answer) == (0xAB, dwell, 7)
    assert client.read("link_seq") == (seq + 1) & 0xFF


def test_a_refused_write_stops_the_client_with_its_reason():
    board = quick_board()
    client = HostClient(SimUARTTransport(board))
    with pytest.raises(WriteRefused, match="x_last = 200") as refused:
        client.write_many([("dwell", 4), ("x_last", 200), ("dwell", 6)])
    assert refused.value.reason == "register" and refused.value.taken == 1
    assert client.read("dwell") == 4


@pytest.mark.parametrize("kind", ["uart", "spi"])
def test_segments_are_queued_whole_and_answered_with_the_room_left(kind):
    board = SimBoard(vector_queue_depth=8, settings=ScanSettings(mode="vector", run=False))
    client = HostClient(make_link(kind, board))
    free = client.queue_segments([(0, 1000, 2000), (0, 3000, 4000)])
    # Eight places, two segments queued, and those the sequencer took from the queue (even
    # stopped, it takes one in hand) free again.
    assert free == 8 - 2 + client.read("vec_taken")
    assert client.read("vec_taken") == 1
    # vec_x and vec_y are the job player's; a host's segment does not touch them.
    assert client.read("vec_x") == BY_NAME["vec_x"].reset
    assert client.read("errors") == 0


def test_uart_finds_the_next_frame_after_a_lost_byte_an_extra_byte_and_a_bad_stop_bit():
    board = quick_board()
    link = SimUARTTransport(board)
    client = HostClient(link)
    seq = client.sequence()
    frame = lambda value: cobs_frame(command(seq, BY_NAME["dwell"].address, value))
    lost = frame(11)
    link.send_bytes(lost[:3] + lost[4:])                # a byte lost
    link.send_bytes(frame(12)[:4] + b"\x42" + frame(12)[4:])   # a byte too many
    bad_stop = frame(13)
    board.uart_to_board.extend([*bad_stop[:2], ("bad_stop", bad_stop[2]), *bad_stop[3:]])
    link.send_bytes(frame(14)[:5])                      # cut short: ends at the next frame
    link.send_bytes(b"\0" + frame(15))                  # (the zero closes it) then a good one
    assert client.read("dwell") == 15
    assert client.read("errors") == 4


def cobs_frame(frame):
    from link_codec import cobs_encode
    return cobs_encode(frame) + b"\0"


def test_spi_frames_of_the_wrong_length_are_discarded_whole():
    board = quick_board()
    link = SimSPITransport(board)
    client = HostClient(link)
    write = command(client.sequence(), BY_NAME["dwell"].address, 13)
    bits = [(b >> (7 - i)) & 1 for b in write for i in range(8)]
    link.transfer_bits(bits[:79])                        # cs_n released one bit early
    link.transfer_bits(bits + [0])                       # one bit too many
    link.transfer_bits([])                               # cs_n pulse with no clock
    assert client.read("dwell") == 3
    assert client.read("errors") == 3
    link.transfer_bits(bits)
    assert client.read("dwell") == 13


@pytest.mark.parametrize("phase", [0.0, 0.2, 0.5, 0.9])
def test_spi_at_1mhz_on_the_boards_12mhz_clock(phase):
    """The stated maximum: SCK = system clock / 12, at any phase to the system clock."""
    board = SimBoard(clk_freq=12e6)
    link = SimSPITransport(board, clocks_per_sck=12, phase=phase)
    assert link.half_period == pytest.approx(0.5e-6)          # 1 MHz
    client = HostClient(link)
    for name, value in (("dwell", 0xBEEF), ("center_y", 0x1234), ("amp_x", 0x8001)):
        client.write(name, value)
        assert client.read(name) == value
    assert client.read("errors") == 0


@pytest.mark.parametrize("clk_freq, baud", [(4e6, 115_200), (12e6, 115_200), (12e6, 1_000_000)])
def test_uart_rates(clk_freq, baud):
    board = SimBoard(clk_freq=clk_freq, baud=baud)
    client = HostClient(SimUARTTransport(board))
    client.write("dwell", 0x4321)
    assert client.read("dwell") == 0x4321
    assert client.read("errors") == 0


@pytest.mark.parametrize("build, caps, depth", [
    # bit 0 spiral, 1 raster, 2 vector, 3 laser, 4 correction, 5 wobble, 6 delays,
    # 7 interpolation, 8 uart, 9 spi (the register's description), worked out by hand.
    ({}, 0b11_1001_1111, 512),
    (dict(modes=("vector",), correction=None, wobble=True, vector_delays=True,
          vector_queue_depth=16, links=("uart",), settings=ScanSettings(mode="vector")),
     0b01_0110_1100, 16),
    (dict(modes=("spiral",), laser=False, correction=None, spiral_interpolation=False,
          links=("uart",)), 0b01_0000_0001, 0),
])
def test_the_bitstream_says_what_it_holds(build, caps, depth):
    """``caps`` and ``vec_depth`` read over the UART pins of builds that differ: what each
    holds, asked without a refused write (``errors`` stays 0)."""
    board = SimBoard(**build)
    client = HostClient(SimUARTTransport(board))
    assert client.read("caps") == caps
    assert client.read("vec_depth") == depth
    assert client.read("errors") == 0


def test_a_long_write_whose_answers_are_lost_is_not_taken_twice():
    """More segments than the 256 sequence numbers in one call, every answer of the first
    batch lost on the line: the board took them all, and the host, reading link_seq, sends
    none of them again (a batch of 300 would have read 44 taken and sent 256 again)."""
    board = quick_board()

    class LosingFirstAnswers(SimUARTTransport):
        lost = False

        def transact(self, frames):
            answers = list(super().transact(frames))
            if not self.lost and len(frames) > 1:
                self.lost = True
                return []
            return answers

    link = LosingFirstAnswers(board)
    client = HostClient(link)
    client.write("vec_flush", 1)
    depth = client.read("fifo_free")
    count = min(depth, 300)
    free = client.queue_segments([(0, i, i) for i in range(count)])
    # Each write taken once: vec_flush and the segments (the queue keeps the rest of them:
    # the sequencer has taken the first).
    assert link.lost and client.read("link_seq") == (1 + count) % 256
    assert client.read("errors") == 0 and free == client.read("fifo_free") >= depth - count
