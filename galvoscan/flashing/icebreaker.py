"""The iCEBreaker's flash on its FTDI (an FT2232H): pyftdi drives channel A, whose SPI pins
the flash and the FPGA share, and :func:`~.writer.program` writes the W25Q128JV on it.

While the flash is written the FPGA is held in reset (CRESET_B, FTDI ADBUS7, low), as iceprog
holds it, so its pins leave the flash alone; after the write and its read-back, CRESET_B goes
high and the FPGA configures from the new bitstream (:mod:`.ice40` checks it first).
"""

import time

from .errors import FlashingError, missing_dependency
from .writer import SPI_HZ, use_wheel_libusb


__all__ = ["DEFAULT_URL", "open_icebreaker"]


#: The iCEBreaker's FTDI, channel A (pyftdi's URL).
DEFAULT_URL = "ftdi://ftdi:2232h/1"
#: The FTDI's pins: the flash's /CS on ADBUS4 (pyftdi's /CS 1), CRESET_B on ADBUS7.
FLASH_CS = 1
CRESET_PIN = 1 << 7


def open_icebreaker(url=DEFAULT_URL):
    """``(port, release)``: the flash's SPI port on the board's FTDI with the FPGA held in
    reset; ``release()`` lets it configure and closes the FTDI. One-line errors."""
    restore = use_wheel_libusb()
    # (Imported here, when the board is opened: a missing pyftdi is said in one line.)
    try:
        from pyftdi.ftdi import FtdiError
        from pyftdi.spi import SpiController
        from pyftdi.usbtools import UsbToolsError
    except ImportError as error:
        restore()
        raise FlashingError(missing_dependency(error)) from None
    controller = SpiController(cs_count=FLASH_CS + 1)
    try:
        controller.configure(url, frequency=SPI_HZ)
    except (FtdiError, UsbToolsError, ValueError, OSError) as error:
        restore()
        raise FlashingError(f"no iCEBreaker at {url} ({error}): is it plugged in, and may "
                            f"this user open it (a udev rule for 0403:6010)?") from None
    gpio = controller.get_gpio()
    gpio.set_direction(CRESET_PIN, CRESET_PIN)
    gpio.write(0)                       # CRESET_B low: the FPGA lets go of the flash
    time.sleep(0.01)

    def release():
        gpio.write(CRESET_PIN)          # CRESET_B high: the FPGA configures
        controller.terminate()
        restore()
    return controller.get_port(FLASH_CS, freq=SPI_HZ), release
