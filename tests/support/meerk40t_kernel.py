"""meerk40t's kernel for the tests, headless and in-process as meerk40t's own driver tests make it
(its test/bootstrap.py: a kernel of its core plugins, console commands), with galvoscan's plugin
loaded from the ``meerk40t.extension`` entry point pip installed and the galvoscan device
started on the tests' simulated board (:class:`sim_board.SimBoard`)."""

import contextlib
from importlib.metadata import entry_points

from galvoscan.build import PRESETS
from galvoscan.meerk40t.device import STATUS_POLL_S

from sim_board import SimBoard


def make_kernel():
    """meerk40t's kernel as its test/bootstrap.py makes it, galvoscan's plugin found through
    its entry point, and the galvoscan device started (``service device start -i galvoscan
    0``)."""
    from meerk40t.core import core
    from meerk40t.device import dummydevice
    from meerk40t.fill import fills
    from meerk40t.grbl import plugin as grbl
    from meerk40t.image import imagetools
    from meerk40t.kernel import Kernel
    from meerk40t.network import kernelserver
    kernel = Kernel("MeerK40t", "0.0.0-testing", "MeerK40t_TEST", ansi=False,
                    ignore_settings=True)
    for plugin in (kernelserver.plugin, dummydevice.plugin, core.plugin, imagetools.plugin,
                   fills.plugin, grbl.plugin):
        kernel.add_plugin(plugin)
    found = [ep for ep in entry_points().select(group="meerk40t.extension")
             if ep.name == "galvoscan"]
    assert len(found) == 1, "galvoscan's meerk40t.extension entry point is not installed"
    kernel.add_plugin(found[0].load())
    kernel(partial=True)
    kernel.console("service device start -i galvoscan 0\n")
    return kernel


@contextlib.contextmanager
def galvoscan_in_meerk40t(*, status_poll_s=0.0):
    """``(kernel, device, board, lines)``: the galvoscan device on a simulated board of the
    default bitstream (compiled), its wires and laser pins recorded; ``lines``: what the
    device says on meerk40t's console. ``status_poll_s``: the device's status poll (0: none,
    so that a test may look at the board between jobs without a poll's thread reading it at
    the same time). The board and the poll are set before the device's first poll is due
    (:data:`~galvoscan.meerk40t.device.STATUS_POLL_S` after its start)."""
    config = PRESETS["default"]
    board = SimBoard(config=config, clk_freq=config.clk_freq, baud=config.baud,
                     backend="compiled", record_laser=True)
    kernel = make_kernel()
    device = kernel.device
    assert device.name == "galvoscan"
    device.driver.make_board = lambda: board.board
    device.status_poll_s = status_poll_s
    assert device.driver.board is None, f"polled within {STATUS_POLL_S} s of the start"
    lines = []
    kernel.channel("console").watch(lambda line: lines.append(str(line)))
    try:
        yield kernel, device, board, lines
    finally:
        kernel()
