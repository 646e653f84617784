"""8N1 UART receiver and transmitter (the host link over the board's USB serial port)."""

from amaranth.hdl import Cat, Module, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.cdc import FFSynchronizer
from amaranth.lib.wiring import In, Out


__all__ = ["uart_divisor", "UARTReceiver", "UARTTransmitter"]


def uart_divisor(clk_freq, baud):
    """System clocks per UART bit, rounded; raises :exc:`ValueError` if the rounding error is
    over 2 % (a receiver at the other end would slip by a bit within one character) or the
    divisor is under 8 (too few clocks to find the middle of a bit)."""
    if not baud > 0:
        raise ValueError(f"baud rate must be positive, not {baud!r}")
    divisor = round(clk_freq / baud)
    if divisor < 8:
        raise ValueError(f"{baud:,.0f} baud needs at least 8 system clocks per bit; "
                         f"{clk_freq / 1e6:g} MHz gives {clk_freq / baud:.2f} (a clock of "
                         f"{8 * baud / 1e6:g} MHz or more, or a lower baud rate)")
    error = abs(clk_freq / divisor - baud) / baud
    if error > 0.02:
        raise ValueError(f"{baud:,.0f} baud from {clk_freq / 1e6:g} MHz is {error:.1%} off "
                         f"(divisor {divisor}); at most 2 % is allowed")
    return divisor


class UARTReceiver(wiring.Component):
    """8N1 receiver.

    The line is synchronised into the system clock domain. A start bit is confirmed half a bit
    after its falling edge, then each bit is sampled in its middle. A byte whose stop bit is low
    is dropped and reported on :attr:`framing_error`; the receiver then waits for the line to go
    idle (high) before looking for the next start bit.

    Parameters
    ----------
    divisor : int
        System clocks per bit (see :func:`uart_divisor`).

    Interface attributes
    --------------------
    rx : ``In(1)``
        The line, idle high. Asynchronous.
    bytes : ``Out(stream.Signature(8))``
        Received bytes. The receiver does not wait: a byte not taken before the next one
        arrives is replaced.
    framing_error : ``Out(1)``
        High for one clock when a byte is dropped for a low stop bit.
    """

    rx: In(1, init=1)
    bytes: Out(stream.Signature(8))
    framing_error: Out(1)

    def __init__(self, *, divisor):
        if not isinstance(divisor, int) or divisor < 8:
            raise ValueError(f"divisor must be an integer of at least 8, not {divisor!r}")
        self.divisor = divisor
        super().__init__()

    def elaborate(self, platform):
        m = Module()
        rx = Signal(init=1)
        m.submodules.rx_sync = FFSynchronizer(self.rx, rx, init=1)

        timer = Signal(range(self.divisor))
        bit = Signal(range(8))
        shift = Signal(8)

        with m.If(self.bytes.ready):
            m.d.sync += self.bytes.valid.eq(0)

        with m.FSM():
            with m.State("IDLE"):
                with m.If(~rx):
                    m.d.sync += timer.eq(self.divisor // 2 - 1)
                    m.next = "START"
            with m.State("START"):
                m.d.sync += timer.eq(timer - 1)
                with m.If(timer == 0):
                    with m.If(rx):      # a glitch, not a start bit
                        m.next = "IDLE"
                    with m.Else():
                        m.d.sync += [timer.eq(self.divisor - 1), bit.eq(0)]
                        m.next = "DATA"
            with m.State("DATA"):
                m.d.sync += timer.eq(timer - 1)
                with m.If(timer == 0):
                    # LSB first: each bit enters at the top and moves down.
                    m.d.sync += [shift.eq(Cat(shift[1:], rx)),
                                 timer.eq(self.divisor - 1), bit.eq(bit + 1)]
                    with m.If(bit == 7):
                        m.next = "STOP"
            with m.State("STOP"):
                m.d.sync += timer.eq(timer - 1)
                with m.If(timer == 0):
                    with m.If(rx):
                        m.d.sync += [self.bytes.payload.eq(shift), self.bytes.valid.eq(1)]
                        m.next = "IDLE"
                    with m.Else():
                        m.d.comb += self.framing_error.eq(1)
                        m.next = "BREAK"
            with m.State("BREAK"):
                with m.If(rx):
                    m.next = "IDLE"
        return m


class UARTTransmitter(wiring.Component):
    """8N1 transmitter.

    Parameters
    ----------
    divisor : int
        System clocks per bit.

    Interface attributes
    --------------------
    bytes : ``In(stream.Signature(8))``
        Bytes to send; taken when the previous one has gone out.
    tx : ``Out(1, init=1)``
        The line, idle high.
    """

    bytes: In(stream.Signature(8))
    tx: Out(1, init=1)

    def __init__(self, *, divisor):
        if not isinstance(divisor, int) or divisor < 2:
            raise ValueError(f"divisor must be an integer of at least 2, not {divisor!r}")
        self.divisor = divisor
        super().__init__()

    def elaborate(self, platform):
        m = Module()
        timer = Signal(range(self.divisor))
        # Start bit, 8 data bits LSB first, stop bit; shifted out LSB first.
        frame = Signal(10)
        bits_left = Signal(range(11))   # bits not yet started

        # Ready once the stop bit has lasted a whole bit time.
        m.d.comb += self.bytes.ready.eq((bits_left == 0) & (timer == 0))
        with m.If(self.bytes.valid & self.bytes.ready):
            m.d.sync += [frame.eq(Cat(0, self.bytes.payload, 1)), bits_left.eq(10)]
        with m.Elif(timer != 0):
            m.d.sync += timer.eq(timer - 1)
        with m.Elif(bits_left != 0):
            m.d.sync += [
                self.tx.eq(frame[0]),
                frame.eq(frame >> 1),
                bits_left.eq(bits_left - 1),
                timer.eq(self.divisor - 1),
            ]
        return m
