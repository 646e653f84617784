"""`galvoscan board --sim`: the simulated board served on a pseudo-terminal, found by the path it
prints, answering `galvoscan read` and `send` run as separate processes, stopped by Ctrl-C."""

import json
import signal
import subprocess
import sys

import pytest


@pytest.mark.slow
def test_send_and_read_a_served_simulated_board():
    board = subprocess.Popen([sys.executable, "-m", "galvoscan.cli", "board", "--sim"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        first = board.stdout.readline()
        assert first.startswith("simulated board") and " on /dev/" in first
        port = first.rsplit(" on ", 1)[1].strip()
        link = ["--port", port, "--timeout", "60"]
        sent = subprocess.run([sys.executable, "-m", "galvoscan.cli", "send", "dwell=9",
                               "guide=1", "--verify", *link], capture_output=True, text=True,
                              timeout=300)
        assert sent.returncode == 0, sent.stderr
        assert "dwell = 9 (read back)" in sent.stdout
        read = subprocess.run([sys.executable, "-m", "galvoscan.cli", "read", "dwell", "guide",
                               "errors", "--json", *link], capture_output=True, text=True,
                              timeout=300)
        assert read.returncode == 0, read.stderr
        assert json.loads(read.stdout) == {"dwell": 9, "guide": 1, "errors": 0}
    finally:
        board.send_signal(signal.SIGINT)
        out, err = board.communicate(timeout=120)
    assert board.returncode == 0, err
    assert "stopped after" in out and "XY2-100 frames" in out


def test_board_needs_sim():
    result = subprocess.run([sys.executable, "-m", "galvoscan.cli", "board"],
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 2 and "--sim" in result.stderr
