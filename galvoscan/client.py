"""Host client: read and write galvoscan registers by name, over UART or SPI.

The frames are those of :mod:`galvoscan.gateware.host.regmap`: four bytes, check byte 0x64, bit 7
of the address byte for a read. A transport moves frames; the client knows the register map::

    from galvoscan.client import HostClient, SerialTransport
    with SerialTransport("/dev/ttyUSB1") as link:
        board = HostClient(link)
        board.write("dwell", 5)
        print(board.read("status"))
"""

from .gateware.clocking import DEFAULT_BAUD
from .gateware.host.regmap import (BY_ADDRESS, BY_NAME, CHECK_BYTE, READ_FLAG, FrameError,
                                   decode_frame, encode_frame)


__all__ = ["ClientError", "HostClient", "SerialTransport", "FTDISPITransport",
           "encode_write", "encode_read", "parse_assignment"]


class ClientError(Exception):
    """A register name, value or answer the client cannot use."""


def _register(name):
    try:
        return BY_NAME[name]
    except KeyError:
        raise ClientError(f"no register named {name!r}; registers: {', '.join(BY_NAME)}")


def encode_write(name, value):
    """The frame that writes ``value`` to register ``name``; checked against the map."""
    reg = _register(name)
    if reg.access == "ro":
        raise ClientError(f"{name} is read-only")
    if isinstance(value, bool) or not isinstance(value, int) or not reg.low <= value <= reg.high:
        raise ClientError(f"{name} takes an integer from {reg.low} to {reg.high} ({reg.unit}), "
                          f"not {value!r}")
    return encode_frame(reg.address, reg.encode(value))


def encode_read(name):
    """The frame that asks for register ``name``."""
    return encode_frame(READ_FLAG | _register(name).address, 0)


def parse_assignment(text):
    """``NAME=VALUE`` (decimal, or 0x… hex) → ``(name, value)``."""
    name, sep, value = text.partition("=")
    if not sep or not name:
        raise ClientError(f"expected NAME=VALUE, not {text!r}")
    try:
        return name.strip(), int(value.strip(), 0)
    except ValueError:
        raise ClientError(f"{name}: {value!r} is not an integer")


class HostClient:
    """Registers by name over a transport (anything with ``write_frame`` and ``query``)."""

    def __init__(self, transport):
        self.transport = transport

    def write(self, name, value):
        self.transport.write_frame(encode_write(name, value))

    def read(self, name):
        reg = _register(name)
        answer = self.transport.query(encode_read(name))
        try:
            address, value = decode_frame(answer)
        except FrameError as error:
            raise ClientError(f"bad answer to a read of {name}: {answer.hex(' ')} ({error})")
        if address != reg.address:
            other = BY_ADDRESS.get(address)
            raise ClientError(f"asked for {name}, got an answer for "
                              f"{other.name if other else hex(address)}")
        return reg.decode(value)

    def write_verified(self, name, value):
        """Write, then read back; raise if the board did not take the value."""
        self.write(name, value)
        got = self.read(name)
        if got != value:
            raise ClientError(f"wrote {value} to {name}, reads back {got}")


class SerialTransport:
    """Frames over a serial port (the iCEBreaker's FTDI channel B), with pyserial.

    Parameters
    ----------
    port : str
        Serial device, e.g. ``/dev/ttyUSB1`` or ``COM4``.
    baud : int
        Must match the bitstream (1 Mbaud by default).
    timeout : float
        Seconds to wait for an answer.
    """

    def __init__(self, port, *, baud=DEFAULT_BAUD, timeout=0.5):
        import serial   # pyserial
        self._serial = serial.Serial(port, baudrate=baud, timeout=timeout)
        try:
            # An FTDI chip holds received bytes up to 16 ms before sending them on; in
            # low-latency mode 1 ms. Every read of a register waits for that round trip.
            self._serial.set_low_latency_mode(True)
        except (AttributeError, NotImplementedError, ValueError, OSError):
            pass            # not Linux, or not a device that has it (a pty)

    def write_frame(self, frame):
        self._serial.write(frame)
        self._serial.flush()

    def query(self, frame):
        self._serial.reset_input_buffer()
        self.write_frame(frame)
        answer = self._serial.read(4)
        if not answer:
            raise ClientError(f"no answer from the board within {self._serial.timeout} s: "
                              f"check the port and the baud rate, or give a slow board (a "
                              f"simulated one: the --timeout it printed) a longer --timeout")
        if len(answer) != 4:
            raise ClientError(f"only {len(answer)} of an answer's 4 bytes within "
                              f"{self._serial.timeout} s: the board answers slower than "
                              f"--timeout allows (a simulated one: give the --timeout it "
                              f"printed), or the baud rate is not the bitstream's")
        return answer

    def close(self):
        self._serial.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class FTDISPITransport:
    """Frames over SPI from an FTDI MPSSE adapter (FT2232H, FT232H), with pyftdi.

    The answer to a read comes out during the next frame, so a read is the request followed by
    a read of ``errors`` (which changes nothing) to clock the answer out.

    Parameters
    ----------
    url : str
        pyftdi device URL, e.g. ``ftdi://ftdi:2232h/1``.
    frequency : float
        SCK in Hz; at most the board's system clock / 12 (1 MHz on the iCEBreaker).
    """

    FETCH = bytes([READ_FLAG | BY_NAME["errors"].address, 0, 0, CHECK_BYTE])

    def __init__(self, url, *, frequency=1e6):
        try:
            from pyftdi.spi import SpiController
        except ImportError:
            raise ClientError("SPI over FTDI needs pyftdi: pip install pyftdi")
        self._controller = SpiController()
        self._controller.configure(url)
        self._port = self._controller.get_port(cs=0, freq=frequency, mode=0)

    def _transfer(self, frame):
        return bytes(self._port.exchange(frame, duplex=True))

    def write_frame(self, frame):
        self._transfer(frame)

    def query(self, frame):
        self._transfer(frame)
        return self._transfer(self.FETCH)

    def close(self):
        self._controller.terminate()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
