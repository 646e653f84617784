"""meerk40t with the galvoscan device, headless and in-process as meerk40t's own driver tests run
it (its test/bootstrap.py: a kernel of its core plugins, console commands), for the tests of
tests/meerk40t/: the kernel (:func:`make_kernel`; the fixtures in tests/meerk40t/conftest.py
give each test module one, on one simulated board), a job spooled and waited for
(:func:`spool_and_wait`), what meerk40t's window shows in its status bar
(:func:`status_bar_signal`, :func:`status_bar_heard`), the marks read off the XY2-100 wires and
the laser pins by the tests' own readers (:func:`marks_off_the_wires`), measured against a
rectangle meerk40t was told to draw, and a G-code sender on meerk40t's GRBL server
(:class:`GrblSender`)."""

import contextlib
import itertools
import re
import socket
import time
from importlib.metadata import entry_points
from pathlib import Path

import meerk40t
import numpy as np
from meerk40t.core import core
from meerk40t.device import dummydevice
from meerk40t.extra import hershey
from meerk40t.fill import fills
from meerk40t.grbl import plugin as grbl
from meerk40t.image import imagetools
from meerk40t.kernel import Kernel
from meerk40t.network import kernelserver

from galvoscan.meerk40t.device import STATUS_POLL_S
from galvoscan.profile.machine import default_profile

from vector_board import pulses_per_frame


__all__ = ["PROFILE", "FIELD_MM", "UNIT_MM", "RECT_MM", "SPEED_MM_S", "PRR_KHZ",
           "POWER_PERMILLE", "LEFT", "TOP", "RIGHT", "BOTTOM", "make_kernel", "spool_and_wait",
           "status_bar_signal", "status_bar_heard", "plan_name", "rect_command",
           "marks_off_the_wires", "distance_to_rect", "outline_gaps", "median_pitch",
           "GrblSender", "device_on"]


PROFILE = default_profile()
FIELD_MM = PROFILE.field.size_mm
#: One galvo unit, mm: 65536 of them across the field (XY2-100's 16 bits).
UNIT_MM = FIELD_MM / 65536
#: The rectangle: meerk40t's scene has its origin at the field's top left corner, Y down.
RECT_MM = (50.0, 52.0, 6.0, 4.0)            # x, y, width, height in the scene
SPEED_MM_S, PRR_KHZ, POWER_PERMILLE = 400.0, 50.0, 600.0
#: What meerk40t's "rect" command draws, in field mm (centre 0,0, Y up): the scene's corner
#: (x, y) is field (x - F/2, F/2 - y).
LEFT, TOP = RECT_MM[0] - FIELD_MM / 2, FIELD_MM / 2 - RECT_MM[1]
RIGHT, BOTTOM = LEFT + RECT_MM[2], TOP - RECT_MM[3]


def make_kernel():
    """meerk40t's kernel as its test/bootstrap.py makes it, with galvoscan's plugin loaded
    from the entry point pip installed."""
    kernel = Kernel("MeerK40t", "0.0.0-testing", "MeerK40t_TEST", ansi=False,
                    ignore_settings=True)
    for plugin in (kernelserver.plugin, dummydevice.plugin, core.plugin, imagetools.plugin,
                   fills.plugin, grbl.plugin, hershey.plugin):
        kernel.add_plugin(plugin)
    found = [ep for ep in entry_points().select(group="meerk40t.extension")
             if ep.name == "galvoscan"]
    assert len(found) == 1, "galvoscan's meerk40t.extension entry point is not installed"
    kernel.add_plugin(found[0].load())
    kernel(partial=True)
    kernel.console("service device start -i galvoscan 0\n")
    return kernel


@contextlib.contextmanager
def device_on(board):
    """``(kernel, device, lines)``: a meerk40t kernel with the galvoscan device on ``board``
    (a :class:`~galvoscan.sim.board.SimulatedBoard`), its status poll off, what it says on
    the console in ``lines``; the kernel shut down after."""
    kernel = make_kernel()
    device = kernel.device
    assert device.name == "galvoscan"
    device.driver.make_board = lambda: board
    device.status_poll_s = 0.0
    assert device.driver.board is None, f"polled within {STATUS_POLL_S} s of the start"
    lines = []
    kernel.channel("console").watch(lambda line: lines.append(str(line)))
    try:
        yield kernel, device, lines
    finally:
        kernel()


def spool_and_wait(kernel, device, command, *, timeout_s=60):
    """Spool ``command``'s plan and wait until the device has run (or refused) it."""
    device.driver.last_report = device.driver.last_error = None
    kernel.elements.clear_all()
    kernel.console(f"{command} {plan_name()} copy-selected preprocess validate blob preopt "
                   f"optimize spool\n")
    deadline = time.monotonic() + timeout_s
    while device.driver.last_report is None and device.driver.last_error is None:
        assert time.monotonic() < deadline, "the device did not finish the job"
        time.sleep(0.02)


