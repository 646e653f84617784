"""The host drives the simulated system top through its UART and SPI pins with the real client."""

import pytest

from galvoscan.client import ClientError, HostClient, encode_read, encode_write
from galvoscan.gateware.host.regmap import BY_NAME, STATUS_BITS, encode_frame
from galvoscan.gateware.sources.spiral import PARK_FRAMES
from galvoscan.gateware.sources.spiral_table import SpiralTable
from galvoscan.gateware.top import ScanSettings

from sim_board import SimBoard, SimSPITransport, SimUARTTransport
from spiral_model import spiral_frames


def writable(board):
    """The board's writable registers that read back what was written (a queue register reads
    its last write), with the ranges of its build."""
    return [r for r in board.top.regmap if r.access in ("rw", "queue")]


def make_link(kind, board):
    return SimUARTTransport(board) if kind == "uart" else SimSPITransport(board)


def contains_run(frames, run):
    """Whether ``run`` appears, in order and contiguous, in ``frames``."""
    n = len(run)
    return any(frames[i:i + n] == run for i in range(len(frames) - n + 1))


@pytest.mark.parametrize("kind", ["uart", "spi"])
def test_every_register_resets_and_reads_back(kind):
    board = SimBoard()
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
    board = SimBoard(table=table)
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
    # Address, data high, data low, 0x64: written out by hand from Dai & Tang 2020's frame.
    assert encode_write("dwell", 0x1234) == bytes([BY_NAME["dwell"].address, 0x12, 0x34, 0x64])
    assert encode_read("errors") == bytes([0x80 | BY_NAME["errors"].address, 0, 0, 0x64])


@pytest.mark.parametrize("kind", ["uart", "spi"])
def test_board_counts_each_rejected_frame(kind):
    board = SimBoard()
    link = make_link(kind, board)
    client = HostClient(link)
    dwell = BY_NAME["dwell"].address
    bad = [
        encode_frame(dwell, 5)[:3] + b"\x65",           # wrong check byte
        encode_frame(0x7E, 5),                           # unknown address
        encode_frame(BY_NAME["status"].address, 1),      # read-only
        encode_frame(dwell, 0),                          # out of range
        encode_frame(BY_NAME["x_last"].address, 200),    # out of range
        encode_frame(0x80 | dwell, 1),                   # read with data
    ]
    for frame in bad:
        link.write_frame(frame)
    assert client.read("dwell") == 3
    assert client.read("errors") == len(bad)
    client.write("dwell", 9)
    assert client.read("dwell") == 9


def test_uart_cut_short_and_line_errors_are_counted_and_realigned():
    board = SimBoard()
    link = SimUARTTransport(board)
    client = HostClient(link)
    write = encode_write("dwell", 11)
    link.send_bytes(write[:2])                           # cut short, then a pause
    board.uart_to_board.extend([write[0], write[1], ("bad_stop", write[2]), write[3]])
    link.send_bytes(b"")                                 # a byte with a bad stop bit
    link.send_bytes(write)                               # then a good frame
    assert client.read("dwell") == 11
    assert client.read("errors") == 2


def test_spi_frames_of_the_wrong_length_are_discarded_whole():
    board = SimBoard()
    link = SimSPITransport(board)
    client = HostClient(link)
    write = encode_write("dwell", 13)
    bits = [(b >> (7 - i)) & 1 for b in write for i in range(8)]
    link.transfer_bits(bits[:31])                        # cs_n released one bit early
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
