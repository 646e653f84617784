"""A ULX3S as its flash writer (galvoscan/flashing/: ulx3s.py, ecp5.py, jtag.py) sees it over
USB, modelled for the tests: the FT231X in synchronous bit-bang, the ECP5's JTAG TAP it clocks,
and the SPI flash behind the ECP5's background SPI (galvoscan.sim.spi_flash's W25Q128JV model).

Written from the documents, not from the driver, so that it catches the driver's mistakes:

* The TAP is IEEE 1149.1's (the TAP controller's state diagram, its sixteen states): TMS is
  taken on TCK's rising edge; Capture-xR loads the register on the rising edge that leaves it;
  each rising edge in Shift-xR shifts it one place toward TDO, TDI entering at the far end;
  TDO changes on the falling edge and is driven in Shift-xR only (the line's pull-up, 1,
  otherwise); Update-xR latches on the falling edge in it. Test-Logic-Reset selects the
  IDCODE instruction; an instruction the part does not have selects BYPASS, a one-bit
  register that captures 0; the IR captures ...01 in its two low bits.
* The ECP5's instructions, registers and status bits are Lattice's (the ECP5 sysCONFIG usage
  guide, TN1260), as the open tools' tables give them (openFPGALoader's src/lattice.cpp,
  ecpprog's lattice_cmds.h): IDCODE_PUB 0xE0 (32 bits), LSC_READ_STATUS 0x3C (32 bits: DONE 8,
  ISC_EN 9, BUSY 12, FAIL 13), LSC_CHECK_BUSY 0xF0 (its register nonzero while busy),
  ISC_ENABLE 0xC6 and ISC_ERASE 0x0E with an 8-bit operand, ISC_DISABLE 0x26, LSC_REFRESH 0x79
  ("equivalent to toggling PROGRAMN"), PRELOAD/SAMPLE 0x1C, BYPASS 0xFF. A configuration
  instruction is carried out in Run-Test/Idle after its update (IEEE 1532's ISC convention)
  and keeps the part busy for a while (the times here are assumptions, long enough that a
  driver which does not wait is caught); one that comes while the part is busy is ignored;
  ISC_ERASE does something only in configuration mode (after ISC_ENABLE).
* Background SPI (LSC_PROG_SPI, 0x3A) is described in no Lattice document read here: it is
  modelled as the open tools use it and as the ECP5 answers them. Its 16-bit data register
  must be updated with the key 0x68FE; from then, while the instruction stays in IR, Shift-DR
  is the flash's bus: /CS low in Shift-DR, TCK the flash's clock, TDI its input, TDO its output
  (the same bit period; openFPGALoader reads the ECP5's answer unshifted). A configured design
  that uses the flash (galvoscan's ULX3S bitstream reads its job image from it) holds its pins:
  the bridge reaches the flash only once the SRAM is erased.
* LSC_REFRESH configures the part from the flash: DONE if the flash holds, at 0, an ECP5
  bitstream whose VERIFY_ID names this part (prjtrellis' bitstream format: the FF FF BD B3
  preamble, dummy FF bytes, then commands, VERIFY_ID E2 with three option bytes and the
  IDCODE, big-endian).
* The FT231X's synchronous bit-bang is FTDI's (AN232R-01, synchronous bit bang mode): each byte
  written drives the output pins; the pins are read first, just before the byte is applied,
  and the byte read is queued for the host.
"""

__all__ = ["ECP5", "FakeFtdi", "Clock", "ecp5_bitstream", "FT231X_BITS", "ULX3S_JTAG"]


#: The FT231X's bit-bang bits: its UART pins D0-D7 (the FT231X datasheet's pin names).
FT231X_BITS = {"TXD": 0, "RXD": 1, "RTS": 2, "CTS": 3, "DTR": 4, "DSR": 5, "DCD": 6, "RI": 7}
#: The ULX3S's JTAG on them (its schematic's FT231X, as openFPGALoader's board.hpp and fujprog
#: wire it): TCK, TMS, TDI are outputs of the FTDI, TDO an input.
ULX3S_JTAG = {"TCK": "DSR", "TMS": "DCD", "TDI": "RI", "TDO": "CTS"}