def status_bar_signal():
    """The signal whose text meerk40t's main window puts in its status bar as "Laser: …": the
    ``@signal_listener`` of the handler that sets it, read off meerk40t's source (its
    gui/wxmmain.py, read as text: the tests have no wxPython)."""
    source = (Path(meerk40t.__file__).parent / "gui" / "wxmmain.py").read_text()
    found = re.findall(r'@signal_listener\("([^"]+)"\)\s+def \w+\(self, origin, value\):\s+'
                       r'self\.main_statusbar\.SetStatusText\(\s+_\("Laser: \{index\}"\)'
                       r'\.format\(index=value\)', source)
    assert len(found) == 1, "meerk40t's window no longer shows a device's state so"
    return found[0]


@contextlib.contextmanager
def status_bar_heard(kernel):
    """Within it, each text meerk40t's status bar is sent (as its window hears it: the kernel
    passes on the last of a signal's texts at each of its ticks), as a set of its items
    (``ready``, ``disarmed`` …), in order."""
    heard = []
    signal = status_bar_signal()

    def listener(origin, text):
        heard.append(set(text.split(", ")))
    kernel.listen(signal, listener)
    try:
        yield heard
    finally:
        kernel.unlisten(signal, listener)


_plans = itertools.count(1)


def plan_name():
    """A plan of its own for each job (meerk40t's plans keep what was copied into them)."""
    return f"plan{next(_plans)}"


def rect_command(x, y, width, height):
    return (f"rect {x}mm {y}mm {width}mm {height}mm engrave -s {SPEED_MM_S:g} "
            f"-p {POWER_PERMILLE:g} frequency {PRR_KHZ:g}")


def marks_off_the_wires(board, since):
    """The positions (field mm) the laser pulsed at, frame ``since`` on, a row each run of
    frames at one position, and the pulses at each: read off the wires and pins by the tests'
    readers."""
    board.run_for(0)
    runs = []
    for xy, pulses in pulses_per_frame(board, since):
        if runs and runs[-1][0] == xy:
            runs[-1][1] += pulses
        else:
            runs.append([xy, pulses])
    marked = [(xy, n) for xy, n in runs if n]
    points = (np.array([xy for xy, _ in marked], dtype=float) - 32768) * UNIT_MM
    return points, np.array([n for _, n in marked])


def distance_to_rect(points, left=None, top=None, right=None, bottom=None):
    """Each point's distance from a rectangle's outline (field mm; None: :data:`RECT_MM`'s)."""
    left, top = (LEFT, TOP) if left is None else (left, top)
    right, bottom = (RIGHT, BOTTOM) if right is None else (right, bottom)
    x, y = points[:, 0], points[:, 1]
    inside_x = np.clip(x, left, right)
    inside_y = np.clip(y, bottom, top)
    to_vertical = np.hypot(np.minimum(abs(x - left), abs(x - right)), y - inside_y)
    to_horizontal = np.hypot(x - inside_x, np.minimum(abs(y - top), abs(y - bottom)))
    return np.minimum(to_vertical, to_horizontal)


def outline_gaps(marks, left, top, right, bottom):
    """The largest distance from a point of the rectangle's outline to the nearest mark."""
    outline = np.concatenate([
        np.column_stack([np.linspace(left, right, 200), np.full(200, top)]),
        np.column_stack([np.linspace(left, right, 200), np.full(200, bottom)]),
        np.column_stack([np.full(200, left), np.linspace(bottom, top, 200)]),
        np.column_stack([np.full(200, right), np.linspace(bottom, top, 200)])])
    return np.min(np.hypot(*(outline[:, None, :] - marks[None, :, :]).transpose(2, 0, 1)),
                  axis=1).max()


def median_pitch(marks):
    """The distance from one marked point to the next, off the wires (their median)."""
    return float(np.median(np.hypot(*np.diff(marks, axis=0).T)))


class GrblSender:
    """A G-code sender on the loopback port: a line at a time, each waiting for its answer
    (as GRBL's simple send-response streaming does)."""

    def __init__(self, port):
        deadline = time.monotonic() + 10
        while True:             # (the server's thread may not be listening yet)
            try:
                self.socket = socket.create_connection(("127.0.0.1", port), timeout=30)
                break
            except ConnectionRefusedError:
                assert time.monotonic() < deadline, f"no GRBL server on port {port}"
                time.sleep(0.05)
        self.pending = b""
        # The greeting: GRBL's banner and its message line.
        assert self.line().startswith("Grbl ")
        assert self.line().startswith("[MSG:")

    def line(self):
        while b"\n" not in self.pending:
            got = self.socket.recv(4096)
            assert got, "the GRBL server closed the connection"
            self.pending += got
        line, self.pending = self.pending.split(b"\n", 1)
        return line.strip().decode()

    def send(self, text):
        self.socket.sendall(text.encode() + b"\n")
        return self.line()

    def close(self):
        self.socket.close()
