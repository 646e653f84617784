"""The ULX3S's ECP5 as the flash writer tells it over JTAG (:mod:`.jtag`): its bitstream
checked, its configuration cleared, and its flash reached through it. The flash is not on the
JTAG's pins; the ECP5 reaches it for us. Its JTAG instruction LSC_PROG_SPI, given its 16-bit
key, turns the TAP's Shift-DR into the flash's SPI bus ("background SPI"): TCK clocks the flash
(MCLK), TDI goes to the flash's input, the flash's output comes out of TDO, /CS is low while
the TAP is in Shift-DR. :class:`BackgroundSPI` makes one SPI transaction of each
``exchange()``, pyftdi's ``SpiPort`` call, so that :func:`~.writer.program` and pyspiflash
erase, write and read back this flash as they do the iCEBreaker's.

The sequence is openFPGALoader's for an ECP5's external flash (src/lattice.cpp:
``program_extFlash`` after ``prepare_flash_access``, ``clearSRAM``, ``EnableISC``,
``DisableISC``, then ``post_flash_access``), written again here; ecpprog's (Greg Davill's,
whom openFPGALoader credits for the key; its ``enter_spi_background_mode``) agrees with it:

1. IDCODE (IDCODE_PUB, 0xE0): an ECP5, the one the bitstream's VERIFY_ID names. Nothing is
   changed on the board before this passes.
2. PRELOAD/SAMPLE (0x1C) of the boundary scan with ones, BYPASS; ISC_ENABLE (0xC6, operand
   0), ISC_ERASE (0x0E) of the SRAM (operand 1), ISC_DISABLE (0x26), each followed by clocks in
   Run-Test/Idle and LSC_CHECK_BUSY (0xF0) polled until the ECP5 is done, and the status
   register (LSC_READ_STATUS, 0x3C) checked: the running design (galvoscan's reads this flash
   with its job player) lets go of the flash's pins.
3. LSC_PROG_SPI (0x3A) with 0x68FE shifted as its data register, then Run-Test/Idle: the
   flash is on Shift-DR from here on.
4. Afterwards LSC_REFRESH (0x79), as toggling PROGRAMN: the ECP5 configures from the new flash;
   its DONE bit (status bit 8) says whether it took the bitstream.
"""

import time

from ..gateware.player.image_format import JOB_OFFSET
from .errors import FlashingError
from .ice40 import ICE40_PREAMBLE
from .jtag import BITBANG_HZ, JTAG


__all__ = ["ECP5_IDCODES", "check_bitstream", "connect", "ECP5TAP", "BackgroundSPI"]


#: ECP5 IDCODEs and their parts (openFPGALoader's src/part.hpp; ecpprog's lattice_cmds.h lists
#: the same): a ULX3S carries an LFE5U-12F, -25F, -45F or -85F.
ECP5_IDCODES = {
    0x21111043: "LFE5U-12F", 0x41111043: "LFE5U-25F", 0x41112043: "LFE5U-45F",
    0x41113043: "LFE5U-85F", 0x01111043: "LFE5UM-25F", 0x01112043: "LFE5UM-45F",
    0x01113043: "LFE5UM-85F", 0x81111043: "LFE5UM5G-25F", 0x81112043: "LFE5UM5G-45F",
    0x81113043: "LFE5UM5G-85F",
}

