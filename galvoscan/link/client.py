"""Host client: read and write galvoscan registers by name, over UART or SPI, every frame
checked and every write acknowledged.

The frames are those of :mod:`galvoscan.gateware.host.frames`: a command frame of ten bytes
with a sequence number and a CRC-16, an answer of six for every frame. A transport moves
frames and answers; the client knows the register map and the sequence::

    from galvoscan.link.client import HostClient, SerialTransport
    with SerialTransport("/dev/ttyUSB1") as link:
        board = HostClient(link)
        board.write("dwell", 5)          # answered with what dwell now holds
        print(board.read("status"))

What the client guarantees: a write is done only as the board's answer says (its value read
back, in order, none skipped: the board refuses a write out of sequence); a read is taken only
from an answer whose CRC holds, whose tag is the request's and whose address is the
register's, and is asked again otherwise (a read changes nothing); a lost answer to a write is
found out from ``link_seq`` (how many writes the board took), and only the writes it did not
take are sent again.
"""

import binascii
import time

# COBS (Consistent Overhead Byte Stuffing) frames each UART packet between zero bytes, so
# that a receiver finds the next frame after a lost or extra byte; the maintained package
# (C, with a pure-Python fallback) rather than an encoder of our own.
from cobs import cobs
import serial

from ..gateware.clocking import DEFAULT_BAUD
from ..gateware.host.frames import ANSWER_BYTES, COMMAND_BYTES, CRC_INIT, REFUSED
from ..gateware.host.regmap import BY_ADDRESS, BY_NAME, READ_FLAG


__all__ = ["ClientError", "LinkLost", "WriteRefused", "HostClient", "SerialTransport",
           "FTDISPITransport", "HostClock", "PacketTransport", "ClockedTransport", "encode_command",
           "encode_write", "encode_read", "decode_answer", "Answer", "parse_assignment",
           "REASONS", "frame_seconds"]


#: Bytes a command frame takes on the serial line: its own, COBS's code byte (a frame of
#: COMMAND_BYTES has no zero run longer than 254) and the zero that ends it; bits a byte (8N1).
_LINE_BYTES, _BITS_PER_BYTE = COMMAND_BYTES + 2, 10


def frame_seconds(baud):
    """Seconds a command frame (a register write, or a vector segment: its end point and
    its operation together) takes on the UART at ``baud``."""
    return _LINE_BYTES * _BITS_PER_BYTE / baud


#: Reasons for a refusal, by the number an answer carries.
REASONS = {number: name for name, number in REFUSED.items()}
_SEGMENT_ADDRESS = BY_NAME["vec_op"].address
#: Write frames sent before their answers are checked: fewer than the 256 sequence numbers, so
#: that ``link_seq`` tells unambiguously how many of a batch the board took.
BATCH_FRAMES = 128


class ClientError(Exception):
    """A register name, value or answer the client cannot use."""


class LinkLost(ClientError):
    """No good answer came from the board, after the tries allowed: the link is cut, or so
    damaged that nothing gets through."""


class WriteRefused(ClientError):
    """The board refused a write (:attr:`reason`: ``"register"``, ``"check"``,
    ``"sequence"`` …); :attr:`taken` writes of the call were done before it."""

    def __init__(self, message, *, reason, taken):
        super().__init__(message)
        self.reason = reason
        self.taken = taken


def _register(name):
    try:
        return BY_NAME[name]
    except KeyError:
        raise ClientError(f"no register named {name!r}; registers: {', '.join(BY_NAME)}")


def _crc(data):
    # CRC-16/CCITT with 0xFFFF: binascii's, a separate implementation from the gateware's.
    return binascii.crc_hqx(data, CRC_INIT)


def encode_command(seq, address, data=0, x=0, y=0):
    """The ten bytes of a command frame (:mod:`~galvoscan.gateware.host.frames`)."""
    for name, value, top in (("seq", seq, 0xFF), ("address", address, 0xFF),
                             ("data", data, 0xFFFF), ("x", x, 0xFFFF), ("y", y, 0xFFFF)):
        if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= top:
            raise ClientError(f"{name} {value!r} does not fit a frame")
    body = bytes([seq, address]) + data.to_bytes(2, "big") + x.to_bytes(2, "big") + \
        y.to_bytes(2, "big")
    return body + _crc(body).to_bytes(2, "big")


