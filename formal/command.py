"""The command path from both links to a register write, as properties: checked frames,
writes in sequence, segments whole, counted refusals, and a watchdog fed by progress only
(the frames of :mod:`~galvoscan.gateware.host.frames`; galvoscan's bad-input rules, README
"Safety").

Two harnesses, each small enough for a quick proof:

* :class:`SPIFrameSpec`: the SPI target alone, its pins free: a frame it hands on as intact
  is one of exactly 80 SCK rising edges since ``cs_n`` fell whose CRC-16 holds, computed here
  from the pins (the spec's own shift register), and carries that frame's first 64 bits;
* :class:`CommandPathSpec`: the decoder and the register file, with frame events from both
  links free (any contents, any intact flag, on any clock: a superset of what either
  transport hands on): no register is written but by an intact write frame with the
  expected sequence number, a segment's end point is the one in the frame that queues it,
  every refused frame is counted, and the watchdog hears only of progress.

Together: no register changes on a frame whose check fails, from either link.
"""

from amaranth.asserts import AnyConst, AnySeq
from amaranth.hdl import (Assert, Cat, ClockDomain, Const, Cover, Elaboratable, Module, Mux,
                          ResetSignal, Signal)
from amaranth.lib.wiring import connect

from ..gateware.host.command import FREE_ADDRESS, SEGMENT_ADDRESS, CommandDecoder
from ..gateware.host.frames import (COMMAND_BITS, CRC_INIT, CRC_POLY, PAYLOAD_BITS, Answer,
                                     crc16)
from ..gateware.host.progress import ProgressFeed
from ..gateware.host.registers import RegisterFile
from ..gateware.host.regmap import BY_NAME
from ..gateware.host.spi_target import SPITarget


__all__ = ["SPIFrameSpec", "CommandPathSpec", "spi_frame_bits"]

#: ``errors`` stops here.
_ERRORS_TOP = 0xFFFF


def spi_frame_bits(seq=0, address=BY_NAME["dwell"].address, data=5, x=0, y=0):
    """The 80 bits, first first, of a write frame (what the paced host clocks in)."""
    body = bytes([seq, address, data >> 8, data & 0xFF, x >> 8, x & 0xFF, y >> 8, y & 0xFF])
    frame = body + crc16(body).to_bytes(2, "big")
    return [(byte >> (7 - i)) & 1 for byte in frame for i in range(8)]


def _synchronised(m, pin, init):
    """The pin two clocks ago, as the design sees it after its synchronisers (which a reset
    does not touch)."""
    stages = [Signal(init=init, reset_less=True, name=f"{pin.name}_d{i}") for i in (1, 2)]
    m.d.sync += [stages[0].eq(pin), stages[1].eq(stages[0])]
    return stages[1]


