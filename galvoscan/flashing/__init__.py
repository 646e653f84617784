"""Writing a board's configuration flash (``galvoscan flash``): the bitstream at 0 and a job
image at :data:`~galvoscan.gateware.player.image_format.JOB_OFFSET`, in Python on pyftdi and
pyspiflash, each region read back.

Modules, each importing only those above it here:

* :mod:`.errors` — :class:`FlashingError` (what stops a write, in one line), and the line for a
  dependency pip did not install;
* :mod:`.chips` — the flash parts, picked by their JEDEC id: pyspiflash's drivers, and
  galvoscan's own for the ISSI IS25LP several ULX3S revisions carry;
* :mod:`.ice40` — the iCE40's bitstream, checked;
* :mod:`.writer` — what both boards share: the regions to write (:func:`flash_regions`), their
  erase, write and read-back through a port that stands where pyftdi's ``SpiPort`` stands
  (:func:`program`), a flash image file as such a port (:class:`ModelPort`, ``flash --to``),
  libusb from its wheel under pyusb;
* :mod:`.icebreaker` — the iCEBreaker: its FT2232H's SPI, the FPGA held in reset meanwhile;
* :mod:`.jtag` — JTAG through an FTDI's synchronous bit-bang: the IEEE 1149.1 TAP and the
  FT231X's pins, whatever the part behind them;
* :mod:`.ecp5` — the ECP5 over JTAG: its bitstream checked, its configuration cleared, the
  flash reached through its background SPI, then the ECP5 configured from it;
* :mod:`.ulx3s` — the ULX3S: its FT231X opened in bit-bang on the ECP5's JTAG.

The names the command line and the tests use are here; the boards' own are in their modules.
"""

from .errors import FlashingError
from .writer import ModelPort, flash_regions, program


__all__ = ["FlashingError", "ModelPort", "flash_regions", "program"]
