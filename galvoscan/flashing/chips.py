"""The SPI flash parts :func:`~.writer.program` writes, picked by their JEDEC id: those
pyspiflash has drivers for, and the ISSI IS25LP series (IS25LP032, IS25LP064, IS25LP128, and
the IS25LP128F, which answers as the IS25LP128), which pyspiflash 0.6 has none for and several
ULX3S revisions carry.

The pick is galvoscan's own table (:data:`DRIVERS`) of pyspiflash's public driver classes, not
pyspiflash's private ``SerialFlashManager._get_flash``: the same ``match()`` calls in the same
order, plus :class:`IS25LPFlashDevice`.

What the IS25LP driver rests on, from ISSI's documents and from tools that write these parts:

* The IS25LP128 datasheet's features (ISSI, "IS25LP128 128Mb 3V serial flash memory with
  133MHz multi I/O SPI & quad I/O QPI DTR interface", rev. A and later; the IS25LP128F's
  datasheet, rev. A1, says the same for it): 16 MiB, 256-byte program pages (1 to 256 bytes a
  Page Program), uniform 4 KB sector and 32/64 KB block erase, SPI modes 0 and 3, 50 MHz normal
  read and fast read to 104 MHz at 2.3-3.6 V; software and hardware write protection.
* Its instructions (the IS25LP128F datasheet's table 6.3, as the ``is25lp128f`` crate lists
  it; flashrom's IS25LP032/064/128 entries, flashchips/issi.c, agree): Write Enable 06h, Write
  Disable 04h, Read Status Register 05h, Write Status Register 01h, Read 03h, Fast Read 0Bh
  (8 dummy clocks by default, the read register's dummy-cycle bits at 0), Page Program 02h,
  Sector Erase (4 KB) 20h, Block Erase 32 KB 52h and 64 KB D8h, Chip Erase C7h/60h, Deep
  Power-Down B9h and its release ABh, JEDEC id 9Fh: 9D (ISSI), 60, then 16/17/18 for
  32/64/128 Mbit (Linux's spi-nor, QEMU's m25p80 and openFPGALoader's spiFlashdb.hpp).
* Its status register: WIP bit 0, WEL bit 1, block protect BP0-BP3 bits 2-5, QE (quad
  enable) bit 6, SRWD (status register write disable, with /WP low) bit 7; BP0-BP3, QE and
  SRWD non-volatile and 0 from the factory; a program or erase in the protected area is
  inhibited; WEL cleared once a write, program or erase completes (ISSI's IS25LQ080 datasheet
  words it so for the family; the bit layout as arribada's IS25LP128F.h and openFPGALoader
  give it, the top/bottom choice being the function register's TBS bit, one-time
  programmable, not the status register's).
"""

from pyftdi.misc import pretty_size
from spiflash.serialflash import (
    AT25XE041BFlashDevice, At25FlashDevice, At45FlashDevice, By25qFlashDevice,
    En25qFlashDevice, Gd25qFlashDevice, M25PxFlashDevice, Mx25lFlashDevice, N25QFlashDevice,
    S25FlFlashDevice, S25FSFlashDevice, SerialFlash, SerialFlashRequestError,
    SerialFlashUnknownJedec, W25xFlashDevice, _Gen25FlashDevice)


__all__ = ["IS25LPFlashDevice", "DRIVERS", "flash_device", "clear_protection"]


#: Added to every maximum time below: pyspiflash gives up on a program or erase typical + max
#: seconds (wall time) after sending it, and a status read over the ULX3S's bit-banged JTAG
#: costs a USB round trip of its own.
POLL_SLACK_S = 0.02


