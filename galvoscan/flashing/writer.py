"""Writing a board's configuration flash over SPI, whatever the board: the bitstream at 0 and a
job image at :data:`~galvoscan.gateware.player.image_format.JOB_OFFSET` (``galvoscan flash``),
each erased, written and read back by pyspiflash's driver for the part (or galvoscan's own,
:mod:`.chips`) through a port that stands where pyftdi's ``SpiPort`` stands: the iCEBreaker's
FTDI (:mod:`.icebreaker`), the ULX3S's ECP5 over JTAG (:mod:`.ecp5`), or a flash image file
(:class:`ModelPort`). Everything is checked before the first byte goes to the board: the
bitstream (by the board's check, the iCE40's by default: :mod:`.ice40`), the regions' sizes.

pyusb, under pyftdi, loads libusb from the libusb-package wheel (:func:`use_wheel_libusb`), so
that no system package is needed to open either board.
"""

import time

from ..gateware.player.image_format import FLASH_BYTES, JOB_OFFSET
from .errors import FlashingError, missing_dependency
from .ice40 import check_bitstream


__all__ = ["flash_regions", "program", "ModelPort", "use_wheel_libusb", "SPI_HZ"]


#: The SPI clock a flash is written at: the iCEBreaker's FTDI's, and what :class:`ModelPort`
#: reports.
SPI_HZ = 6e6


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
    iCEBreaker's W25Q, or with ``any_flash`` any part :mod:`.chips` has a driver for
    (pyspiflash's, and the ISSI IS25LP several ULX3S revisions carry)."""
    # (Loaded when a flash is written, as pyftdi is: pyspiflash imports it, and so do the
    # parts' drivers. A missing pyftdi is then said in one line by the board's opening,
    # before this, not by an import of galvoscan.flashing.)
    from spiflash.serialflash import SerialFlashManager, W25xFlashDevice
    from .chips import flash_device
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
    :class:`~.ecp5.BackgroundSPI`); ``progress(bytes)`` as it goes; ``any_flash``: take any
    part :mod:`.chips` knows, not only a W25Q, its block protection cleared first where it
    has one set (the IS25LP's). Returns the flash's description. A flash or a link that
    fails is a :class:`FlashingError`."""
    # (Loaded when a flash is written: see _flash_device.)
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
    # (Loaded when a flash is written: see _flash_device.)
    from spiflash.serialflash import SerialFlashRequestError
    from .chips import clear_protection
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
    # (Imported here, when a board is opened: a missing one is said in one line.)
    try:
        import libusb_package
        import usb.backend.libusb1
    except ImportError as error:
        raise FlashingError(missing_dependency(error)) from None
    backend = usb.backend.libusb1.get_backend(find_library=libusb_package.find_library)
    if backend is None:
        raise FlashingError("libusb (from the libusb-package wheel) does not load here")
    original = usb.backend.libusb1.get_backend
    usb.backend.libusb1.get_backend = lambda *args, **kwargs: backend

    def restore():
        usb.backend.libusb1.get_backend = original
    return restore