def _checked_value(name, value):
    reg = _register(name)
    if reg.access == "ro":
        raise ClientError(f"{name} is read-only")
    if isinstance(value, bool) or not isinstance(value, int) or not reg.low <= value <= reg.high:
        raise ClientError(f"{name} takes an integer from {reg.low} to {reg.high} ({reg.unit}), "
                          f"not {value!r}")
    return reg


def encode_write(name, value, *, seq=0):
    """The frame that writes ``value`` to register ``name``; checked against the map."""
    reg = _checked_value(name, value)
    return encode_command(seq, reg.address, reg.encode(value))


def encode_read(name, *, tag=0):
    """The frame that asks for register ``name``."""
    return encode_command(tag, READ_FLAG | _register(name).address)


class Answer:
    """An answer whose CRC held: ``tag``, ``code`` (an address, or ``0x80 | reason``) and
    ``data``."""

    __slots__ = ("tag", "code", "data")

    def __init__(self, tag, code, data):
        self.tag, self.code, self.data = tag, code, data

    @property
    def refused(self):
        return bool(self.code & 0x80)

    @property
    def reason(self):
        return REASONS.get(self.code & 0x7F, f"reason {self.code & 0x7F}")

    def __repr__(self):
        return f"Answer(tag={self.tag}, code={self.code:#04x}, data={self.data})"


