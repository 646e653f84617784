"""The command path from both links to a register write, as properties (Dai & Tang 2020's
frame; galvoscan's bad-input rules, README "Safety")."""

from amaranth.asserts import AnyConst, AnySeq
from amaranth.hdl import (Assert, Cat, ClockDomain, Cover, Elaboratable, Module, Mux,
                          ResetSignal, Signal)
from amaranth.lib.wiring import connect

from ..gateware.host.command import CommandDecoder
from ..gateware.host.frames import FRAME_BITS
from ..gateware.host.registers import RegisterFile
from ..gateware.host.regmap import CHECK_BYTE
from ..gateware.host.spi_target import SPITarget


__all__ = ["CommandPathSpec"]

#: ``errors`` stops here.
_ERRORS_TOP = 0xFFFF


class CommandPathSpec(Elaboratable):
    """No register write without a complete 32-bit frame with check byte 0x64, from either link,
    and every other frame counted; for every input and every reset.

    The SPI pins are free on every clock (any SCK rate, glitches, ``cs_n`` released anywhere),
    and so is the UART port's side of the decoder (any frame event, on any clock, with any
    contents: a superset of what the UART port can hand on; the port's byte and idle rules are
    simulated against a model in ``tests/test_uart_port.py``). The reset is free too, mid-frame
    included. The spec reads the SPI pins as the design must: through two flip-flops. Proved:

    * **writes**: a register is written only two clocks after ``cs_n`` rose at the end of a
      frame of exactly 32 SCK rising edges (counted since ``cs_n`` fell after the last reset)
      whose last byte is 0x64 and whose address bit 7 is clear, or on the clock after a UART
      frame event of 32 bits with those bytes is taken; and the access given to the register
      file on the clock the frame was taken is that frame's address and data. So a frame cut
      short, run over, or cut by a reset never writes;
    * **one frame a clock**: a UART frame waits while an SPI frame is decoded;
    * **counting**: a frame is accepted or not on the clock after it is taken, and only if it
      is complete with check byte 0x64; ``errors`` goes up by one on the clock after a frame is
      not accepted (up to 65535), and changes at no other time.

    A frame may last for ever, so k-induction alone cannot relate the spec's view of the frame
    to the SPI target's; helper invariants (also proved) say that the two agree.

    The proof is made with everything live. Its covers come in two harnesses: this one shows
    a UART write, a rejected frame counted and a read answered within a few clocks; an SPI
    harness (``uart_live=False, reset_free=False, one_frame=True``: a restriction of this
    one) shows an SPI write, a frame cut short and a read answered over SPI, which need some
    70 clocks, where the free UART, reset and SCK would make every step of the search far
    slower.

    Parameters
    ----------
    make_spi, make_decoder : callables
        Build the SPI target and the decoder under proof (the tests pass broken ones).
    helpers : bool
        State the helper invariants. The broken designs' bounded checks leave them out, so
        that the counterexample shows the bad write itself.
    uart_live : bool
        UART frame events free (else none come).
    reset_free : bool
        The reset free (else never asserted).
    regmap : :class:`~galvoscan.gateware.host.regmap.RegisterMap`, optional
        The register file's map (default: the default build's). The SPI covers' harness uses a
        small one: the properties do not depend on which registers there are, and a smaller
        register file makes each of the 70 steps of the search cheaper.
    one_frame : bool
        One SPI frame from a paced host instead of free pins: for covers and the broken
        designs' bounded checks only, never for the proof. SCK toggles on every clock from
        power-up; ``cs_n`` is low from the first clock to a last one the solver chooses (any
        constant), then high; COPI is free; with ``reset_free`` the reset is free on every
        clock while ``cs_n`` is low, except its last (a reset that cuts the frame). Each such
        run is one of the free harness's runs, so a cover reached or a counterexample found
        here is one there too. The SCK and frame timing being fixed spares the solver ruling
        out every other SCK pattern step by step, which took minutes; a rising edge every
        other clock is the fastest SCK the synchronisers pass, so a frame ends here as soon as
        it can with free pins: 31 bits are seen at clock 65 at the earliest, 32 at clock 67.
    """

    def __init__(self, *, make_spi=SPITarget, make_decoder=CommandDecoder, helpers=True,
                 uart_live=True, reset_free=True, regmap=None, one_frame=False):
        self.regmap = regmap
        self.one_frame = one_frame
        self.make_spi = make_spi
        self.make_decoder = make_decoder
        self.helpers = helpers
        self.uart_live = uart_live
        self.reset_free = reset_free

    def elaborate(self, platform):
        m = Module()
        m.domains.sync = ClockDomain()
        reset = Signal()
        m.d.comb += ResetSignal("sync").eq(reset)
        if self.reset_free and not self.one_frame:
            m.d.comb += reset.eq(AnySeq(1))
        m.submodules.spi = spi = self.make_spi()
        m.submodules.decoder = decoder = self.make_decoder()
        # The register file without its read path: a value read is anything at all.
        m.submodules.registers = registers = RegisterFile(self.regmap, read_back=False)
        m.d.comb += registers.bus.read_data.eq(AnySeq(16))
        connect(m, spi.frames, decoder.spi_frames)
        connect(m, decoder.spi_replies, spi.replies)
        connect(m, decoder.bus, registers.bus)
        uart = decoder.uart_frames
        m.d.comb += [
            uart.valid.eq(AnySeq(1) if self.uart_live else 0),
            uart.payload.word.eq(AnySeq(len(uart.payload.word))),
            uart.payload.bits.eq(AnySeq(len(uart.payload.bits))),
            decoder.uart_replies.ready.eq(AnySeq(1)),
            spi.copi.eq(AnySeq(1)),
        ]
        if self.one_frame:
            # The host's own count of clocks (a reset of the design does not touch the host).
            clock = Signal(8, reset_less=True)
            with m.If(clock != 255):
                m.d.sync += clock.eq(clock + 1)
            last = AnyConst(8)                  # cs_n's last low clock
            sck_pin = Signal(reset_less=True)
            m.d.sync += sck_pin.eq(~sck_pin)
            m.d.comb += [spi.sck.eq(sck_pin), spi.cs_n.eq(clock > last)]
            if self.reset_free:
                m.d.comb += reset.eq(AnySeq(1) & (clock < last))
        else:
            m.d.comb += [spi.sck.eq(AnySeq(1)), spi.cs_n.eq(AnySeq(1))]

        # The pins two clocks ago, as the design sees them after its synchronisers (which a
        # reset does not touch).
        def delayed(pin, init):
            stages = [Signal(init=init, reset_less=True, name=f"{pin.name}_d{i}")
                      for i in (1, 2)]
            m.d.sync += [stages[0].eq(pin), stages[1].eq(stages[0])]
            return stages[1]
        sck, cs_n, copi = delayed(spi.sck, 0), delayed(spi.cs_n, 1), delayed(spi.copi, 0)
        sck_q = Signal()
        m.d.sync += sck_q.eq(sck)

        # The SPI frame, from cs_n falling (or seen low after a reset) to cs_n rising.
        selected = Signal()
        bits = Signal(range(FRAME_BITS + 2))
        shift = Signal(FRAME_BITS)
        with m.If(~cs_n & ~selected):
            m.d.sync += [selected.eq(1), bits.eq(0), shift.eq(0)]
        with m.Elif(~cs_n & selected & sck & ~sck_q):
            m.d.sync += shift.eq(Cat(copi, shift))
            with m.If(bits != FRAME_BITS + 1):
                m.d.sync += bits.eq(bits + 1)
        with m.Elif(cs_n & selected):
            m.d.sync += selected.eq(0)

        # The SPI frame that ended on the last clock.
        ended = Signal()
        word = Signal(FRAME_BITS)
        word_bits = Signal.like(bits)
        m.d.sync += ended.eq(cs_n & selected)
        with m.If(cs_n & selected):
            m.d.sync += [word.eq(shift), word_bits.eq(bits)]

        def good_write(frame_bits, frame_word):
            return ((frame_bits == FRAME_BITS) & (frame_word[0:8] == CHECK_BYTE) &
                    ~frame_word[31] & (registers.bus.address == frame_word[24:31]) &
                    (registers.bus.write_data == frame_word[8:24]))

        def complete(frame_bits, frame_word):
            return (frame_bits == FRAME_BITS) & (frame_word[0:8] == CHECK_BYTE)

        uart_taken = uart.valid & ~ended
        taken = ended | uart_taken
        # A frame taken on one clock is decided on the next (the register file checks the
        # access on the clock it is given and writes on the next): what was taken, as seen
        # on the clock after.
        good_q, complete_q, taken_q, ended_q = Signal(), Signal(), Signal(), Signal()
        m.d.sync += [
            good_q.eq((ended & good_write(word_bits, word)) |
                      (uart_taken & good_write(uart.payload.bits, uart.payload.word))),
            complete_q.eq(Mux(ended, complete(word_bits, word),
                              uart_taken & complete(uart.payload.bits, uart.payload.word))),
            taken_q.eq(taken),
            ended_q.eq(ended),
        ]
        write = registers.bus.write_en & registers.bus.write_ok
        m.d.comb += [
            # On the clock after the frame was taken, the access given on that clock being
            # the frame's address and data.
            Assert(~write | good_q,
                   "a register is written only by a complete frame with check byte 0x64"),
            Assert(uart.ready == ~ended, "one frame a clock: a UART frame waits for SPI"),
        ]

        # --- every frame accepted or counted ------------------------------------------------
        accepted = decoder.accepted
        m.d.comb += Assert(~accepted | (taken_q & complete_q),
                           "only a complete frame with check byte 0x64 is accepted")
        m.d.comb += Assert(~write | accepted, "a write is an accepted frame")
        errors_q = Signal.like(decoder.errors)
        rejected_q = Signal()
        m.d.sync += [errors_q.eq(decoder.errors), rejected_q.eq(taken_q & ~accepted)]
        m.d.comb += Assert(
            decoder.errors == Mux((errors_q == _ERRORS_TOP) | ~rejected_q, errors_q,
                                  errors_q + 1),
            "every rejected frame is counted, and nothing else")

        if self.helpers:
            # Helper invariants: the SPI target's frame is the spec's frame.
            m.d.comb += [
                Assert(spi._selected == selected, "helper: target selected"),
                Assert(spi._bits == bits, "helper: target bit count"),
                Assert(~selected | (spi._shift == shift), "helper: target bits"),
                Assert(spi.frames.valid == ended, "helper: one frame event per frame"),
                Assert(~ended | ((spi.frames.payload.word == word) &
                                 (spi.frames.payload.bits == word_bits)),
                       "helper: frame event carries the frame"),
            ]

        # --- covers -------------------------------------------------------------------------
        if self.uart_live:
            m.d.comb += [
                Cover(write & taken_q & ~ended_q, "a register is written over the UART"),
                Cover(rejected_q & (errors_q != 0), "a second rejected frame counted"),
                Cover(decoder.uart_replies.valid, "a read is answered over the UART"),
            ]
        else:
            m.d.comb += [
                Cover(write & ended_q, "a register is written over SPI"),
                Cover(ended & (word_bits == FRAME_BITS - 1) & (word[0:8] == CHECK_BYTE),
                      "a frame with a good check byte cut short by cs_n"),
                Cover(decoder.spi_replies.valid, "a read is answered over SPI"),
            ]
        return m
