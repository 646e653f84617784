"""Writing the iCEBreaker's configuration flash: the bitstream at 0 and a job image at
:data:`~galvoscan.gateware.player.image_format.JOB_OFFSET` (``galvoscan flash``), with what PyPI
has: pyftdi drives the board's FTDI (channel A, whose SPI pins the flash and the FPGA share),
pyspiflash the W25Q128JV on it, and libusb comes from the libusb-package wheel.

While the flash is written the FPGA is held in reset (CRESET_B, FTDI ADBUS7, low), as iceprog
holds it, so its pins leave the flash alone; after the write and its read-back, CRESET_B goes
high and the FPGA configures from the new bitstream. Everything is checked before the first
byte goes to the board: the bitstream's preamble and size (it must end below the job image),
the image as the player will check it.

The ULX3S's flash is written by the same :func:`program` through its ECP5's JTAG
(:mod:`galvoscan.flashing_ecp5`), whose port stands where pyftdi's SPI port stands here; its
part differs between board revisions, and :mod:`galvoscan.flash_chips` picks the driver by
the JEDEC id it answers (pyspiflash's, or galvoscan's own for the ISSI IS25LP).
"""

import time

from .gateware.player.image_format import FLASH_BYTES, JOB_OFFSET


__all__ = ["FlashingError", "check_bitstream", "flash_regions", "program", "ModelPort",
           "open_icebreaker", "use_wheel_libusb", "DEFAULT_URL"]


#: The iCEBreaker's FTDI, channel A (pyftdi's URL).
DEFAULT_URL = "ftdi://ftdi:2232h/1"
#: An iCE40 bitstream's synchronisation word (after an optional comment).
ICE40_PREAMBLE = b"\x7e\xaa\x99\x7e"
#: The FTDI's pins: the flash's /CS on ADBUS4 (pyftdi's /CS 1), CRESET_B on ADBUS7.
FLASH_CS = 1
CRESET_PIN = 1 << 7
#: SPI clock while writing.
SPI_HZ = 6e6


class FlashingError(Exception):
    """What stops a write, in one line."""


def check_bitstream(data, *, name="the bitstream"):
    """Refuse what is not an iCE40 bitstream, or one that would reach the job image."""
    if ICE40_PREAMBLE not in data[:256]:
        raise FlashingError(f"{name} is not an iCE40 bitstream (no 7E AA 99 7E preamble): "
                            f"give the .bin galvoscan build writes")
    if len(data) > JOB_OFFSET:
        raise FlashingError(f"{name} is {len(data):,} bytes: it would overlap the job image "
                            f"at {JOB_OFFSET:#x}")


def flash_regions(bitstream=None, job=None, *, check=check_bitstream):
    """``[(address, bytes)]`` to write: the bitstream at 0, the job image at its offset;
    ``check(bitstream)`` refuses a bitstream not for the board (the iCE40's by default)."""
    regions = []
    if bitstream is not None:
        check(bitstream)
        regions.append((0, bytes(bitstream)))
    if job is not None:
        if JOB_OFFSET + len(job) > FLASH_BYTES:
            raise FlashingError(f"the job image is {len(job):,} bytes: more than the flash "
                                f"holds above {JOB_OFFSET:#x}")
        regions.append((JOB_OFFSET, bytes(job)))
    if not regions:
        raise FlashingError("nothing to write: give a bitstream, --job, or both")
    return regions


def _flash_device(port, *, any_flash=False):
    """The flash's driver on ``port``, woken from power-down, its JEDEC id checked: the
    iCEBreaker's W25Q, or with ``any_flash`` any part :mod:`galvoscan.flash_chips` has a
    driver for (pyspiflash's, and the ISSI IS25LP several ULX3S revisions carry)."""
    # (Loaded when a flash is written, as pyftdi is: pyspiflash imports it.)
    from spiflash.serialflash import SerialFlashManager, W25xFlashDevice
    from .flash_chips import flash_device
    port.exchange(b"\xab")              # release from deep power-down (the FPGA's may be)
    time.sleep(10e-6)                   # tRES1, 3 µs
    jedec = bytes(SerialFlashManager.read_jedec_id(port))
    if any_flash:
        # JEP106 gives every manufacturer's code odd parity: FF and 00 (nothing driven) and
        # any other even byte are no flash answering.
        if bin(jedec[0]).count("1") % 2 == 0:
            raise FlashingError(f"no flash answers (JEDEC id {jedec.hex(' ')}): is the board "
                                f"connected, and nothing else holding its FTDI?")
        # (The ULX3S's part differs between board revisions.)
        device = flash_device(port, jedec)
        if device is None:
            raise FlashingError(f"the flash answers JEDEC id {jedec.hex(' ')}, a part "
                                f"galvoscan has no driver for: write it with another "
                                f"programmer (galvoscan flash --to FILE writes the image)")
        return device
    if not W25xFlashDevice.match(jedec) or jedec[2] not in W25xFlashDevice.SIZES:
        raise FlashingError(f"the flash answers JEDEC id {jedec.hex(' ')}, not a Winbond "
                            f"W25Q (EF 40 18 on the iCEBreaker): is the board connected, "
                            f"and nothing else holding its FTDI?")
    return W25xFlashDevice(port, jedec)