def decode_answer(packet):
    """The :class:`Answer` of six bytes, or None if they are not one (wrong length, CRC)."""
    if packet is None or len(packet) != ANSWER_BYTES or _crc(packet) != 0:
        return None
    return Answer(packet[0], packet[1], int.from_bytes(packet[2:4], "big"))


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
    """Registers by name over a transport (anything with ``transact``: frames in, one answer
    packet or None for each out, in order).

    Parameters
    ----------
    transport
    tries : int
        Times a read, or a write whose answer was lost, is tried before :exc:`LinkLost`.
    """

    def __init__(self, transport, *, tries=3):
        self.transport = transport
        self.tries = tries
        self._seq = None             # the seq the board expects (None: ask it)
        self._tag = 0
        #: Frames sent, answers that failed their check, and tries made again (for reports).
        self.sent = 0
        self.bad_answers = 0
        self.retries = 0

    def now(self):
        """Seconds on the link's clock: the transport's (a simulated board's own time), else
        the host's."""
        now = getattr(self.transport, "now", None)
        return now() if now is not None else time.monotonic()

    def sleep(self, seconds):
        """Let ``seconds`` pass on the link's clock (a simulated board runs for them)."""
        sleep = getattr(self.transport, "sleep", None)
        if sleep is not None:
            sleep(seconds)
        else:
            time.sleep(seconds)

    def _transact(self, frames):
        self.sent += len(frames)
        packets = list(self.transport.transact(frames))
        packets += [None] * (len(frames) - len(packets))
        answers = [decode_answer(packet) for packet in packets[:len(frames)]]
        self.bad_answers += sum(answer is None for answer in answers)
        return answers

    def _flush(self):
        flush = getattr(self.transport, "flush", None)
        if flush is not None:
            flush()

    # --- reads ---------------------------------------------------------------------------------

    def read(self, name):
        reg = _register(name)
        return reg.decode(self._read_address(reg.address, name))

    def _read_address(self, address, name):
        heard = False
        for attempt in range(self.tries):
            self._tag = (self._tag + 1) & 0xFF
            tag = self._tag
            [answer] = self._transact([encode_command(tag, READ_FLAG | address)])
            heard = heard or getattr(self.transport, "heard", True)
            if answer is not None and answer.tag == tag and answer.code == address:
                return answer.data
            if answer is not None and answer.tag == tag and answer.refused and \
                    answer.reason == "register":
                raise ClientError(f"the board has no register {name} (its bitstream was built "
                                  f"without it)")
            if attempt + 1 < self.tries:
                self.retries += 1
                self._flush()
        raise LinkLost(self._lost(f"a read of {name}", heard))

    def _lost(self, what, heard):
        """Why no good answer came: nothing at all, or bytes that are no answer."""
        timeout = getattr(self.transport, "timeout", None)
        if not heard:
            return (f"no answer from the board within {timeout:g} s ({what}, {self.tries} "
                    f"tries): check the port and the baud rate, or give a slow board (a "
                    f"simulated one: the --timeout it printed) a longer --timeout")
        return (f"no good answer to {what} in {self.tries} tries, only answers that do not "
                f"check: the baud rate is not the bitstream's, or the link is damaged")

    def sequence(self):
        """The seq the board expects next (``link_seq``), read from the board."""
        self._seq = self._read_address(BY_NAME["link_seq"].address, "link_seq")
        return self._seq

    # --- writes --------------------------------------------------------------------------------

    def write(self, name, value):
        self.write_many([(name, value)])

    def write_verified(self, name, value):
        """Write, then read back; raise if the board does not hold the value."""
        self.write(name, value)
        got = self.read(name)
        if got != value:
            raise ClientError(f"wrote {value} to {name}, reads back {got}")

    def write_many(self, items):
        """Write ``[(name, value)]`` in order, each checked against the map first and each
        acknowledged with what its register then holds."""
        writes = []
        for name, value in items:
            reg = _checked_value(name, value)
            if reg.address == _SEGMENT_ADDRESS:
                raise ClientError("vec_op queues a segment: use queue_segments")
            writes.append((reg, reg.encode(value), 0, 0))
        self._write_all(writes)

    def queue_segments(self, segments):
        """Queue ``[(op_word, x, y)]`` (``vec_op``'s value and the end point), a checked frame
        each; returns the queue's free places after the last."""
        reg = BY_NAME["vec_op"]
        writes = []
        for op, x, y in segments:
            _checked_value("vec_op", op)
            writes.append((reg, op, x, y))
        free = self._write_all(writes)
        # (The last answer lost, and the segment found taken by link_seq: ask the queue.)
        return self.read("fifo_free") if free is None else free

    def _write_all(self, writes):
        """Send the writes, then check each answer; a write whose answer was lost is found
        out from ``link_seq`` and only those the board did not take are sent again. Returns
        the last answer's data, or None where it was lost."""
        done = 0
        last = None
        tries = 0
        while done < len(writes):
            if self._seq is None:
                self.sequence()
            start = self._seq
            # At most half the sequence numbers a batch: how many the board took is then
            # read unambiguously from link_seq, which counts modulo 256 (a batch of 300 whose
            # answers were lost would read as 44 taken, and the rest sent again, taken twice).
            batch = writes[done:done + BATCH_FRAMES]
            frames = [encode_command((start + i) & 0xFF, reg.address, data, x, y)
                      for i, (reg, data, x, y) in enumerate(batch)]
            answers = self._transact(frames)
            for i, ((reg, data, x, y), answer) in enumerate(zip(batch, answers)):
                seq = (start + i) & 0xFF
                if answer is None or answer.tag != seq:
                    break               # lost: ask the board how far it got
                if answer.refused:
                    self._seq = answer.data & 0xFF
                    if answer.reason in ("register",):
                        raise WriteRefused(
                            f"the board refused {reg.name} = {reg.decode(data)} "
                            f"({_refusal_words(reg)})", reason=answer.reason, taken=done + i)
                    break               # a damaged or out-of-step frame: send it again
                if answer.code != reg.address:
                    break
                if reg.access == "rw" and answer.data != data:
                    raise WriteRefused(f"wrote {reg.decode(data)} to {reg.name}, the board holds "
                                       f"{reg.decode(answer.data)}", reason="mismatch",
                                       taken=done + i + 1)
                last = answer.data
                self._seq = (seq + 1) & 0xFF
            else:
                done += len(batch)
                continue
            # Something went wrong: how many did the board take?
            self._flush()
            taken = (self.sequence() - start) & 0xFF
            if taken > len(batch):
                raise ClientError(f"the board took {taken} writes of {len(batch)} sent: another "
                                  f"host is writing to it")
            done += taken
            last = None             # (its answer may be the one lost: the caller asks again)
            tries += 1
            if tries >= self.tries:
                raise WriteRefused(
                    f"{len(writes) - done} of {len(writes)} writes not taken after {tries} "
                    f"tries: the link is damaged", reason="check", taken=done)
            # (link_seq read back above: the board answers, so the link is not cut.)
            self.retries += 1
        return last


def _refusal_words(reg):
    if reg.address == _SEGMENT_ADDRESS:
        return "its vector queue is full"
    return "its bitstream may not have that register or range"