class SPIFrameSpec(Elaboratable):
    """The SPI target: what it hands on is what the pins carried.

    Proved for free pins and a free reset (mid-frame included):

    * **frames**: the target offers a frame event exactly while the spec holds an ended frame
      not yet taken (cs_n rose after falling, and no frame started since), and it carries the
      first 64 bits clocked in;
    * **check**: the event is intact only if exactly 80 SCK rising edges came while ``cs_n``
      was low and the CRC-16/CCITT of the 80 bits, worked out here bit by bit from the pins,
      is zero (the frame's own CRC holds).

    Helper invariants tie the target's assembly registers and CRC to the spec's.

    Parameters
    ----------
    make_spi : callable
        Builds the target under proof (the tests pass broken ones).
    helpers : bool
        State the helper invariants (the broken designs' bounded checks leave them out).
    reset_free : bool
    one_frame : bool
        A paced host instead of free pins, for the covers and the broken designs' bounded
        checks: SCK toggles every clock, ``cs_n`` is low from the first clock to a last one
        the solver chooses, and COPI carries a good write frame (:func:`spi_frame_bits`)
        with any one bit flipped or none. Each such run is one of the free pins' runs.
    """

    def __init__(self, *, make_spi=SPITarget, helpers=True, reset_free=True, one_frame=False):
        self.make_spi = make_spi
        self.helpers = helpers
        self.reset_free = reset_free
        self.one_frame = one_frame

    def elaborate(self, platform):
        m = Module()
        m.domains.sync = ClockDomain()
        reset = Signal()
        m.d.comb += ResetSignal("sync").eq(reset)
        m.submodules.spi = spi = self.make_spi()
        m.d.comb += spi.replies.valid.eq(AnySeq(1))
        m.d.comb += spi.replies.payload.eq(AnySeq(Answer.size))
        m.d.comb += spi.frames.ready.eq(AnySeq(1))
        if self.one_frame:
            clock = Signal(8, reset_less=True)
            with m.If(clock != 255):
                m.d.sync += clock.eq(clock + 1)
            last = AnyConst(8)
            flip = AnyConst(7)              # a bit to flip (80 and up: none)
            bits = spi_frame_bits()
            sck_pin = Signal(reset_less=True)
            m.d.sync += sck_pin.eq(~sck_pin)
            # The bit on COPI at each rising SCK edge: bit k rises at clock 2k + 1.
            index = clock[1:]
            copi = Signal()
            with m.Switch(index):
                for k, bit in enumerate(bits):
                    with m.Case(k):
                        m.d.comb += copi.eq(bit ^ (flip == k))
            m.d.comb += [spi.sck.eq(sck_pin), spi.cs_n.eq(clock > last), spi.copi.eq(copi)]
            if self.reset_free:
                m.d.comb += reset.eq(AnySeq(1) & (clock < last))
        else:
            m.d.comb += [spi.sck.eq(AnySeq(1)), spi.cs_n.eq(AnySeq(1)), spi.copi.eq(AnySeq(1))]
            if self.reset_free:
                m.d.comb += reset.eq(AnySeq(1))

        sck = _synchronised(m, spi.sck, 0)
        cs_n = _synchronised(m, spi.cs_n, 1)
        copi = _synchronised(m, spi.copi, 0)
        sck_q = Signal()
        m.d.sync += sck_q.eq(sck)

        # The frame as the pins carry it, and its CRC, a bit at a time.
        selected = Signal()
        bits = Signal(range(COMMAND_BITS + 2))
        shift = Signal(PAYLOAD_BITS)
        crc = Signal(16, init=CRC_INIT)
        ended = Signal()            # an ended frame the target has not had taken
        feedback = crc[15] ^ copi
        with m.If(~cs_n & ~selected):
            m.d.sync += [selected.eq(1), bits.eq(0), shift.eq(0), crc.eq(CRC_INIT),
                         ended.eq(0)]
        with m.Elif(~cs_n & selected & sck & ~sck_q):
            with m.If(bits < PAYLOAD_BITS):
                m.d.sync += shift.eq(Cat(copi, shift))
            with m.If(bits != COMMAND_BITS + 1):
                m.d.sync += bits.eq(bits + 1)
            m.d.sync += crc.eq(Cat(Const(0, 1), crc[:15]) ^
                               (Const(CRC_POLY, 16) & feedback.replicate(16)))
        with m.Elif(cs_n & selected):
            m.d.sync += [selected.eq(0), ended.eq(1)]
        with m.If(spi.frames.valid & spi.frames.ready):
            m.d.sync += ended.eq(0)

        intact = (bits == COMMAND_BITS) & (crc == 0)
        event = spi.frames
        m.d.comb += [
            Assert(event.valid == ended, "an SPI frame event is offered once per frame"),
            Assert(~event.valid | (event.payload.payload == shift),
                   "an SPI frame event carries the frame's first 64 bits"),
            Assert(~event.valid | ~event.payload.intact | intact,
                   "an SPI frame is intact only with 80 bits and a CRC that holds"),
            Assert(~event.valid | event.payload.intact | ~intact,
                   "an SPI frame with 80 bits and a CRC that holds is intact"),
        ]
        if self.helpers:
            m.d.comb += [
                Assert(spi._selected == selected, "helper: target selected"),
                Assert(spi._bits == bits, "helper: target bit count"),
                Assert(spi._shift == shift, "helper: target bits"),
                Assert(spi._check.crc == crc, "helper: target CRC"),
                Assert(~(ended & selected), "helper: a frame event only between frames"),
            ]
        m.d.comb += [
            Cover(event.valid & event.payload.intact, "an intact SPI frame"),
            Cover(event.valid & ~event.payload.intact & (bits == COMMAND_BITS),
                  "a damaged 80-bit SPI frame refused by its CRC"),
            Cover(event.valid & (bits == COMMAND_BITS - 1), "a frame cut short by cs_n"),
        ]
        return m