#: IEEE 1149.1's TAP controller: each state and where TMS = 0 and TMS = 1 take it.
TAP_DIAGRAM = {
    "Test-Logic-Reset": ("Run-Test/Idle", "Test-Logic-Reset"),
    "Run-Test/Idle": ("Run-Test/Idle", "Select-DR-Scan"),
    "Select-DR-Scan": ("Capture-DR", "Select-IR-Scan"),
    "Capture-DR": ("Shift-DR", "Exit1-DR"),
    "Shift-DR": ("Shift-DR", "Exit1-DR"),
    "Exit1-DR": ("Pause-DR", "Update-DR"),
    "Pause-DR": ("Pause-DR", "Exit2-DR"),
    "Exit2-DR": ("Shift-DR", "Update-DR"),
    "Update-DR": ("Run-Test/Idle", "Select-DR-Scan"),
    "Select-IR-Scan": ("Capture-IR", "Test-Logic-Reset"),
    "Capture-IR": ("Shift-IR", "Exit1-IR"),
    "Shift-IR": ("Shift-IR", "Exit1-IR"),
    "Exit1-IR": ("Pause-IR", "Update-IR"),
    "Pause-IR": ("Pause-IR", "Exit2-IR"),
    "Exit2-IR": ("Shift-IR", "Update-IR"),
    "Update-IR": ("Run-Test/Idle", "Select-DR-Scan"),
}

IR_BITS = 8
IDCODE_PUB, LSC_READ_STATUS, LSC_CHECK_BUSY = 0xE0, 0x3C, 0xF0
ISC_ENABLE, ISC_ERASE, ISC_DISABLE, LSC_REFRESH = 0xC6, 0x0E, 0x26, 0x79
LSC_PROG_SPI, PRELOAD_SAMPLE, BYPASS = 0x3A, 0x1C, 0xFF
BACKGROUND_SPI_KEY = 0x68FE
DONE, ISC_EN, BUSY, FAIL = 1 << 8, 1 << 9, 1 << 12, 1 << 13
#: Boundary-scan cells (any length: the model does nothing with them).
BOUNDARY_BITS = 300
#: How long each configuration instruction keeps the part busy, s (assumed).
BUSY_S = {ISC_ENABLE: 1e-3, ISC_ERASE: 20e-3, ISC_DISABLE: 1e-3, LSC_REFRESH: 50e-3}


class Clock:
    """One clock for everything in a test: the fake FTDI advances it with each byte it clocks,
    pyspiflash's and the writer's sleeps advance it, the flash and the ECP5 read it."""

    def __init__(self):
        self.now = 0.0

    def time(self):
        return self.now

    def monotonic(self):
        return self.now

    def sleep(self, seconds):
        self.now += seconds


