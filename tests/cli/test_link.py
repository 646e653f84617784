"""`galvoscan send` and `galvoscan read` through pyserial and a pseudo-terminal into the simulated
board: the CLI's own serial I/O, end to end, with no hardware."""

import json
import os
import pty
import select
import threading
import tty

import pytest

from galvoscan.cli import main

from sim_board import SimBoard, SimUARTTransport


class SerialBridge:
    """A pty whose far end is the simulated board's UART."""

    def __init__(self, board):
        self.board = board
        self.link = SimUARTTransport(board)
        self.master, slave = pty.openpty()
        tty.setraw(slave)
        self.port = os.ttyname(slave)
        self._slave = slave
        self._stop = threading.Event()
        self._sent = 0
        self._thread = threading.Thread(target=self._pump, daemon=True)
        self._thread.start()

    def _pump(self):
        while not self._stop.is_set():
            ready, _, _ = select.select([self.master], [], [], 0.01)
            if ready:
                try:
                    data = os.read(self.master, 256)
                except OSError:
                    return
                # The host wrote a burst; a pause follows it, as between the client's frames.
                self.link.send_bytes(data)
                self.board.run_for(6 * 10 * self.board.bit_time)    # room for an answer
            answers = self.board.uart_from_board
            if len(answers) > self._sent:
                os.write(self.master, bytes(answers[self._sent:]))
                self._sent = len(answers)

    def close(self):
        self._stop.set()
        self._thread.join()
        os.close(self.master)
        os.close(self._slave)


@pytest.fixture
def bridge():
    bridge = SerialBridge(SimBoard(baud=500_000))
    yield bridge
    bridge.close()


def test_send_and_read_over_serial(bridge, capsys):
    link = ["--port", bridge.port, "--baud", "500000", "--timeout", "5"]
    assert main(["send", "dwell=7", "center_x=0x7000", "--verify", *link]) == 0
    out = capsys.readouterr().out
    assert "dwell = 7 (read back)" in out and "center_x = 28672 (read back)" in out

    assert main(["read", "dwell", "center_x", "errors", "--json", *link]) == 0
    assert json.loads(capsys.readouterr().out) == {"dwell": 7, "center_x": 28672, "errors": 0}


def test_send_refuses_bad_values_before_sending(bridge):
    link = ["--port", bridge.port, "--baud", "500000", "--timeout", "5"]
    with pytest.raises(SystemExit, match="dwell takes an integer from 1 to 65535"):
        main(["send", "dwell=0", *link])
    with pytest.raises(SystemExit, match="expected NAME=VALUE"):
        main(["send", "dwell", *link])
    with pytest.raises(SystemExit, match="no register named"):
        main(["read", "speed", *link])
    assert bridge.board.uart_to_board == type(bridge.board.uart_to_board)()
    assert not bridge.board.uart_from_board


def test_a_board_that_answers_late_or_not_at_all_is_told_apart():
    """No byte back: the port, the baud rate, or a slow board's --timeout. Bytes that are no
    answer (a wrong baud rate, a damaged line): said as such, never taken as a value."""
    from galvoscan.link.client import HostClient, LinkLost, SerialTransport
    master, slave = pty.openpty()
    tty.setraw(slave)
    try:
        with SerialTransport(os.ttyname(slave), baud=115200, timeout=0.05) as link:
            with pytest.raises(LinkLost, match=r"no answer from the board within 0.05 s "
                                               r"\(a read of status, 3 tries\): check the "
                                               r"port .* longer --timeout"):
                HostClient(link).read("status")
            os.read(master, 4096)                       # (the frames it sent)

            def noise():
                for _ in range(3):
                    select.select([master], [], [], 1)
                    os.read(master, 4096)
                    os.write(master, b"\x05\x01\x02\x03\x04\x00")
            thread = threading.Thread(target=noise)
            thread.start()
            with pytest.raises(LinkLost, match=r"answers that do not check"):
                HostClient(link).read("status")
            thread.join()
    finally:
        os.close(master)
        os.close(slave)


def test_reset_empties_a_half_queued_job(capsys):
    """A host that died mid-job left segments queued: `galvoscan reset` disarms, stops and
    flushes, and the next job is taken."""
    from galvoscan.gateware.top import ScanSettings
    board = SimBoard(baud=500_000, modes=("vector",), correction=None,
                     settings=ScanSettings(mode="vector", run=False), vector_queue_depth=8)
    bridge = SerialBridge(board)
    try:
        link = ["--port", bridge.port, "--baud", "500000", "--timeout", "5"]
        from galvoscan.link.client import HostClient, SerialTransport
        with SerialTransport(bridge.port, baud=500_000, timeout=5) as serial:
            HostClient(serial).queue_segments([(1, 30000, 30000), (1, 31000, 30000)])
        with pytest.raises(SystemExit, match="vec_op queues a segment"):
            main(["send", "vec_op=1", *link])
        assert main(["read", "fifo_free", "--json", *link]) == 0
        assert json.loads(capsys.readouterr().out)["fifo_free"] < 8
        assert main(["reset", *link]) == 0
        out = capsys.readouterr().out
        assert "vector queue emptied (8 segments free)" in out and "no fault latched" in out
        assert main(["read", "fifo_free", "errors", "--json", *link]) == 0
        assert json.loads(capsys.readouterr().out) == {"fifo_free": 8, "errors": 0}
    finally:
        bridge.close()
