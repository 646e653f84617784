"""A reader for the board's SPI configuration flash, used after configuration (a W25Q128-class
part, as on the iCEBreaker).

It wakes the flash from deep power-down (0xAB, then tRES1), then reads from a byte address
with the plain Read Data command (0x03: no dummy clocks, up to 50 MHz) for as long as bytes are
taken. SPI mode 0; SCK is half the system clock, and stops (low) while a byte waits to be
taken, which a flash allows at any time during a read.
"""

from amaranth.hdl import Cat, Module, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out


__all__ = ["SPIFlashReader", "RELEASE_POWER_DOWN", "READ_DATA", "RELEASE_US"]


#: Release from deep power-down (W25Q128JV datasheet, 8.2.19): 8 bits, then tRES1.
RELEASE_POWER_DOWN = 0xAB
#: Read Data (8.2.6): the command, a 24-bit address, then bytes for as long as SCK runs.
READ_DATA = 0x03
#: tRES1, µs: /CS high to the next command after a release from power-down (3 µs max).
RELEASE_US = 3


class SPIFlashReader(wiring.Component):
    """Reads a SPI flash from a byte address, as a stream of bytes.

    A pulse on :attr:`start` (while :attr:`idle`) begins a read at :attr:`address`: the flash
    is sent the release from deep power-down (it answers nothing while powered down, and a
    flash already awake ignores it), /CS rises for tRES1, then the read command and the
    address go out and bytes come on :attr:`data`, in order, for as long as they are taken.
    :attr:`stop` ends the read (/CS high) at any time. Each read wakes the flash again, so a
    flash powered down by anything else since still reads.

    Parameters
    ----------
    clk_freq : int or float
        The system clock, Hz (for tRES1). SCK is half of it: 6 MHz on a 12 MHz board.

    Interface attributes
    --------------------
    cs_n, sck, copi : ``Out(1)``; cipo : ``In(1)``
        The flash's pins (/CS idles high, SCK low). CIPO is sampled as SCK rises, half an SCK
        period after the flash set it on the falling edge (within a system clock).
    address : ``In(24)``
        The first byte's address: held from :attr:`start` until the first byte comes (it
        goes out after tRES1, a byte at a time).
    start : ``In(1)``
        Begin a read (ignored unless :attr:`idle`).
    stop : ``In(1)``
        End the read, or the wake-up, now; a byte waiting on :attr:`data` is dropped.
    data : ``Out(stream.Signature(8))``
        The bytes read, from ``address`` on.
    idle : ``Out(1)``
        No read under way (/CS high, nothing waiting).
    """

    cs_n: Out(1, init=1)
    sck: Out(1)
    copi: Out(1)
    cipo: In(1)
    address: In(24)
    start: In(1)
    stop: In(1)
    data: Out(stream.Signature(8))
    idle: Out(1)

    def __init__(self, *, clk_freq):
        if not clk_freq > 0:
            raise ValueError(f"clk_freq must be a positive frequency in Hz, not {clk_freq!r}")
        self.clk_freq = clk_freq
        #: Clocks /CS stays high after the release: tRES1, plus one for the rounding.
        self.release_clocks = int(clk_freq * RELEASE_US / 1e6) + 1
        super().__init__()

    def elaborate(self, platform):
        m = Module()
        # What goes out, a byte at a time, MSB first: the release, then (after tRES1) the read
        # command and the address's three bytes, taken from `address` as each is sent.
        shift_out = Signal(8)
        shift_in = Signal(8)
        bits = Signal(range(9))             # bits left to send, or to receive in a byte
        command_byte = Signal(range(4))     # of the read command's bytes, the one going out
        wait = Signal(range(self.release_clocks + 1))
        m.d.comb += self.copi.eq(shift_out[7])
        next_byte = Signal(8)
        with m.Switch(command_byte):
            for index, part in enumerate((self.address[16:24], self.address[8:16],
                                          self.address[0:8])):
                with m.Case(index):
                    m.d.comb += next_byte.eq(part)

        with m.FSM():
            with m.State("IDLE"):
                m.d.comb += self.idle.eq(1)
                m.d.sync += [self.cs_n.eq(1), self.sck.eq(0)]
                with m.If(self.start & ~self.stop):
                    m.d.sync += [self.cs_n.eq(0), shift_out.eq(RELEASE_POWER_DOWN), bits.eq(8)]
                    m.next = "RELEASE"
            with m.State("RELEASE"):
                with m.If(self._send(m, shift_out, bits)):
                    m.d.sync += wait.eq(self.release_clocks)
                    m.next = "WAKE"
                self._stoppable(m)
            with m.State("WAKE"):
                # /CS high for tRES1, then the read command.
                m.d.sync += [self.cs_n.eq(1), wait.eq(wait - 1)]
                with m.If(wait == 0):
                    m.d.sync += [self.cs_n.eq(0), shift_out.eq(READ_DATA), bits.eq(8),
                                 command_byte.eq(0)]
                    m.next = "COMMAND"
                self._stoppable(m)
            with m.State("COMMAND"):
                # The command, then the address, high byte first.
                with m.If(self._send(m, shift_out, bits)):
                    m.d.sync += [shift_out.eq(next_byte), bits.eq(8),
                                 command_byte.eq(command_byte + 1)]
                    with m.If(command_byte == 3):
                        m.next = "READ"
                self._stoppable(m)
            with m.State("READ"):
                # A byte in eight SCK periods; SCK waits low while the last byte is untaken.
                with m.If(self.data.valid & self.data.ready):
                    m.d.sync += self.data.valid.eq(0)
                with m.If(self.sck):
                    m.d.sync += self.sck.eq(0)
                    with m.If(bits == 0):
                        m.d.sync += [self.data.payload.eq(shift_in), self.data.valid.eq(1),
                                     bits.eq(8)]
                with m.Elif(~self.data.valid | self.data.ready):
                    # SCK rises: the flash's bit, set on the last falling edge, is taken now.
                    m.d.sync += [self.sck.eq(1), shift_in.eq(Cat(self.cipo, shift_in[:7])),
                                 bits.eq(bits - 1)]
                self._stoppable(m)
        return m

    def _stoppable(self, m):
        """In a state of a read under way: :attr:`stop` ends it, whatever else the state
        does on this clock."""
        with m.If(self.stop):
            m.d.sync += [self.cs_n.eq(1), self.sck.eq(0), self.data.valid.eq(0)]
            m.next = "IDLE"

    def _send(self, m, shift_out, bits):
        """Clock the byte in ``shift_out`` out, MSB first: COPI is set while SCK is low and
        taken by the flash as SCK rises. True on the clock it is all out (SCK low again)."""
        done = Signal()
        with m.If(bits == 0):
            m.d.comb += done.eq(1)
        with m.Elif(~self.sck):
            m.d.sync += self.sck.eq(1)
        with m.Else():
            m.d.sync += [self.sck.eq(0), shift_out.eq(shift_out << 1), bits.eq(bits - 1)]
        return done
