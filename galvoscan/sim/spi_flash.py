"""A Winbond W25Q128JV SPI flash, modelled from its datasheet (rev. F, sections 8 and 9), for
the simulated board and for the host's flashing code: the board's configuration flash.

It is driven one of two ways, both through the same command engine:

* :meth:`SPIFlashModel.pins`, once per clock with the pins' levels (SPI mode 0 or 3: COPI
  taken as SCK rises, CIPO set as it falls), for a simulated board's flash pins;
* :meth:`SPIFlashModel.transfer`, one /CS-low transaction of whole bytes, for the host's
  programmer (what an FTDI's SPI engine does).

What it models: deep power-down and its release (0xB9, 0xAB with tDP and tRES1: a command
in power-down, or before tRES1 has passed, is ignored and counted in :attr:`ignored`),
Read Data (0x03), Fast Read (0x0B, 8 dummy clocks), the JEDEC id (0x9F: EF 40 18), the status
register (0x05: BUSY, WEL), Write Enable / Disable (0x06 / 0x04), Page Program (0x02, within
one 256-byte page, bits only cleared), Sector / Block / Chip Erase (0x20, 0x52, 0xD8, 0xC7 or
0x60) with their typical times, and a read that runs past the top wrapping to address 0. A
program or erase needs Write Enable first and clears it; while one is under way only the status
register answers. An erased byte reads 0xFF.
"""

__all__ = ["SPIFlashModel", "FLASH_BYTES", "JEDEC_ID", "PAGE_BYTES", "SECTOR_BYTES"]


#: The W25Q128JV's size: 128 Mbit.
FLASH_BYTES = 16 * 1024 * 1024
#: Manufacturer (Winbond), memory type, capacity (8.2.29).
JEDEC_ID = bytes([0xEF, 0x40, 0x18])
#: A page (the most one Page Program writes) and the smallest erase, bytes.
PAGE_BYTES = 256
SECTOR_BYTES = 4096
#: Erase instructions and the bytes each erases (8.2.17 - 8.2.20).
ERASES = {0x20: SECTOR_BYTES, 0x52: 32 * 1024, 0xD8: 64 * 1024, 0xC7: FLASH_BYTES,
          0x60: FLASH_BYTES}
#: Typical times, s (9.6): page program, each erase, power-down and its release.
T_PP = 0.4e-3
T_ERASE = {SECTOR_BYTES: 45e-3, 32 * 1024: 120e-3, 64 * 1024: 150e-3, FLASH_BYTES: 40.0}
T_DP = 3e-6
T_RES1 = 3e-6


