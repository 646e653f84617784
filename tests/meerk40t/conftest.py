"""The fixtures of the meerk40t device's tests: one meerk40t kernel with the galvoscan device
on one simulated board a test module, and a loopback port for meerk40t's GRBL server."""

import socket

import pytest

from galvoscan.build import PRESETS

from meerk40t_session import device_on
from sim_board import SimBoard


@pytest.fixture(scope="module")
def meerk40t():
    """``(kernel, device, board, lines)``: the galvoscan device on a simulated board of the
    default bitstream (compiled), its wires and laser pins recorded; ``lines``: what the
    device says on meerk40t's console. The device's status poll is off (``status_poll_s`` 0),
    so that a test looks at the board between jobs without a poll's thread reading it at the
    same time; a test of the poll sets it (tests/meerk40t/test_status.py). The board is made
    first, and the poll turned off before the device's first one is due
    (:data:`~galvoscan.meerk40t.device.STATUS_POLL_S` after its start)."""
    config = PRESETS["default"]
    board = SimBoard(config=config, clk_freq=config.clk_freq, baud=config.baud,
                     backend="compiled", record_laser=True)
    with device_on(board.board) as (kernel, device, lines):
        yield kernel, device, board, lines


@pytest.fixture
def grbl_port(meerk40t, monkeypatch):
    """A loopback port for meerk40t's GRBL server, and the server's end of each connection
    closed after the test: meerk40t's TCP server leaves a connection the sender closed to the
    garbage collector (its handler leaves its loop on an empty read without closing the
    socket), which -W error would fail whichever test it is collected in."""
    accepted = []
    accept = socket.socket.accept

    def recording(self):
        connection, address = accept(self)
        accepted.append(connection)
        return connection, address
    monkeypatch.setattr(socket.socket, "accept", recording)
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    yield port
    for connection in accepted:
        connection.close()
