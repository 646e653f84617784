"""The job player writes nothing, and arms nothing, before its check has passed (galvoscan's
stand-alone rules, README "Stand-alone marking")."""

from amaranth.asserts import AnySeq
from amaranth.hdl import (Assert, Cat, ClockDomain, Const, Cover, Elaboratable, Module, Mux,
                          ResetSignal, Signal)

from ..gateware.fields import PlayerState
from ..gateware.player.image_format import FORMAT_VERSION, HEADER_BYTES, HEADER_WORDS, MAGIC


__all__ = ["PlayerSpec", "CRC_POLYNOMIAL", "valid_image"]


#: CRC-32's reflected polynomial (IEEE 802.3).
CRC_POLYNOMIAL = 0xEDB88320


def crc_byte(crc, byte):
    """CRC-32's register after ``byte``, LSB first (the textbook definition)."""
    for k in range(8):
        crc = (crc >> 1) ^ Mux(crc[0] ^ byte[k], CRC_POLYNOMIAL, 0)
    return crc


def valid_image(*, segments=((20000, 30000, 0),), tamper=None):
    """A job image of ``segments`` (vec_x, vec_y, vec_op), no settings, one repeat, with its
    CRC made right (after ``tamper(bytearray)``, if given, changes it)."""
    import zlib
    from ..gateware.player.image_format import CRC_BYTES
    words = [int.from_bytes(MAGIC[:2], "little"), int.from_bytes(MAGIC[2:], "little"),
             FORMAT_VERSION, 0, 0, 0, 0, 1, 0]
    for segment in segments:
        words += list(segment)
    words[3], words[4] = (2 * len(words)) & 0xFFFF, (2 * len(words)) >> 16
    image = bytearray(b"".join(word.to_bytes(2, "little") for word in words))
    if tamper is not None:
        tamper(image)
    image[CRC_BYTES.start:CRC_BYTES.stop] = bytes(4)
    image[CRC_BYTES.start:CRC_BYTES.stop] = zlib.crc32(image).to_bytes(4, "little")
    return bytes(image)