class SPIFlashModel:
    """The flash: its memory, its state, and the commands it takes. (A subclass for another
    part sets :attr:`jedec_id` and adds to :meth:`_status` and the commands.)

    Parameters
    ----------
    contents : bytes or dict of int to bytes, optional
        What the memory holds at address 0 on (bytes), or at each address given; the rest is
        erased (0xFF).
    powered_down : bool
        Start in deep power-down (as a bitstream may leave it): only the release answers.
    sck_hz : float
        SCK rate for :meth:`transfer`: the time a transaction's bytes take, so that a program
        or erase is busy for as many status reads as it would be (1 MHz).

    Attributes
    ----------
    memory : bytearray
        The 16 MiB.
    time_s : float
        The flash's clock, s: set by :meth:`pins`, advanced by :meth:`transfer`.
    ignored : list of (float, int)
        ``(time, instruction)`` of each instruction the flash did not carry out because it was
        powered down, not yet released (tRES1) or busy.
    commands : list of int
        Every instruction it carried out, in order.
    """

    #: What Read JEDEC ID (0x9F) answers.
    jedec_id = JEDEC_ID

    def __init__(self, contents=None, *, powered_down=True, sck_hz=1e6):
        self.memory = bytearray(b"\xff") * FLASH_BYTES
        if isinstance(contents, (bytes, bytearray)):
            contents = {0: contents}
        for address, block in (contents or {}).items():
            if not 0 <= address <= FLASH_BYTES - len(block):
                raise ValueError(f"{len(block)} bytes at {address:#x} do not fit the flash")
            self.memory[address:address + len(block)] = block
        self.powered_down = bool(powered_down)
        self.sck_hz = sck_hz
        self.time_s = 0.0
        self.ready_at = 0.0             # end of tRES1 / tDP / a program or erase
        self.busy = False               # a program or erase under way (until ready_at)
        self.write_enabled = False
        self.ignored = []
        self.commands = []
        self._selected = False
        self._received = []             # this transaction's bytes
        self._next_out = 0xFF           # the byte CIPO carries in the next byte slot
        # Pin level: the last levels seen, the bits of the byte coming in and going out.
        self._sck = 0
        self._bit = 0
        self._in = 0
        self._out = 0xFF
        self._cipo = 1

    # --- the command engine: whole bytes --------------------------------------------------------

    def _update(self):
        if self.busy and self.time_s >= self.ready_at:
            self.busy = False

    def _select(self):
        self._update()
        self._selected = True
        self._received = []
        self._accepted = False
        self._next_out = 0xFF

    def _byte(self, value):
        """A byte in from the host; sets what goes out in the next byte slot."""
        received = self._received
        received.append(value)
        command = received[0]
        n = len(received)
        out = 0xFF
        if n == 1:
            self._accepted = self._accepting(command)
        if not self._accepted:
            pass
        elif command in (0x03, 0x0B):
            first = 4 if command == 0x03 else 5
            if n >= first:
                address = int.from_bytes(bytes(received[1:4]), "big")
                out = self.memory[(address + n - first) % FLASH_BYTES]
        elif command == 0x9F:
            out = self.jedec_id[n - 1] if n <= len(self.jedec_id) else 0xFF
        elif command == 0x05:
            out = self._status()
        elif command == 0xAB and n >= 4:
            out = 0x17                  # the device id, after three dummy bytes
        self._next_out = out

    def _status(self):
        """The status register as Read Status Register (0x05) gives it: BUSY, WEL."""
        return int(self.busy) | int(self.write_enabled) << 1

    def _accepting(self, command):
        """Whether the flash carries out ``command``, given at its first byte (the
        datasheet's rules); an instruction it does not is counted in :attr:`ignored`."""
        self._update()
        if self.powered_down:
            ok = command == 0xAB
        elif self.busy:
            ok = command == 0x05
        else:
            ok = self.time_s >= self.ready_at
        if ok:
            self.commands.append(command)
        else:
            self.ignored.append((self.time_s, command))
        return ok

    def _deselect(self):
        """/CS rises: instructions that act at the end of their transaction do so now."""
        self._selected = False
        received = self._received
        if not received:
            return
        command = received[0]
        if self.powered_down:
            if command == 0xAB:
                self.powered_down = False
                self.ready_at = self.time_s + T_RES1
            return
        if not self._accepted:
            return
        if command == 0xB9 and len(received) == 1:
            self.powered_down = True
            self.ready_at = self.time_s + T_DP
        elif command == 0x06 and len(received) == 1:
            self.write_enabled = True
        elif command == 0x04 and len(received) == 1:
            self.write_enabled = False
        elif command == 0x02 and len(received) >= 5 and self.write_enabled:
            address = int.from_bytes(bytes(received[1:4]), "big")
            page = address & ~(PAGE_BYTES - 1)
            # Past the page's end the address wraps to the page's start (8.2.13); the last
            # 256 bytes sent are kept.
            for i, value in enumerate(received[4:][-PAGE_BYTES:]):
                at = page + (address + i) % PAGE_BYTES
                self.memory[at] &= value
            self._start_busy(T_PP)
        elif command in ERASES and self.write_enabled and \
                len(received) == (1 if ERASES[command] == FLASH_BYTES else 4):
            size = ERASES[command]
            address = int.from_bytes(bytes(received[1:4]), "big") if size < FLASH_BYTES else 0
            start = address & ~(size - 1)
            self.memory[start:start + size] = b"\xff" * size
            self._start_busy(T_ERASE[size])

    def _start_busy(self, seconds):
        self.write_enabled = False
        self.busy = True
        self.ready_at = self.time_s + seconds

    # --- driven by transactions ----------------------------------------------------------------

    def transfer(self, data):
        """One transaction: /CS low, ``data`` out and as many bytes in, /CS high; returns the
        bytes CIPO carried (0xFF where the flash drove nothing)."""
        self._select()
        answer = bytearray()
        for value in data:
            answer.append(self._next_out)
            self._byte(value)
            self.time_s += 8 / self.sck_hz
        self._deselect()
        self.time_s += 1 / self.sck_hz
        return bytes(answer)

    def wait(self, seconds):
        """Let ``seconds`` pass with /CS high."""
        self.time_s += seconds

    # --- driven by pins --------------------------------------------------------------------------

    def pins(self, cs_n, sck, copi, time_s):
        """The pins' levels at ``time_s``; returns CIPO's (1 while the flash drives it not:
        the board's pull-up)."""
        self.time_s = time_s
        if cs_n:
            if self._selected:
                self._deselect()
            self._sck = sck
            self._cipo = 1
            return 1
        if not self._selected:
            self._select()
            self._bit = 0
            self._in = 0
            self._out = 0xFF
            self._cipo = 1
        if sck and not self._sck:                       # rising: COPI in
            self._in = (self._in << 1 | (copi & 1)) & 0xFF
            self._bit += 1
            if self._bit == 8:
                self._bit = 0
                self._byte(self._in)
        elif self._sck and not sck:                     # falling: the next bit out
            if self._bit == 0:
                self._out = self._next_out
            self._cipo = self._out >> (7 - self._bit) & 1
        self._sck = sck
        return self._cipo
