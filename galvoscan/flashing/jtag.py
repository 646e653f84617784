"""JTAG through an FTDI's synchronous bit-bang, with no MPSSE engine: an IEEE 1149.1 TAP
driven pin write by pin write (:class:`JTAG`) on the FT231X's pins (:class:`FtdiBitbang`); the
instructions are the part's (:mod:`.ecp5`'s for the ECP5).

The FT231X (0403:6015) is a UART: the JTAG hangs on its modem pins, which pyftdi drives in
synchronous bit-bang (as fujprog and openFPGALoader's ``ft231X`` cable do), two pin writes a TCK
period. Which pin is which is the ULX3S's wiring (:data:`TCK` and the others), the one board
here that has it; :mod:`.ulx3s` opens its FT231X so.
"""

import time

import numpy as np

from .errors import FlashingError


__all__ = ["JTAG", "FtdiBitbang", "TCK", "TMS", "TDI", "TDO", "BITBANG_HZ"]


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

    def read(self, instruction, length):
        """``length`` bytes of the data register ``instruction`` selects."""
        # (Exit1-IR straight to Shift-DR, not through Run-Test/Idle, as openFPGALoader does.)
        self.shift_ir(instruction, end="exit1_ir")
        return self.shift_dr(bytes(length), read=True)


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