class PlayerSpec(Elaboratable):
    """The job player's check, for every input sequence and every reset.

    Every input is free on every clock: the flash's bytes (any value, any timing), the
    reader's idle flag, the arbiter's grants, the register file's answers, the start input,
    the queue, the sequencer and the laser. The spec watches the bytes the player takes from
    the reader after its last read start, and keeps its own CRC-32 of them (the four bytes of
    the CRC field read as zero). Proved:

    * **no write before the check**: the player writes a register (``arm`` among them) only
      if, since the start it took, it has taken a whole image from the image's offset: the
      magic ``GSJB``, the format version, a length of at least the header, as many bytes as
      the length says, and a CRC-32 of them equal to the image's CRC field.

    Parameters
    ----------
    player : a :class:`~galvoscan.gateware.player.player.JobPlayer` (or a broken one)
    helpers : bool
        State the helper invariants, which tie the player's count of words, its length, its
        CRC and its expected CRC to the spec's (so that a short induction covers any image).
        The broken players' checks leave them out.
    image : bytes, optional
        A restriction of the free inputs, for the covers and the broken players' bounded
        checks (a trace found in it is one of the free harness too): the flash gives these
        bytes from each read start on, at once, the reset is never asserted, every write is
        granted and taken, the start input held, the laser ready and the queue free; the
        solver then searches no CRC. What the assertion and the covers watch is then also
        latched (a flag each that stays set), so that a search of the last clock alone finds
        what any clock before it reached: each clock searched is a query over the whole
        unrolled image, some 7 s, and the eleven clocks the covers were searched over took
        90 s.
    """

    def __init__(self, player, *, helpers=True, image=None):
        self.player = player
        self.helpers = helpers
        self.image = image

    def elaborate(self, platform):
        m = Module()
        m.domains.sync = ClockDomain()
        m.submodules.dut = dut = self.player
        if self.image is None:
            m.d.comb += ResetSignal("sync").eq(AnySeq(1))
            for port in (dut.read_data.valid, dut.read_data.payload, dut.read_idle, dut.grant,
                         dut.bus.write_ok, dut.bus.read_ok, dut.bus.read_data, dut.start,
                         dut.queue_ready, dut.queue_empty, dut.vector_busy, dut.laser_ready,
                         dut.fault, dut.host_took_over):
                m.d.comb += port.eq(AnySeq(len(port)))

        # --- the bytes the player takes, from its last read start on --------------------------
        inner = getattr(dut, "inner", dut)          # (a broken player wraps the real one)
        limit = inner.max_image_bytes + 2
        count = Signal(range(limit + 1))
        from_offset = Signal()
        crc = Signal(32, init=0xFFFFFFFF)
        header = Signal(8 * 14)         # magic, version, length, CRC field
        last_two = Signal(16)           # the last two bytes taken, the last one high
        taken = dut.read_data.valid & dut.read_data.ready
        byte = dut.read_data.payload
        with m.If(taken):
            m.d.sync += last_two.eq(Cat(last_two[8:], byte))
        with m.If(dut.read_start):
            m.d.sync += [count.eq(0), crc.eq(0xFFFFFFFF), header.eq(0),
                         from_offset.eq(dut.read_address == inner.offset)]
        with m.Elif(taken):
            m.d.sync += count.eq(Mux(count == limit, limit, count + 1))
            in_field = (count >= 10) & (count < 14)
            m.d.sync += crc.eq(crc_byte(crc, Mux(in_field, 0, byte)))
            with m.Switch(count):
                for k in range(14):
                    with m.Case(k):
                        m.d.sync += header[8 * k:8 * k + 8].eq(byte)
        if self.image is not None:
            payload = Signal(8)
            with m.Switch(count):
                for k, value in enumerate(self.image):
                    with m.Case(k):
                        m.d.comb += payload.eq(value)
            m.d.comb += [dut.read_data.valid.eq(1), dut.read_data.payload.eq(payload),
                         dut.read_idle.eq(1), dut.grant.eq(1), dut.bus.write_ok.eq(1),
                         dut.start.eq(1), dut.queue_ready.eq(1), dut.queue_empty.eq(1),
                         dut.laser_ready.eq(1)]
        magic, version = header[0:32], header[32:48]
        length, field = header[48:80], header[80:112]
        whole = from_offset & (magic == int.from_bytes(MAGIC, "little")) & \
            (version == FORMAT_VERSION) & (length >= HEADER_BYTES) & (count == length) & \
            (~crc == field)
        passed = Signal()
        with m.If(dut.start & (dut.state == PlayerState.IDLE)):
            m.d.sync += passed.eq(0)
        with m.Elif(whole):
            m.d.sync += passed.eq(1)

        early = dut.bus.write_en & ~passed
        # A whole image checked; the first write after it (``run`` 0, then ``mode``: the
        # arming comes as many words later again, past the covers' depth).
        checked, wrote = whole, passed & dut.bus.write_en
        if self.image is not None:
            # Latched: once seen, seen on every later clock (no reset comes in this mode).
            seen = Signal(3)
            m.d.sync += seen.eq(seen | Cat(early, checked, wrote))
            early, checked, wrote = early | seen[0], checked | seen[1], wrote | seen[2]
        m.d.comb += Assert(~early,
                           "no register written before a whole image passed the check")
        m.d.comb += [Cover(checked), Cover(wrote)]

        if self.helpers:
            # The header's bytes are the last ones taken, as they came.
            for k in range(14):
                m.d.comb += [
                    Assert(~inner._parsing | (count != k + 1) |
                           (header[8 * k:8 * k + 8] == last_two[8:])),
                    Assert(~inner._parsing | (count != k + 2) |
                           (header[8 * k:8 * k + 8] == last_two[:8])),
                ]
            self._helpers(m, inner, count, from_offset, crc, magic, version, length, field,
                          passed, last_two)
        return m

    @staticmethod
    def _helpers(m, dut, count, from_offset, crc, magic, version, length, field, passed,
                 last_two):
        position = dut._position
        parsing = dut._parsing
        m.d.comb += [
            Assert(~dut._live | passed),
            Assert(dut._live | ~dut._writing),
            Assert(dut._live | ~dut._playing),
            Assert(dut._live | ~dut.armed),
            Assert(dut._live | ~(dut._reading | parsing) | ~dut._repeating),
            Assert(~parsing | from_offset),
            # The word being put together is the bytes taken.
            Assert(~parsing | ~dut._byte_high | (dut._word[:8] == last_two[8:])),
            Assert(~parsing | ~dut._word_valid | (dut._word == last_two)),
            # A read of the check starts from the image's first word, the CRC cleared.
            Assert(~dut._reading | dut._live |
                   ((position == 0) & ~dut._word_valid & ~dut._byte_high &
                    (dut._section.as_value() == 0) & ~dut._crc.busy &
                    (dut._crc._state == 0xFFFFFFFF))),
            Assert(~parsing | ((position < HEADER_WORDS) == (dut._section.as_value() == 0))),
            Assert(~parsing | dut._took |
                   (dut._ended == ((dut._section.as_value() != 0) & (position == dut._length)))),
            Assert(~parsing | (count == dut._byte_high +
                               2 * (position + dut._word_valid))),
            Assert(~parsing | (position <= 0) |
                   (magic[:16] == int.from_bytes(MAGIC[:2], "little"))),
            Assert(~parsing | (position <= 1) | (magic == int.from_bytes(MAGIC, "little"))),
            Assert(~parsing | (position <= 3) |
                   (length[:16] == Cat(Const(0, 1), dut._length[:15]))),
            Assert(~parsing | (position <= 2) | (version == FORMAT_VERSION)),
            Assert(~parsing | (position <= 4) | (length == 2 * dut._length)),
            Assert(~parsing | (position <= 4) | (dut._length >= HEADER_BYTES // 2)),
            Assert(~parsing | (position <= 4) |
                   ((position <= dut._length) & (dut._length <= dut.max_image_bytes // 2))),
            Assert(~parsing | (position <= 5) | (dut._expected_crc[:16] == field[:16])),
            Assert(~parsing | (position <= 6) | (dut._expected_crc == field)),
            Assert(~parsing | dut._crc.busy | (dut._crc._state == crc)),
        ]
