"""The ULX3S's flash (``galvoscan flash --board ulx3s``), written in Python on pyftdi through
the board's own USB port: its FT231X (0403:6015) opened in synchronous bit-bang on the ECP5's
JTAG pins (:mod:`.jtag`), and the flash reached through the ECP5 (:mod:`.ecp5`), with the
bitstream at 0 and a job image at
:data:`~galvoscan.gateware.player.image_format.JOB_OFFSET` as on the iCEBreaker. The ULX3S's
flash part differs between board revisions: :func:`~.writer.program` is given ``any_flash``,
and :mod:`.chips` picks the driver by the JEDEC id it answers.
"""

from .ecp5 import check_bitstream, connect
from .errors import FlashingError, missing_dependency
from .jtag import BITBANG_HZ, TCK, TDI, TMS, FtdiBitbang
from .writer import use_wheel_libusb


__all__ = ["DEFAULT_URL", "open_ulx3s"]


#: The ULX3S's FT231X (0403:6015), pyftdi's URL (``ft-x``: pyftdi's name for the FT-X series).
DEFAULT_URL = "ftdi://ftdi:ft-x/1"


def open_ulx3s(url=DEFAULT_URL, *, bitstream=None):
    """``(port, release)`` as :func:`~.icebreaker.open_icebreaker` gives them, for the
    ULX3S at ``url``: the flash's :class:`~.ecp5.BackgroundSPI` through the ECP5, which must
    be the FPGA ``bitstream`` (if given) is for; ``release()`` lets the ECP5 configure from
    the flash, closes the FTDI and returns whether it configured. One-line errors."""
    idcode = check_bitstream(bitstream) if bitstream is not None else None
    return connect(_open_ftdi(url), idcode=idcode)


def _open_ftdi(url):
    """The FT231X at ``url`` in synchronous bit-bang, its JTAG pins driven. One-line errors."""
    restore = use_wheel_libusb()
    # (Imported here, when the board is opened: a missing pyftdi is said in one line.)
    try:
        from pyftdi.ftdi import Ftdi, FtdiError
        from pyftdi.usbtools import UsbToolsError
    except ImportError as error:
        restore()
        raise FlashingError(missing_dependency(error)) from None
    ftdi = Ftdi()
    try:
        # TCK, TMS and TDI out, the rest in; a 1 ms latency timer, as fujprog finds synchronous
        # bit-bang needs.
        ftdi.open_bitbang_from_url(url, direction=TCK | TMS | TDI, latency=1,
                                   baudrate=BITBANG_HZ, sync=True)
    except (FtdiError, UsbToolsError, ValueError, OSError) as error:
        restore()
        raise FlashingError(f"no ULX3S at {url} ({error}): is it plugged in, may this user "
                            f"open it (a udev rule for 0403:6015), and has no serial terminal "
                            f"got its port?") from None
    return FtdiBitbang(ftdi, on_close=restore)
