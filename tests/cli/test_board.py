"""`galvoscan board --sim`: the simulated board served on a pseudo-terminal, found by the path it
prints, answering `galvoscan read` and `send` run as separate processes, stopped by Ctrl-C."""

import json
import signal
import subprocess
import sys

import pytest


from cli_processes import BOARD, CLIENT


def _client(*argv):
    return subprocess.Popen([sys.executable, "-c", CLIENT, *argv], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _served(client, port):
    out, err = client.communicate(port + "\n", timeout=300)
    return client.returncode, out, err


@pytest.mark.slow
def test_send_and_read_a_served_simulated_board():
    # Both commands start (and import) while the board does.
    link = ["--timeout", "60"]
    send = _client("send", "dwell=9", "guide=1", "--verify", *link)
    read = _client("read", "dwell", "guide", "errors", "--json", *link)
    board = subprocess.Popen([sys.executable, "-c", BOARD, "board", "--sim"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        first = board.stdout.readline()
        assert first.startswith("simulated board") and " on /dev/" in first
        port = first.rsplit(" on ", 1)[1].strip()
        code, out, err = _served(send, port)
        assert code == 0, err
        assert "dwell = 9 (read back)" in out
        code, out, err = _served(read, port)
        assert code == 0, err
        assert json.loads(out) == {"dwell": 9, "guide": 1, "errors": 0}
    finally:
        for client in (send, read):
            if client.poll() is None:
                client.kill()
                client.communicate()
        board.send_signal(signal.SIGINT)
        out, err = board.communicate(timeout=600)
    assert board.returncode == 0, err
    assert "stopped after" in out and "XY2-100 frames" in out


def test_board_needs_sim():
    result = subprocess.run([sys.executable, "-m", "galvoscan.cli", "board"],
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 2 and "--sim" in result.stderr


def _served_for(board, seconds, **kwargs):
    """Serve ``board`` for ``seconds`` of the host's clock: ``(server, wall seconds, board
    seconds, lag)``, the last three read together at the end."""
    import time
    from galvoscan.sim.board import PTYServer
    server = PTYServer(board, **kwargs)
    started, board_started = time.monotonic(), board.now
    with server:
        time.sleep(seconds)
        ran = board.now - board_started
        wall = time.monotonic() - started
        lag = server.lag_s
    return server, wall, ran, lag


def test_a_board_faster_than_real_time_keeps_the_hosts_clock():
    """The spiral alone at 4 MHz runs faster than real time on the compiled board: served in
    real time, its time never runs ahead of the host's (by more than the step it is on)."""
    from galvoscan.sim.board import SimulatedBoard
    board = SimulatedBoard(clk_freq=4e6, baud=115_200, modes=("spiral",), correction=None,
                           links=("uart",), backend="compiled")
    server, wall, ran, lag = _served_for(board, 1.0, real_time=True)
    # (It runs a step, then waits for the wall: a step ahead at most, and the wait's own
    # precision, a fraction of a millisecond.)
    assert ran <= wall + server.step + 1e-3
    # (It keeps up when the machine is not too busy; a step's worth behind at most then.)
    assert lag < 0.5


def test_a_board_slower_than_real_time_says_how_far_behind_it_is():
    import threading
    import time
    from galvoscan.sim.board import PTYServer, SimulatedBoard
    board = SimulatedBoard(clk_freq=4e6, baud=115_200, modes=("spiral",), correction=None,
                           links=("uart",), backend="python")
    server = PTYServer(board, real_time=True)
    reports = []
    timer = threading.Timer(1.5, server.stop)
    started = time.monotonic()
    timer.start()
    server.serve_forever(report=reports.append, every_s=0.3)
    timer.join()
    wall = time.monotonic() - started
    # Amaranth's simulator runs this board at some 1/100 of real time: nearly all of the
    # wall time is lag, reported as it grows (never more than the wall time itself).
    assert reports and reports == sorted(reports) and 0.5 < reports[-1] <= wall
    assert board.now < 0.1