class ECP5:
    """The ECP5's TAP and what it does, with ``flash`` (a
    :class:`~galvoscan.sim.spi_flash.SPIFlashModel`) on its configuration SPI pins.

    ``configured``: a design is running (DONE) and holds the flash; ``state``: the TAP's
    state at the start (Test-Logic-Reset after power-up; anything after another tool). The
    tests read :attr:`carried_out` (each configuration instruction carried out, in order, with
    the flash's commands so far), :attr:`ignored`, :attr:`configured` and :attr:`spi_open`.
    """

    def __init__(self, flash, *, idcode, clock, configured=True, state="Test-Logic-Reset"):
        self.flash = flash
        self.idcode = idcode
        self.clock = clock
        self.state = state
        self.configured = configured
        self.isc_enabled = False
        self.fail = False
        self.busy_until = 0.0
        self.spi_open = False           # LSC_PROG_SPI took its key
        self.ir = IDCODE_PUB
        self.pending = False            # an updated instruction to carry out in Run-Test/Idle
        self.operands = {ISC_ENABLE: 0, ISC_ERASE: 0}
        self.ir_register = 0
        self.dr_register = 0
        self.dr_bits = 1
        self.tdo = 1
        self.carried_out = []
        self.ignored = []
        self._cs_n = 1

    # --- what the state and the instruction mean ----------------------------------------------

    def busy(self):
        return self.clock.now < self.busy_until

    def status(self):
        return (DONE * self.configured | ISC_EN * self.isc_enabled | BUSY * self.busy()
                | FAIL * self.fail)

    def bridging(self):
        """Whether Shift-DR is the flash's bus now."""
        return self.spi_open and self.ir == LSC_PROG_SPI and not self.configured

    def _capture(self):
        """The selected data register's length and what it captures."""
        ir = self.ir
        if ir == IDCODE_PUB:
            return 32, self.idcode
        if ir == LSC_READ_STATUS:
            return 32, self.status()
        if ir == LSC_CHECK_BUSY:
            return 8, int(self.busy())
        if ir in self.operands:
            return 8, 0
        if ir == LSC_PROG_SPI:
            return 16, 0
        if ir == PRELOAD_SAMPLE:
            return BOUNDARY_BITS, 0
        return 1, 0                     # BYPASS, and any instruction the model has not

    # --- the pins ----------------------------------------------------------------------------

    def rising(self, tms, tdi):
        """TCK rises with ``tms`` and ``tdi`` on their pins."""
        state = self.state
        if state == "Capture-IR":
            self.ir_register = 0b01
        elif state == "Shift-IR":
            self.ir_register = self.ir_register >> 1 | tdi << (IR_BITS - 1)
        elif state == "Capture-DR":
            self.dr_bits, self.dr_register = self._capture()
        elif state == "Shift-DR" and not self.bridging():
            self.dr_register = self.dr_register >> 1 | tdi << (self.dr_bits - 1)
        self.state = TAP_DIAGRAM[state][tms]
        if self.state == "Test-Logic-Reset":
            self.ir = IDCODE_PUB
            self.spi_open = False
            self.pending = False
        elif self.state == "Run-Test/Idle" and self.pending:
            self.pending = False
            self._carry_out(self.ir)
        self._flash_pins(1, tdi)

    def falling(self, tdi):
        """TCK falls."""
        state = self.state
        cipo = self._flash_pins(0, tdi)
        if state == "Shift-IR":
            self.tdo = self.ir_register & 1
        elif state == "Shift-DR":
            self.tdo = cipo if self.bridging() else self.dr_register & 1
        else:
            self.tdo = 1
        if state == "Update-IR":
            if self.ir_register != LSC_PROG_SPI:
                self.spi_open = False
            self.ir = self.ir_register
            self.pending = True
        elif state == "Update-DR":
            self._update_dr()

    def _flash_pins(self, sck, tdi):
        """The flash sees the clock edge with /CS as it was, then /CS as the state now has it;
        returns its output."""
        cipo = self.flash.pins(self._cs_n, sck, tdi, self.clock.now)
        cs_n = 0 if self.state == "Shift-DR" and self.bridging() else 1
        if cs_n != self._cs_n:
            self._cs_n = cs_n
            cipo = self.flash.pins(cs_n, sck, tdi, self.clock.now)
        return cipo

    def _update_dr(self):
        ir = self.ir
        if ir in self.operands:
            self.operands[ir] = self.dr_register
            self.pending = True
        elif ir == LSC_PROG_SPI and not self.spi_open:
            if self.busy():
                self.ignored.append(("key", self.dr_register))
            elif self.dr_register == BACKGROUND_SPI_KEY:
                self.spi_open = True
                self.carried_out.append(("LSC_PROG_SPI", len(self.flash.commands)))

    def _carry_out(self, ir):
        names = {ISC_ENABLE: "ISC_ENABLE", ISC_ERASE: "ISC_ERASE", ISC_DISABLE: "ISC_DISABLE",
                 LSC_REFRESH: "LSC_REFRESH"}
        if ir not in names:
            return
        if self.busy() or (ir == ISC_ERASE and not self.isc_enabled):
            self.ignored.append((names[ir], self.clock.now))
            return
        self.carried_out.append((names[ir], len(self.flash.commands)))
        if ir == ISC_ENABLE:
            self.isc_enabled = True
        elif ir == ISC_ERASE:
            self.configured = False     # the SRAM, whatever the operand says (tools differ)
        elif ir == ISC_DISABLE:
            self.isc_enabled = False
        else:
            self.isc_enabled = self.spi_open = False
            self.configured = bitstream_id(self.flash.memory) == self.idcode
        self.busy_until = self.clock.now + BUSY_S[ir]


