"""An ISSI IS25LP128 (the flash several ULX3S revisions carry) for the flash writer's tests:
galvoscan's W25Q128JV model (galvoscan/sim/spi_flash.py), whose reads, page program, erases,
power-down and busy rules the two parts share, with the ISSI's JEDEC id and the block
protection of its status register. Written from ISSI's documents, not from the driver
(galvoscan/flashing/chips.py):

* Read JEDEC ID (9Fh): 9D 60 18 (9D 60 16 and 9D 60 17 for the IS25LP032 and IS25LP064).
* The status register: WIP bit 0, WEL bit 1, BP0-BP3 bits 2-5, QE bit 6, SRWD bit 7; BP0-BP3,
  QE and SRWD non-volatile.
* Write Status Register (01h and one byte) needs WEL, writes bits 2-7, clears WEL when done
  and keeps the part busy meanwhile (tW: :data:`T_W` here, an assumption); while SRWD is set
  and /WP is low (hardware protected mode) it is not carried out.
* A Page Program or an erase in the protected area is inhibited (not carried out, counted in
  :attr:`IS25LPModel.refused`). ISSI's table protects, for BP0-BP3 other than 0, a part of the
  array from one end that grows with BP; the model protects the whole array for any BP other
  than 0, stricter than the part, so that a driver leaving any BP set fails whatever it writes.
"""

from galvoscan.sim.spi_flash import SPIFlashModel


__all__ = ["IS25LPModel", "IS25LP128_ID", "SR_BP", "SR_QE", "SR_SRWD"]


IS25LP128_ID = bytes([0x9D, 0x60, 0x18])
SR_BP = 0x3C
SR_QE = 0x40
SR_SRWD = 0x80
#: The status register's non-volatile bits, the ones Write Status Register writes.
NONVOLATILE = SR_BP | SR_QE | SR_SRWD
WRSR = 0x01
#: Program and erase instructions (Page Program; 4 KB, 32 KB, 64 KB and chip erase).
WRITES = {0x02, 0x20, 0x52, 0xD8, 0xC7, 0x60}
#: Write Status Register's time, s (assumed: long enough that a driver which does not wait
#: for it is caught).
T_W = 5e-3


class IS25LPModel(SPIFlashModel):
    """The IS25LP128; ``status``: its non-volatile status bits at power-up (BP, QE, SRWD);
    ``wp_n``: the /WP pin's level (the board's pull-up: 1)."""

    jedec_id = IS25LP128_ID

    def __init__(self, contents=None, *, status=0, wp_n=1, **kwargs):
        super().__init__(contents, **kwargs)
        self.nonvolatile = status & NONVOLATILE
        self.wp_n = wp_n
        #: ``(time, instruction)`` of each program or erase the block protection inhibited.
        self.refused = []

    def _status(self):
        return super()._status() | self.nonvolatile

    def _deselect(self):
        received = self._received
        if received and self._accepted and not self.powered_down:
            command = received[0]
            if command == WRSR:
                self._selected = False
                locked = self.nonvolatile & SR_SRWD and not self.wp_n
                if len(received) == 2 and self.write_enabled and not locked:
                    self.nonvolatile = received[1] & NONVOLATILE
                    self._start_busy(T_W)
                return
            if command in WRITES and self.write_enabled and self.nonvolatile & SR_BP:
                self._selected = False
                self.refused.append((self.time_s, command))
                return
        super()._deselect()