class IS25LPFlashDevice(_Gen25FlashDevice):
    """ISSI IS25LP032 / IS25LP064 / IS25LP128(F): pyspiflash's generic '25' device (its WREN,
    RDSR polling on WIP, Page Program by 256-byte pages, Fast Read, 4 KB and 64 KB erases),
    which these parts' commands match, with their sizes, times and block protection.

    (pyspiflash's names: its "subsector" is the 4 KB sector, its "sector" the 64 KB block.)"""

    JEDEC_ID = 0x9D
    DEVICES = {0x60: "IS25LP"}
    SIZES = {0x16: 4 << 20, 0x17: 8 << 20, 0x18: 16 << 20}
    SPI_FREQ_MAX = 104      # MHz: Fast Read at 2.3-3.6 V
    # (typical, max), s. The typical is only how long pyspiflash sleeps between status reads.
    # The maxima: Page Program 0.8 ms (the IS25LP128F's, as its distributors list it); the
    # erases' are ISSI's for the IS25LP064A, its 64 Mbit sibling (4 KB 400 ms, 64 KB 1 s, as
    # libDaisy's dev_flash_IS25LP064A.h gives them), the IS25LP128's own AC table not being
    # at hand; the status register's write given pyspiflash's W25Q's maximum, 100 ms.
    TIMINGS = {"page": (0.0002, 0.0008 + POLL_SLACK_S),
               "subsector": (0.05, 0.4 + POLL_SLACK_S),
               "sector": (0.15, 1.0 + POLL_SLACK_S),
               "lock": (0.005, 0.1 + POLL_SLACK_S)}
    # No chip erase (program() erases only what it writes, and a Chip Erase is ignored while
    # any BP bit is set); no 32 KB erase: pyspiflash's half-sector pass takes its left end
    # with the 64 KB block's mask (0.6.5), and 4 KB and 64 KB erases cover any region.
    FEATURES = SerialFlash.FEAT_SECTERASE | SerialFlash.FEAT_SUBSECTERASE

    CMD_WRSR = 0x01
    SR_WIP = 0x01
    SR_WEL = 0x02
    SR_BP = 0x3C            # BP0-BP3
    SR_QE = 0x40
    SR_SRWD = 0x80

    def __init__(self, spi, jedec):
        super().__init__(spi)
        if not self.match(jedec):
            raise SerialFlashUnknownJedec(jedec)
        device, capacity = jedec[1:3]
        self._device = self.DEVICES[device]
        self._size = self.SIZES[capacity]

    def __str__(self):
        # "ISSI IS25LP128 16 MiB", as pyspiflash names its parts.
        return (f"ISSI {self._device}{len(self) >> 17:03d} "
                f"{pretty_size(self._size, lim_m=1 << 20)}")

    def unlock(self):
        """Clear BP0-BP3, if any is set, so that no block is protected; QE and SRWD stay as
        the board has them (non-volatile: QE makes /WP and /HOLD data lines for a quad-mode
        boot). A status register that stays locked (SRWD set, /WP low) is a
        :class:`~spiflash.serialflash.SerialFlashRequestError` that says so."""
        status = self._read_status()
        if not status & self.SR_BP:
            return
        self._enable_write()
        self._spi.exchange(bytes((self.CMD_WRSR,
                                  status & ~(self.SR_BP | self.SR_WIP | self.SR_WEL))))
        self._wait_for_completion(self.get_timings("lock"))
        after = self._read_status()
        if after & self.SR_BP:
            self._disable_write()       # (an ignored WRSR leaves WEL set)
            after = self._read_status()
            locked = (": SRWD is set and /WP held low, which locks it" if after & self.SR_SRWD
                      else "")
            raise SerialFlashRequestError(f"its block protection stays on (status register "
                                          f"{after:#04x}{locked})")


#: The drivers, tried in turn, the first whose ``match()`` takes the JEDEC id: pyspiflash's
#: public classes in the order its own ``_get_flash`` tries them (some makers' ids overlap:
#: Atmel's three, GigaDevice's and Boya's), then the IS25LP. Left out: pyspiflash's
#: ``Sst25FlashDevice``, whose ``write()`` pops bytes off the ``bytes`` program() gives it and
#: fails with an AttributeError after erasing (0.6.5): an SST25 is refused by its id instead,
#: before anything is erased.
DRIVERS = (
    S25FlFlashDevice, S25FSFlashDevice, M25PxFlashDevice, W25xFlashDevice, Mx25lFlashDevice,
    En25qFlashDevice, At25FlashDevice, AT25XE041BFlashDevice, At45FlashDevice,
    N25QFlashDevice, Gd25qFlashDevice, By25qFlashDevice,
    IS25LPFlashDevice,
)


def flash_device(port, jedec):
    """The driver for the part that answered ``jedec`` (its three JEDEC id bytes) on
    ``port``, or None if none of :data:`DRIVERS` takes it."""
    jedec = bytes(jedec)
    for driver in DRIVERS:
        if driver.match(jedec):
            return driver(port, jedec)
    return None


def clear_protection(device):
    """Make ``device`` writable where galvoscan knows how: the IS25LP's block protection
    cleared. pyspiflash's parts are left as they are: their ``unlock()``s write whole status
    or lock registers maker by maker, untested here, and the iCEBreaker's W25Q ships
    unprotected."""
    if isinstance(device, IS25LPFlashDevice):
        device.unlock()