class CommandPathSpec(Elaboratable):
    """Decoder → register file, for any frame events on both links, on any clock, and any
    reset. Proved:

    * **writes**: a register is written only two clocks after a frame is taken, and only if
      that frame is intact, a write (address bit 7 clear) whose ``seq`` is the one expected,
      and the access given is its address and data. So a frame whose check failed never
      writes, nor does one out of sequence;
    * **sequence**: the ``seq`` expected starts at 0 and goes up by one with each write done;
    * **segments**: a write of ``vec_op`` is done with the frame's x and y on
      ``segment_x`` / ``segment_y`` and ``segment`` high, and ``segment`` is high at no other
      time: the queue never takes one word of a segment without the others;
    * **counting**: a frame taken that is not intact is refused two clocks later; ``refused``
      comes only two or three clocks after a frame was taken; ``errors`` goes up by one on the
      clock after a refusal or an answer its link could not take (up to 65535), and changes
      at no other time;
    * **watchdog**: the progress feed tells the laser's watchdog of life only on the clock
      after a segment was queued or ``keepalive`` was pulsed: reads never feed it;
    * **answers**: a UART answer is never offered while the port is busy, and the answer it
      sends is held while it does (the port reads it from the decoder, with no copy). The
      UART port is modelled as busy from taking an answer until any later clock; the SPI
      target takes an answer or not, freely.

    Parameters
    ----------
    make_decoder, make_feed : callables
        Build the decoder and the progress feed under proof (the tests pass broken ones).
    reset_free : bool
    """

    def __init__(self, *, make_decoder=CommandDecoder, make_feed=ProgressFeed, reset_free=True,
                 regmap=None):
        self.make_decoder = make_decoder
        self.make_feed = make_feed
        self.reset_free = reset_free
        self.regmap = regmap

    def elaborate(self, platform):
        m = Module()
        m.domains.sync = ClockDomain()
        if self.reset_free:
            m.d.comb += ResetSignal("sync").eq(AnySeq(1))
        m.submodules.decoder = decoder = self.make_decoder()
        # The register file without its read path: a value read is anything at all.
        m.submodules.registers = registers = RegisterFile(self.regmap, read_back=False)
        m.d.comb += registers.bus.read_data.eq(AnySeq(16))
        connect(m, decoder.bus, registers.bus)
        for name in ("vec_op_ready", "cor_write_ready"):
            if hasattr(registers, name):
                m.d.comb += getattr(registers, name).eq(AnySeq(1))
        for link in (decoder.spi_frames, decoder.uart_frames):
            m.d.comb += [link.valid.eq(AnySeq(1)),
                         link.payload.payload.eq(AnySeq(PAYLOAD_BITS)),
                         link.payload.intact.eq(AnySeq(1))]
        # The UART port as the decoder meets it: busy from taking an answer (it sends it from
        # the decoder's copy) until any later clock; the SPI target takes one or not, freely.
        uart_busy = Signal()
        with m.If(decoder.uart_replies.valid & decoder.uart_replies.ready):
            m.d.sync += uart_busy.eq(1)
        with m.Elif(AnySeq(1)):
            m.d.sync += uart_busy.eq(0)
        m.d.comb += [decoder.uart_replies.ready.eq(~uart_busy),
                     decoder.spi_replies.ready.eq(AnySeq(1))]
        m.submodules.feed = feed = self.make_feed()
        m.d.comb += [feed.segment.eq(decoder.segment), feed.pushed.eq(registers.vec_op_push),
                     feed.keepalive.eq(registers.keepalive), feed.player.eq(0)]
        if hasattr(feed, "accepted"):           # (a broken feed that listens to every frame)
            m.d.comb += feed.accepted.eq(decoder.accepted)

        # --- the frames taken -----------------------------------------------------------------
        spi, uart = decoder.spi_frames, decoder.uart_frames
        take_spi = spi.valid & spi.ready
        take_uart = uart.valid & uart.ready
        taken = take_spi | take_uart
        frame = Mux(take_spi, spi.payload.as_value(), uart.payload.as_value())
        taken_q, taken_qq, taken_qqq = Signal(), Signal(), Signal()
        frame_q, frame_qq = Signal.like(spi.payload), Signal.like(spi.payload)
        m.d.sync += [taken_q.eq(taken), frame_q.eq(frame),
                     taken_qq.eq(taken_q), frame_qq.eq(frame_q), taken_qqq.eq(taken_qq)]
        m.d.comb += Assert(~(take_spi & take_uart), "one frame a clock: SPI first")

        def fields(f):
            p = f.payload
            return {"seq": p[56:64], "address": p[48:56], "data": p[32:48], "x": p[16:32],
                    "y": p[0:16], "intact": f.intact}

        # --- the sequence ---------------------------------------------------------------------
        write = registers.bus.write_en & registers.bus.write_ok
        seq = Signal(8)
        with m.If(write):
            m.d.sync += seq.eq(seq + 1)
        m.d.comb += Assert(decoder.seq == seq, "the seq expected goes up with each write done")

        # --- writes ---------------------------------------------------------------------------
        f = fields(frame_qq)
        good = (taken_qq & f["intact"] & ~f["address"][7] & (f["seq"] == seq) &
                (registers._write_address == f["address"][:7]) &
                (registers._write_data == f["data"]))
        m.d.comb += Assert(
            ~write | good,
            "a register is written only by an intact write frame with the expected seq")
        # --- segments -------------------------------------------------------------------------
        pushed = write & (registers._write_address == SEGMENT_ADDRESS)
        frame_end_point = ((decoder.segment_x == f["x"]) & (decoder.segment_y == f["y"]))
        m.d.comb += [
            Assert(~pushed | (decoder.segment & frame_end_point),
                   "a segment is queued with its frame's end point"),
            Assert(~decoder.segment | (registers.bus.write_en &
                                      (registers._write_address == SEGMENT_ADDRESS)),
                   "segment only with a write of vec_op"),
        ]

        # --- counting -------------------------------------------------------------------------
        m.d.comb += [
            Assert(~(taken_qq & ~frame_qq.intact) | decoder.refused,
                   "a frame that is not intact is refused"),
            Assert(~decoder.refused | taken_qq | taken_qqq, "only a frame taken is refused"),
        ]
        # An answer the link cannot take on the clock it is offered is lost, and counted (over
        # the UART, never: no frame is taken while it is busy).
        lost = ((decoder.uart_replies.valid & ~decoder.uart_replies.ready) |
                (decoder.spi_replies.valid & ~decoder.spi_replies.ready))
        errors_q = Signal.like(decoder.errors)
        counted_q = Signal()
        m.d.sync += [errors_q.eq(decoder.errors), counted_q.eq(decoder.refused | lost)]
        m.d.comb += Assert(
            decoder.errors == Mux((errors_q == _ERRORS_TOP) | ~counted_q, errors_q,
                                  errors_q + 1),
            "every refused frame is counted, and nothing else")

        # --- the watchdog's food --------------------------------------------------------------
        fed_q = Signal()
        m.d.sync += fed_q.eq((decoder.segment & registers.vec_op_push) | registers.keepalive)
        m.d.comb += Assert(~feed.alive | fed_q,
                           "the watchdog is fed only by a segment queued or a keepalive")

        # --- covers ---------------------------------------------------------------------------
        read_answered = decoder.uart_replies.valid & ~decoder.uart_replies.payload.code[7]
        m.d.comb += Assert(~decoder.uart_replies.valid | decoder.uart_replies.ready,
                           "a UART answer is never lost")
        held_q = Signal.like(decoder.uart_replies.payload)
        busy_q = Signal()
        m.d.sync += [held_q.eq(decoder.uart_replies.payload), busy_q.eq(uart_busy)]
        m.d.comb += Assert(~(busy_q & uart_busy) |
                           (decoder.uart_replies.payload.as_value() == held_q.as_value()),
                           "the answer the UART port sends is held while it does")
        m.d.comb += [
            Cover(write & (registers._write_address != SEGMENT_ADDRESS), "a register written"),
            Cover(pushed & (seq == 1), "a second write: a segment queued"),
            Cover(feed.alive, "the watchdog fed"),
            Cover(decoder.refused & (errors_q != 0), "a second refused frame counted"),
            Cover(read_answered & (decoder.uart_replies.payload.code == FREE_ADDRESS),
                  "a read answered"),
        ]
        return m