# The ECP5's JTAG instructions (8-bit IR), as openFPGALoader's lattice.cpp names them.
IDCODE_PUB = 0xE0
PRELOAD = 0x1C
BYPASS = 0xFF
ISC_ENABLE = 0xC6
ISC_ERASE = 0x0E
ISC_DISABLE = 0x26
LSC_CHECK_BUSY = 0xF0
LSC_READ_STATUS = 0x3C
LSC_PROG_SPI = 0x3A
LSC_REFRESH = 0x79
#: LSC_PROG_SPI's data register: the key that opens the flash to Shift-DR (shifted LSB first,
#: 0xFE then 0x68, as openFPGALoader and ecpprog shift it).
SPI_KEY = 0x68FE
#: ISC_ERASE's operand: the SRAM (openFPGALoader's FLASH_ERASE_SRAM).
ERASE_SRAM = 0x01
#: The boundary-scan bits PRELOAD is given, all ones (openFPGALoader's 26 bytes).
PRELOAD_BITS = 26 * 8
#: Status register bits (LSC_READ_STATUS; openFPGALoader's REG_STATUS_*, ecpprog's decoding).
STATUS_DONE = 1 << 8
STATUS_ISC_EN = 1 << 9
STATUS_BUSY = 1 << 12
STATUS_FAIL = 1 << 13
#: TCK periods in Run-Test/Idle after each configuration instruction (openFPGALoader's 1000).
IDLE_CLOCKS = 1000
#: The longest an instruction may keep the ECP5 busy, and configuring from the flash may take
#: (seconds for a large bitstream at the ECP5's slow default master clock), s.
BUSY_TIMEOUT_S = 2.0
REFRESH_TIMEOUT_S = 10.0
POLL_S = 1e-3

#: An ECP5 bitstream as ecppack writes its .bit: a comment (FF 00, NUL-ended strings, FF),
#: then the preamble; after the preamble's dummy bytes, the commands (prjtrellis'
#: libtrellis/src/Bitstream.cpp, serialise_chip and write_bit; its docs'
#: architecture/bitstream_format).
COMMENT_START = b"\xff\x00"
ECP5_PREAMBLE = b"\xff\xff\xbd\xb3"
#: The commands ecppack may write before VERIFY_ID (the SPI mode, a CRC reset), each with its
#: three bytes of options and no payload, and VERIFY_ID itself, whose payload is the IDCODE.
SPI_MODE = 0x79
LSC_RESET_CRC = 0x3B
VERIFY_ID = 0xE2


def check_bitstream(data, *, name="the bitstream"):
    """Refuse what is not an ECP5 bitstream as ecppack writes it (the .bit ``galvoscan build
    --board ulx3s`` writes: a comment, the FF FF BD B3 preamble, VERIFY_ID naming an ECP5), or
    one that would reach the job image; returns the IDCODE the bitstream is for."""
    data = bytes(data)
    start = 0
    if data.startswith(COMMENT_START):
        end = data.find(b"\xff", len(COMMENT_START))
        start = len(data) if end < 0 else end
    preamble = data.find(ECP5_PREAMBLE, start, start + 64)
    if preamble < 0 or data[start:preamble].strip(b"\xff"):
        ice40 = ICE40_PREAMBLE in data[:256]
        raise FlashingError(f"{name} is not an ECP5 bitstream (no FF FF BD B3 preamble after "
                            f"its comment): "
                            + ("it is an iCE40's: flash it with --board icebreaker" if ice40
                               else "give the .bit galvoscan build --board ulx3s writes"))
    idcode = _verify_id(data, preamble + len(ECP5_PREAMBLE))
    if idcode is None:
        raise FlashingError(f"{name} has no VERIFY_ID (E2) command after its preamble: it "
                            f"names no FPGA (not ecppack's, or damaged)")
    if idcode not in ECP5_IDCODES:
        raise FlashingError(f"{name} is for IDCODE {idcode:#010x}, which is no ECP5")
    if len(data) > JOB_OFFSET:
        raise FlashingError(f"{name} is {len(data):,} bytes: it would overlap the job image at "
                            f"{JOB_OFFSET:#x} (a larger ECP5's uncompressed bitstream can: "
                            f"pack it with ecppack --compress)")
    return idcode


def _verify_id(data, at):
    """The IDCODE of the VERIFY_ID command among the first commands from ``at``, or None."""
    end = min(len(data), at + 64)
    while at < end:
        command = data[at]
        if command == 0xFF:                             # dummy bytes
            at += 1
        elif command in (SPI_MODE, LSC_RESET_CRC):
            at += 4
        elif command == VERIFY_ID and at + 8 <= len(data):
            return int.from_bytes(data[at + 4:at + 8], "big")
        else:
            return None
    return None


