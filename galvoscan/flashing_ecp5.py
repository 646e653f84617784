"""Writing the ULX3S's configuration flash (``galvoscan flash --board ulx3s``) through its
ECP5's JTAG, in Python on pyftdi, with the bitstream at 0 and a job image at
:data:`~galvoscan.gateware.player.image_format.JOB_OFFSET` as on the iCEBreaker.

The ULX3S's USB chip is an FT231X (0403:6015), a UART with no MPSSE engine: the ECP5's JTAG
hangs on the UART's modem pins, which pyftdi drives in synchronous bit-bang (as fujprog and
openFPGALoader's ``ft231X`` cable do), two pin writes a TCK period. The flash is not on those
pins; the ECP5 reaches it for us. Its JTAG instruction LSC_PROG_SPI, given its 16-bit key,
turns the TAP's Shift-DR into the flash's SPI bus ("background SPI"): TCK clocks the flash
(MCLK), TDI goes to the flash's input, the flash's output comes out of TDO, /CS is low while
the TAP is in Shift-DR. :class:`BackgroundSPI` makes one SPI transaction of each
``exchange()``, pyftdi's ``SpiPort`` call, so that :func:`galvoscan.flashing.program` and
pyspiflash erase, write and read back this flash as they do the iCEBreaker's.

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

import numpy as np

from .flashing import FlashingError, _missing, use_wheel_libusb
from .gateware.player.image_format import JOB_OFFSET


__all__ = ["DEFAULT_URL", "ECP5_IDCODES", "check_bitstream", "open_ulx3s", "connect",
           "FtdiBitbang", "JTAG", "BackgroundSPI"]


#: The ULX3S's FT231X (0403:6015), pyftdi's URL (``ft-x``: pyftdi's name for the FT-X series).
DEFAULT_URL = "ftdi://ftdi:ft-x/1"

#: The FT231X's bit-bang bits are its UART pins (D0-D7: TXD, RXD, RTS, CTS, DTR, DSR, DCD, RI);
#: the ULX3S wires its ECP5's JTAG to four of them: TCK on DSR, TMS on DCD, TDI on RI, TDO on
#: CTS. From openFPGALoader's src/board.hpp, the "ulx3s" entry (JTAG_BITBANG_BOARD on the
#: "ft231X" cable with TMS = FT232RL_DCD, TCK = FT232RL_DSR, TDI = FT232RL_RI,
#: TDO = FT232RL_CTS), and fujprog.c's cable_hw_map for 0403:6015 "ULX3S FPGA ..." (tck 0x20,
#: tms 0x40, tdi 0x80, tdo 0x08): the two agree.
TCK = 1 << 5
TMS = 1 << 6
TDI = 1 << 7
TDO = 1 << 3
#: Pin writes a second in bit-bang (pyftdi's bit-bang rate, fujprog's 1 M): two a TCK period,
#: so TCK is 500 kHz at most; the USB round trips of synchronous bit-bang keep it well below.
BITBANG_HZ = 1_000_000
#: Pin writes sent before their samples are read: synchronous bit-bang samples the pins for
#: every byte written and holds the output while the FT231X's 512-byte buffer towards the host
#: is full, so a chunk must fit in it (fujprog's is 384 on Linux, openFPGALoader's 512).
CHUNK_BYTES = 384
#: How long the FTDI may take to return a chunk's samples, s.
READ_TIMEOUT_S = 2.0

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
        ice40 = b"\x7e\xaa\x99\x7e" in data[:256]
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


# --- the JTAG port --------------------------------------------------------------------------

#: IEEE 1149.1's TAP controller: state → (the next state with TMS low, with TMS high).
_TAP = {
    "reset": ("idle", "reset"),
    "idle": ("idle", "select_dr"),
    "select_dr": ("capture_dr", "select_ir"),
    "capture_dr": ("shift_dr", "exit1_dr"),
    "shift_dr": ("shift_dr", "exit1_dr"),
    "exit1_dr": ("pause_dr", "update_dr"),
    "pause_dr": ("pause_dr", "exit2_dr"),
    "exit2_dr": ("shift_dr", "update_dr"),
    "update_dr": ("idle", "select_dr"),
    "select_ir": ("capture_ir", "reset"),
    "capture_ir": ("shift_ir", "exit1_ir"),
    "shift_ir": ("shift_ir", "exit1_ir"),
    "exit1_ir": ("pause_ir", "update_ir"),
    "pause_ir": ("pause_ir", "exit2_ir"),
    "exit2_ir": ("shift_ir", "update_ir"),
    "update_ir": ("idle", "select_dr"),
}


def _paths():
    """Every state → every state: the shortest TMS sequence (breadth first)."""
    paths = {}
    for start in _TAP:
        found = {start: ()}
        frontier = [start]
        while frontier:
            following = []
            for state in frontier:
                for tms, after in enumerate(_TAP[state]):
                    if after not in found:
                        found[after] = found[state] + (tms,)
                        following.append(after)
            frontier = following
        paths[start] = found
    return paths


_PATHS = _paths()


def _tick(tms, tdi):
    """One TCK period: TMS and TDI set with TCK low, then TCK high (the TAP's rising edge)."""
    pins = (TMS if tms else 0) | (TDI if tdi else 0)
    return bytes((pins, pins | TCK))


#: A byte shifted LSB first with TMS low: its 16 pin writes.
_SHIFT = [b"".join(_tick(0, value >> bit & 1) for bit in range(8)) for value in range(256)]
#: Each byte with its bits reversed: the flash takes MSB first, JTAG shifts LSB first.
_REVERSED = bytes(int(f"{value:08b}"[::-1], 2) for value in range(256))


class JTAG:
    """An IEEE 1149.1 TAP driven through a bit-bang port: ``pins.clock(data)`` writes the pin
    bytes of ``data`` in turn and returns, for each, the pins sampled just before it was
    written (FTDI's synchronous bit-bang). A TCK period is two writes, TCK low then high; TDO
    is read from the second's sample, taken while TCK is still low, after the falling edge
    that put the bit on TDO (and before the rising edge that shifts the next)."""

    def __init__(self, pins):
        self.pins = pins
        self.state = None               # unknown until reset()

    def reset(self):
        """Test-Logic-Reset, whatever the state: five TMS-high clocks reach it from any."""
        self.pins.clock(_tick(1, 1) * 6)
        self.state = "reset"

    def _go(self, goal):
        """The pin writes that take the TAP to ``goal``."""
        path = _PATHS[self.state][goal]
        self.state = goal
        return b"".join(_tick(tms, 1) for tms in path)

    def idle(self, clocks):
        """Run-Test/Idle for ``clocks`` TCK periods."""
        self.pins.clock(self._go("idle") + _tick(0, 1) * clocks)

    def shift_ir(self, instruction, *, end="idle"):
        """Shift the 8-bit ``instruction`` into IR; then go to ``end``."""
        self._shift("shift_ir", bytes((instruction,)), 8, False, end)

    def shift_dr(self, data, bits=None, *, read=False, end="idle"):
        """Shift ``bits`` (all of ``data``'s by default) of ``data`` into DR, LSB first; with
        ``read``, return what came out of TDO, packed the same way. ``end="shift_dr"`` stays
        in Shift-DR (the next shift continues it)."""
        return self._shift("shift_dr", bytes(data), 8 * len(data) if bits is None else bits,
                           read, end)

    def _shift(self, where, data, bits, read, end):
        head = self._go(where)
        body = bytearray(b"".join(_SHIFT[value] for value in data)[:2 * bits])
        tail = b""
        if end != where:
            # The last bit leaves with TMS high (to Exit1), then on to ``end``.
            body[-2] |= TMS
            body[-1] |= TMS
            self.state = _TAP[where][1]
            tail = self._go(end)
        samples = self.pins.clock(head + bytes(body) + tail)
        if not read:
            return None
        tdo = np.frombuffer(samples, np.uint8)[len(head) + 1:len(head) + 2 * bits:2] & TDO
        return np.packbits(tdo != 0, bitorder="little").tobytes()

    # --- the ECP5's instructions -----------------------------------------------------------

    def read(self, instruction, length):
        """``length`` bytes of the data register ``instruction`` selects."""
        # (Exit1-IR straight to Shift-DR, not through Run-Test/Idle, as openFPGALoader does.)
        self.shift_ir(instruction, end="exit1_ir")
        return self.shift_dr(bytes(length), read=True)

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


# --- the board --------------------------------------------------------------------------------

def connect(pins, *, idcode=None):
    """``(port, release)`` on a ULX3S's JTAG through the bit-bang port ``pins`` (``clock()``
    and ``close()``, :class:`FtdiBitbang`): its ECP5 checked (``idcode``: the one the
    bitstream is for; None: any ECP5), its configuration cleared, the flash opened to
    Shift-DR; ``port`` is the flash's :class:`BackgroundSPI`. ``release()`` sends
    LSC_REFRESH, closes ``pins`` and returns whether the ECP5 configured from the flash.
    One-line errors; a wrong FPGA is refused before anything on the board changes."""
    jtag = JTAG(pins)
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


class FtdiBitbang:
    """The FT231X's pins in synchronous bit-bang (a pyftdi ``Ftdi`` opened so): ``clock()``
    writes pin bytes and returns the pins sampled before each (FTDI AN232R-01: "the data bus
    pins are read first, before data from the USB RX FIFO is transmitted"), a chunk at a time;
    ``close()`` gives the FTDI back to its UART (and the kernel's serial driver)."""

    def __init__(self, ftdi, *, on_close=None):
        self.ftdi = ftdi
        self._on_close = on_close

    def clock(self, data):
        samples = bytearray()
        try:
            for start in range(0, len(data), CHUNK_BYTES):
                chunk = data[start:start + CHUNK_BYTES]
                self.ftdi.write_data(chunk)
                samples += self._read(len(chunk))
        except (OSError, ValueError) as error:     # (pyftdi's and pyusb's, a lost device)
            raise FlashingError(f"the link to the ULX3S's FTDI failed ({error}); the flash "
                                f"may be half written: run galvoscan flash again") from None
        return bytes(samples)

    def _read(self, size):
        got = bytearray()
        deadline = time.monotonic() + READ_TIMEOUT_S
        while len(got) < size:
            got += self.ftdi.read_data_bytes(size - len(got), attempt=4)
            if len(got) < size and time.monotonic() > deadline:
                raise FlashingError(f"the ULX3S's FTDI returned {len(got)} of {size} pin "
                                    f"samples in bit-bang: unplug the board, plug it in again "
                                    f"and retry")
        return got

    def close(self):
        try:
            self.ftdi.close()
        finally:
            if self._on_close:
                self._on_close()


def open_ulx3s(url=DEFAULT_URL, *, bitstream=None):
    """``(port, release)`` as :func:`galvoscan.flashing.open_icebreaker` gives them, for the
    ULX3S at ``url``: the flash's :class:`BackgroundSPI` through the ECP5, which must be the
    FPGA ``bitstream`` (if given) is for; ``release()`` lets the ECP5 configure from the flash,
    closes the FTDI and returns whether it configured. One-line errors."""
    idcode = check_bitstream(bitstream) if bitstream is not None else None
    return connect(_open_ftdi(url), idcode=idcode)


def _open_ftdi(url):
    restore = use_wheel_libusb()
    try:
        from pyftdi.ftdi import Ftdi, FtdiError
        from pyftdi.usbtools import UsbToolsError
    except ImportError as error:
        restore()
        raise FlashingError(_missing(error)) from None
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