def program(port, regions, *, progress=None, any_flash=False):
    """Erase, write and read back each of ``regions`` on the flash behind ``port`` (a pyftdi
    :class:`~pyftdi.spi.SpiPort`, :class:`ModelPort`, or the ULX3S's
    :class:`~galvoscan.flashing_ecp5.BackgroundSPI`); ``progress(bytes)`` as it goes;
    ``any_flash``: take any part :mod:`galvoscan.flash_chips` knows, not only a W25Q, its
    block protection cleared first where it has one set (the IS25LP's). Returns the flash's
    description. A flash or a link that fails is a :class:`FlashingError`."""
    from spiflash.serialflash import SerialFlashError
    try:
        return _program(port, regions, progress, any_flash)
    except SerialFlashError as error:
        raise FlashingError(f"the flash did not do as told ({error}): is the board's FTDI "
                            f"cable sound, and the flash not write-protected?") from None
    except (OSError, ValueError) as error:      # (pyftdi's and pyusb's, a lost device)
        raise FlashingError(f"the link to the board failed while writing ({error}); the "
                            f"flash may be half written: run galvoscan flash again") from None


def _program(port, regions, progress, any_flash):
    from spiflash.serialflash import SerialFlashRequestError
    from .flash_chips import clear_protection
    device = _flash_device(port, any_flash=any_flash)
    for address, data in regions:
        # (A smaller part than the 16 MiB the image format assumes: before any erase.)
        if address + len(data) > len(device):
            raise FlashingError(f"{len(data):,} bytes at {address:#x} do not fit the flash "
                                f"({device}, {len(device):,} bytes)")
    try:
        clear_protection(device)
    except SerialFlashRequestError as error:
        raise FlashingError(f"the flash ({device}) cannot be written: {error}; nothing was "
                            f"erased") from None
    sector = device.get_erase_size()
    for address, data in regions:
        start = address - address % sector
        end = -(-(address + len(data)) // sector) * sector
        device.erase(start, end - start)
        for offset in range(0, len(data), 4096):
            chunk = data[offset:offset + 4096]
            device.write(address + offset, chunk)
            if progress:
                progress(len(chunk))
        back = device.read(address, len(data))
        if back != data:
            first = next(i for i, (a, b) in enumerate(zip(back, data)) if a != b)
            raise FlashingError(f"the flash reads back {back[first]:#04x} at "
                                f"{address + first:#x}, where {data[first]:#04x} was "
                                f"written: the write failed (write-protected, or a bad "
                                f"connection)")
    return str(device)


class ModelPort:
    """A :class:`~galvoscan.sim.spi_flash.SPIFlashModel` behind pyftdi's ``SpiPort`` calls,
    for the tests and for ``galvoscan flash --to`` (a flash image file): its clock follows
    ``clock`` (the wall's) between exchanges, so a program or erase is busy as long as the
    part's would be."""

    def __init__(self, model, *, clock=None):
        self.model = model
        self._clock = clock or (lambda: time.monotonic())
        self._last = self._clock()
        self.frequency = SPI_HZ

    def set_frequency(self, frequency):
        self.frequency = frequency

    def exchange(self, out=b"", readlen=0, start=True, stop=True, duplex=False, droptail=0):
        # The time since the last exchange passes for the flash too (a wait for an erase).
        now = self._clock()
        self.model.wait(now - self._last)
        self._last = now
        out = bytes(out)
        return self.model.transfer(out + b"\0" * readlen)[len(out):]


def use_wheel_libusb():
    """Have pyusb (under pyftdi) load libusb from the libusb-package wheel, not the system's;
    returns the function that gives pyusb its own lookup back. One-line errors."""
    try:
        import libusb_package
        import usb.backend.libusb1
    except ImportError as error:
        raise FlashingError(_missing(error)) from None
    backend = usb.backend.libusb1.get_backend(find_library=libusb_package.find_library)
    if backend is None:
        raise FlashingError("libusb (from the libusb-package wheel) does not load here")
    original = usb.backend.libusb1.get_backend
    usb.backend.libusb1.get_backend = lambda *args, **kwargs: backend

    def restore():
        usb.backend.libusb1.get_backend = original
    return restore


def _missing(error):
    return f"flashing needs {error.name} (pip install galvoscan installs it)"


def open_icebreaker(url=DEFAULT_URL):
    """``(port, release)``: the flash's SPI port on the board's FTDI with the FPGA held in
    reset; ``release()`` lets it configure and closes the FTDI. One-line errors."""
    restore = use_wheel_libusb()
    try:
        from pyftdi.ftdi import FtdiError
        from pyftdi.spi import SpiController
        from pyftdi.usbtools import UsbToolsError
    except ImportError as error:
        restore()
        raise FlashingError(_missing(error)) from None
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
