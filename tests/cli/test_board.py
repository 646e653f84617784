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