def bitstream_id(memory):
    """The IDCODE an ECP5 bitstream at the start of ``memory`` names, or None."""
    start = bytes(memory[:4096]).find(b"\xff\xff\xbd\xb3")
    if start < 0:
        return None
    rest = bytes(memory[start + 4:start + 4 + 64]).lstrip(b"\xff")
    while rest[:1] in (b"\x3b", b"\x79"):       # a CRC reset, the SPI mode: 4 bytes each
        rest = rest[4:]
    if rest[:4] != b"\xe2\x00\x00\x00":
        return None
    return int.from_bytes(rest[4:8], "big")


class FakeFtdi:
    """pyftdi's ``Ftdi`` on a ULX3S's FT231X in synchronous bit-bang, as far as the flash
    writer uses it: ``open_bitbang_from_url``, ``write_data``, ``read_data_bytes``,
    ``close``. Each byte written moves TCK, TMS and TDI (the outputs opened) and clocks
    :class:`ECP5` on TCK's edges; the pins read just before it are queued for reading.

    ``tdo``: 0 or 1 for a TDO line stuck there (no board, a broken cable); ``bits``: where
    the ULX3S's JTAG sits on the FT231X (:data:`ULX3S_JTAG`'s); ``byte_s``: each byte's time.
    """

    def __init__(self, ecp5, clock, *, tdo=None, jtag=ULX3S_JTAG, byte_s=1e-6):
        self.ecp5 = ecp5
        self.clock = clock
        self.stuck = tdo
        bit = {signal: 1 << FT231X_BITS[pin] for signal, pin in jtag.items()}
        self.tck, self.tms, self.tdi, self.tdo = (bit[name] for name in
                                                  ("TCK", "TMS", "TDI", "TDO"))
        self.byte_s = byte_s
        self.url = None
        self.direction = 0
        self.outputs = 0
        self.written = 0
        self.closed = False
        self._samples = bytearray()

    def open_bitbang_from_url(self, url, direction=0, latency=16, baudrate=1000000,
                              sync=False):
        assert sync, "asynchronous bit-bang returns no sample a byte"
        assert direction & (self.tck | self.tms | self.tdi) == self.tck | self.tms | self.tdi
        assert not direction & self.tdo, "TDO is the ECP5's output: the FTDI must not drive it"
        self.url, self.direction = url, direction
        return baudrate

    def _pins(self):
        tdo = self.ecp5.tdo if self.stuck is None else self.stuck
        inputs = 0xFF & ~self.direction & ~self.tdo      # (the UART's idle lines read high)
        return self.outputs & self.direction | inputs | (self.tdo if tdo else 0)

    def write_data(self, data):
        assert self.url is not None and not self.closed
        for byte in bytes(data):
            self._samples.append(self._pins())
            before, self.outputs = self.outputs, byte & self.direction
            tdi = int(bool(byte & self.tdi))
            self.clock.now += self.byte_s
            if byte & self.tck and not before & self.tck:
                self.ecp5.rising(int(bool(byte & self.tms)), tdi)
            elif before & self.tck and not byte & self.tck:
                self.ecp5.falling(tdi)
        self.written += len(data)
        return len(data)

    def read_data_bytes(self, size, attempt=1):
        got = self._samples[:size]
        del self._samples[:size]
        return got

    def close(self):
        self.closed = True


def ecp5_bitstream(idcode, payload=b"", *, comment=(b"Part: LFE5U-25F-6CABGA381",)):
    """A bitstream as ecppack lays one out (prjtrellis' Bitstream::write_bit and
    serialise_chip): the comment, the preamble, dummy bytes, a CRC reset, VERIFY_ID naming
    ``idcode``, then ``payload`` in place of the rest."""
    header = b"\xff\x00" + b"".join(line + b"\x00" for line in comment) + b"\xff"
    return (header + b"\xff\xff\xbd\xb3" + b"\xff" * 2 + b"\x3b\x00\x00\x00"
            + b"\xe2\x00\x00\x00" + idcode.to_bytes(4, "big") + bytes(payload))