class ECP5TAP(JTAG):
    """The ECP5's TAP: :class:`~.jtag.JTAG` with the ECP5's instructions for its IDCODE, its
    status register and its configuration commands."""

    def idcode(self):
        return int.from_bytes(self.read(IDCODE_PUB, 4), "little")

    def status(self):
        return int.from_bytes(self.read(LSC_READ_STATUS, 4), "little")

    def command(self, instruction, operand=None, *, what, timeout_s=BUSY_TIMEOUT_S):
        """``instruction`` (with its 8-bit ``operand``) carried out in Run-Test/Idle, and
        LSC_CHECK_BUSY polled until the ECP5 is done with it; returns the status register."""
        if operand is None:
            self.shift_ir(instruction)
        else:
            self.shift_ir(instruction, end="exit1_ir")
            self.shift_dr(bytes((operand,)))
        self.idle(IDLE_CLOCKS)
        deadline = time.monotonic() + timeout_s
        while self.read(LSC_CHECK_BUSY, 1) != b"\0":
            if time.monotonic() > deadline:
                raise FlashingError(f"the ECP5 stays busy after {what} (status register "
                                    f"{self.status():#010x})")
            time.sleep(POLL_S)
        return self.status()


#: Each byte with its bits reversed: the flash takes MSB first, JTAG shifts LSB first.
_REVERSED = bytes(int(f"{value:08b}"[::-1], 2) for value in range(256))


class BackgroundSPI:
    """The flash behind the ECP5's LSC_PROG_SPI, as pyftdi's ``SpiPort``: each
    :meth:`exchange` is one SPI transaction, /CS low while the TAP is in Shift-DR, the bytes'
    bits reversed (JTAG shifts LSB first, the flash takes MSB first). The flash's answer comes
    out of TDO in step with TDI, as openFPGALoader reads it on the ECP5 (``spi_put``)."""

    def __init__(self, jtag):
        self.jtag = jtag
        self.frequency = BITBANG_HZ / 2     # TCK at most, Hz (pyspiflash asks for it)

    def set_frequency(self, frequency):
        """(TCK is the bit-bang's: it is not set per transaction.)"""

    def exchange(self, out=b"", readlen=0, start=True, stop=True, duplex=False, droptail=0):
        """Send ``out`` and return the ``readlen`` bytes that follow it (half duplex), or
        those that come in with it (``duplex``), as pyftdi's SpiPort does; ``stop=False``
        keeps /CS low (the TAP stays in Shift-DR) for the next exchange to continue, which
        then gives ``start=False``; ``droptail`` leaves out the last byte's last bits."""
        if not 0 <= droptail <= 7:
            raise ValueError(f"droptail is 0 to 7 bits, not {droptail}")
        out = bytes(out)
        if duplex:
            out += bytes(max(0, readlen - len(out)))
            readlen = readlen or len(out)
            sent = out
        else:
            sent = out + bytes(readlen)
        if not sent:
            return b""
        got = self.jtag.shift_dr(sent.translate(_REVERSED), 8 * len(sent) - droptail,
                                 read=bool(readlen), end="idle" if stop else "shift_dr")
        if not readlen:
            return b""
        got = got.translate(_REVERSED)
        return got[:readlen] if duplex else got[len(out):]


# --- the flash opened through the ECP5 --------------------------------------------------------