class HostClock:
    """A link's clock: the host's. A simulated board's transports give the board's own time
    instead, so that every wait on them counts what the board did."""

    def now(self):
        """The link's clock, in seconds."""
        return time.monotonic()

    def sleep(self, seconds):
        """Let ``seconds`` pass on the link's clock."""
        time.sleep(seconds)


class PacketTransport(HostClock):
    """What a UART link does with frames: each COBS-encoded with a zero byte after it, sent
    back to back; each answer comes back as its six bytes. A subclass gives ``_write(bytes)``
    and ``_read(seconds)`` (the bytes that came, up to the time given)."""

    timeout = 0.5
    #: Whether any byte came back in the last :meth:`transact` (for the client's message).
    heard = True
    #: How long the line must be quiet before a :meth:`flush` drops what came.
    quiet_s = 0.02

    def transact(self, frames):
        self._write(b"".join(cobs.encode(frame) + b"\0" for frame in frames))
        return self._answers(len(frames))

    def _answers(self, count):
        """Up to ``count`` answers (six bytes each), as they come within the timeout."""
        want = count * ANSWER_BYTES
        buffer = b""
        self.heard = False
        deadline = self.now() + self.timeout
        while len(buffer) < want and self.now() <= deadline:
            more = self._read(max(0.0, deadline - self.now()))
            self.heard = self.heard or bool(more)
            buffer += more
        return [buffer[i:i + ANSWER_BYTES] for i in range(0, len(buffer), ANSWER_BYTES)]

    def flush(self):
        """Start afresh: a zero byte ends whatever the board was gathering, and whatever comes
        back until the line has been quiet a while is dropped (so the next answer read is the
        next one asked for, whole)."""
        self._write(b"\0")
        while self._read(self.quiet_s):
            pass


class ClockedTransport(HostClock):
    """What an SPI link does with frames: each one clocked in whole; its answer comes out
    during the next, so a last read of ``link_seq`` (which changes nothing) clocks out the
    last answer. A subclass gives ``transfer(bytes) -> bytes``: the bytes clocked out while
    those were clocked in."""

    FETCH = encode_command(0xFF, READ_FLAG | BY_NAME["link_seq"].address)

    def transact(self, frames):
        returned = [self.transfer(frame) for frame in [*frames, self.FETCH]]
        return [data[:ANSWER_BYTES] for data in returned[1:]]


class SerialTransport(PacketTransport):
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
        self._serial = serial.Serial(port, baudrate=baud, timeout=timeout)
        self.timeout = timeout
        try:
            # An FTDI chip holds received bytes up to 16 ms before sending them on; in
            # low-latency mode 1 ms. Every read of a register waits for that round trip.
            self._serial.set_low_latency_mode(True)
        except (AttributeError, NotImplementedError, ValueError, OSError):
            pass            # not Linux, or not a device that has it (a pty)
        self._serial.reset_input_buffer()
        self.flush()

    def _write(self, data):
        self._serial.write(data)
        self._serial.flush()

    def _read(self, seconds):
        self._serial.timeout = min(seconds, self.timeout)
        first = self._serial.read(1)
        return first + self._serial.read(self._serial.in_waiting) if first else b""

    def close(self):
        self._serial.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class FTDISPITransport(ClockedTransport):
    """Frames over SPI from an FTDI MPSSE adapter (FT2232H, FT232H), with pyftdi.

    Parameters
    ----------
    url : str
        pyftdi device URL, e.g. ``ftdi://ftdi:2232h/1``.
    frequency : float
        SCK in Hz; at most the board's system clock / 12 (1 MHz on the iCEBreaker).
    """

    def __init__(self, url, *, frequency=1e6):
        # Here: pyftdi loads libusb, for SPI over an FTDI adapter only (not the UART or the
        # simulator).
        try:
            from pyftdi.spi import SpiController
        except ImportError:
            raise ClientError("SPI over FTDI needs pyftdi: pip install pyftdi")
        self._controller = SpiController()
        self._controller.configure(url)
        self._port = self._controller.get_port(cs=0, freq=frequency, mode=0)

    def transfer(self, frame):
        return bytes(self._port.exchange(frame, duplex=True))

    def close(self):
        self._controller.terminate()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
