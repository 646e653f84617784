# amaranth: UnusedElaboratable=no
# (parameter checks build components without elaborating them)
"""The build options for the smallest FPGAs (the iCEstick's HX1K): serial multipliers, one host
link, no laser controller; on the system top's pins."""

import pytest

from galvoscan.link.client import HostClient, WriteRefused
from galvoscan.gateware.sources.spiral_table import SpiralTable
from galvoscan.gateware.top import GalvoScanTop, ScanSettings
from galvoscan.platforms.icestick import ICEStickScanner

from link_codec import command
from sim_board import SimBoard, SimSPITransport, SimUARTTransport
from spiral_model import spiral_frames
from wires import frames_from_samples, record_falling_edges


#: The iCEstick's top, as platforms/icestick.py builds it.
SMALL = dict(modes=("spiral",), correction=None, multiplier="serial", links=("uart",),
             laser=False, spiral_interpolation=False)


@pytest.mark.parametrize("dwell", [1, 3])
def test_small_top_draws_the_spiral(dwell):
    """With the serial multipliers, the frames on the wires are the spiral model's, frame for
    frame: the 17-clock products fit inside a frame (40 clocks at 4 MHz)."""
    table = SpiralTable()
    settings = ScanSettings(dwell=dwell, amp_x=30000, amp_y=45000, center_x=31000,
                            center_y=36000)
    top = GalvoScanTop(clk_freq=4e6, table=table, settings=settings, **SMALL)
    frames = frames_from_samples(record_falling_edges(top, 4e6, frames=2 + 150 * dwell))
    assert frames == spiral_frames(table.x, table.y, 150, dwell=dwell, x_range=(0, 127),
                                   y_range=(1, 126), gain=(30000, 45000), centre=(31000, 36000))


def test_small_top_answers_on_uart_only_and_has_no_laser():
    board = SimBoard(record_laser=True, **SMALL)
    uart = HostClient(SimUARTTransport(board))
    assert uart.read("errors") == 0
    uart.write("dwell", 4)
    assert uart.read("dwell") == 4
    # The laser registers are not there: writes are refused and counted, nothing switches on.
    for name, value in (("laser_power", 200), ("arm", 1), ("fault_clear", 1)):
        with pytest.raises(WriteRefused) as refused:
            uart.write(name, value)
        assert refused.value.reason == "register"
    assert uart.read("errors") == 3
    board.run_for(1e-3)
    assert not any(any(pins) for pins in board.laser_pins)
    # SPI is not built: frames on its pins change nothing and are not answered.
    spi = SimSPITransport(board)
    spi.transfer(command(uart.sequence(), 0x04, 9))        # dwell = 9
    assert uart.read("dwell") == 4 and uart.read("errors") == 3


@pytest.mark.parametrize("kwargs, message", [
    (dict(multiplier="lut"), "multiplier must be dsp or serial"),
    (dict(multiplier="serial"), "the serial multiplier is for FPGAs without DSP blocks"),
    (dict(links=()), "links must be some of spi, uart"),
    (dict(links=("usb",)), "links must be some of spi, uart"),
    (dict(laser=False), "vector mode times its points by the laser's pulses"),
])
def test_top_rejects_bad_small_options(kwargs, message):
    with pytest.raises(ValueError, match=message):
        GalvoScanTop(clk_freq=12e6, **kwargs)


@pytest.mark.parametrize("kwargs, message", [
    (dict(modes=("spiral", "vector")), "holds the spiral mode only"),
    (dict(clock=24e6), "12 MHz oscillator only"),
])
def test_icestick_refuses_what_does_not_fit(kwargs, message):
    with pytest.raises(ValueError, match=message):
        ICEStickScanner.config(**kwargs)