def connect(pins, *, idcode=None):
    """``(port, release)`` on a ULX3S's JTAG through the bit-bang port ``pins`` (``clock()``
    and ``close()``, :class:`~.jtag.FtdiBitbang`): its ECP5 checked (``idcode``: the one the
    bitstream is for; None: any ECP5), its configuration cleared, the flash opened to
    Shift-DR; ``port`` is the flash's :class:`BackgroundSPI`. ``release()`` sends
    LSC_REFRESH, closes ``pins`` and returns whether the ECP5 configured from the flash.
    One-line errors; a wrong FPGA is refused before anything on the board changes."""
    jtag = ECP5TAP(pins)
    try:
        jtag.reset()
        _check_idcode(jtag.idcode(), idcode)
    except BaseException:
        pins.close()
        raise
    try:
        _clear_configuration(jtag)
        # The key as LSC_PROG_SPI's data register, from Exit1-IR straight to Shift-DR; then
        # Run-Test/Idle, which ecpprog found essential.
        jtag.shift_ir(LSC_PROG_SPI, end="exit1_ir")
        jtag.shift_dr(SPI_KEY.to_bytes(2, "little"))
    except BaseException:
        try:
            _refresh(jtag)              # (the FPGA back from its flash, as it was)
        except FlashingError:
            pass                        # (the first error is the one to report)
        finally:
            pins.close()
        raise

    def release():
        try:
            configured = _refresh(jtag)
            jtag.shift_ir(BYPASS)
            jtag.reset()
        finally:
            pins.close()
        return configured
    return BackgroundSPI(jtag), release


def _check_idcode(found, expected):
    if found in (0, 0xFFFFFFFF):
        raise FlashingError(f"no JTAG answers on the ULX3S's FTDI (TDO reads all "
                            f"{'ones' if found else 'zeros'}): is the board powered, and is "
                            f"it a ULX3S?")
    if found not in ECP5_IDCODES:
        raise FlashingError(f"the board's JTAG answers IDCODE {found:#010x}, no ECP5 (a ULX3S's "
                            f"LFE5U: 12F {0x21111043:#010x}, 25F {0x41111043:#010x}, 45F "
                            f"{0x41112043:#010x}, 85F {0x41113043:#010x})")
    if expected is not None and found != expected:
        part = ECP5_IDCODES[found]
        raise FlashingError(f"the board's FPGA is an {part} (IDCODE {found:#010x}), the "
                            f"bitstream is for an {ECP5_IDCODES[expected]} ({expected:#010x}): "
                            f"build it with galvoscan build --board ulx3s --device "
                            f"{part.split('-')[1]}")


def _clear_configuration(jtag):
    """The ECP5's SRAM erased, so that the design lets go of the flash (openFPGALoader's
    clearSRAM): the boundary scan preloaded with ones (the pins' levels while the ECP5 is in
    configuration mode), then ISC_ENABLE, ISC_ERASE of the SRAM, ISC_DISABLE."""
    jtag.shift_ir(PRELOAD, end="exit1_ir")
    jtag.shift_dr(b"\xff" * (PRELOAD_BITS // 8))
    jtag.shift_ir(BYPASS)
    status = jtag.command(ISC_ENABLE, 0x00, what="ISC_ENABLE")
    if not status & STATUS_ISC_EN:
        raise FlashingError(f"the ECP5 did not enter configuration mode (ISC_ENABLE; status "
                            f"register {status:#010x})")
    status = jtag.command(ISC_ERASE, ERASE_SRAM, what="ISC_ERASE")
    if status & STATUS_FAIL:
        raise FlashingError(f"the ECP5 failed to erase its configuration (ISC_ERASE; status "
                            f"register {status:#010x})")
    status = jtag.command(ISC_DISABLE, what="ISC_DISABLE")
    if status & STATUS_ISC_EN:
        raise FlashingError(f"the ECP5 stays in configuration mode (ISC_DISABLE; status "
                            f"register {status:#010x})")


def _refresh(jtag):
    """LSC_REFRESH: the ECP5 leaves background SPI and configures from the flash; whether it
    did (DONE), waited for as long as a large bitstream takes to load."""
    jtag.command(LSC_REFRESH, what="LSC_REFRESH", timeout_s=REFRESH_TIMEOUT_S)
    deadline = time.monotonic() + REFRESH_TIMEOUT_S
    while not jtag.status() & STATUS_DONE:
        if time.monotonic() > deadline:
            return False
        time.sleep(10 * POLL_S)
    return True
