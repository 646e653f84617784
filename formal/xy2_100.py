"""What an XY2-100 scan head needs from the transmitter, as properties.

The spec watches only what a scan head and a position source can see: the four wires and the
position stream. Its monitor is written from the XY2-100 protocol (control bits, 001 by
default; even parity; SYNC low on the parity bit), not from the PHY, so a PHY that differs
from the protocol anywhere fails the proof.
"""

from amaranth.asserts import AnySeq
from amaranth.hdl import (Assert, Cat, ClockDomain, Cover, Elaboratable, Fragment, Module, Mux,
                          ResetSignal, Signal)

from ..gateware.phy.xy2_100 import FRAME_BITS, frame_word
from ..gateware.points import FIELD_CENTRE, FieldPoint


__all__ = ["XY2TransmitterSpec"]


class XY2TransmitterSpec(Elaboratable):
    """Properties of an XY2 transmitter, for SymbiYosys.

    Proved from power-up and after every reset (the reset is free on every clock, mid-frame
    included: the monitor starts again with it, so after a reset the wires must once more give
    whole, correct frames from the first clock on), for any sequence of offered positions
    (free ``valid`` and payload on every clock):

    * **clock**: ``xy2_clk`` toggles every ``clocks_per_bit / 2`` system clocks, for ever;
    * **edges**: SYNC, X and Y change only together with a rising edge of ``xy2_clk``, so they
      are stable at every falling edge, where the scan head samples;
    * **frames**: every frame is 20 clocks; SYNC rises at the first bit of each frame, stays high
      for bits 1-19 and is low during the parity bit, with no idle clock between frames;
    * **content**: on each axis, the three control bits are ``control_bits``, the 20 bits have
      even parity, and the 16 data bits are the position taken from the stream at the start of
      the frame (the centre until the first one);
    * **latching**: the stream is ready only on the clock before a frame starts;
    * **Z** (a transmitter with ``xy2_z``): the Z line keeps the same edges, control bits and
      parity, and its 16 data bits are ``z`` as it was on the clock the frame's position was
      taken (free on every clock).

    Parameters
    ----------
    dut : component with the :class:`~galvoscan.gateware.phy.xy2_100.XY2Transmitter` signature
    clocks_per_bit : int
        System clocks per XY2 bit of ``dut``.
    control_bits : int
        Control bits the frames must carry.
    reset_free : bool
        The reset free on every clock (else never asserted: power-up only).
    """

    def __init__(self, dut, *, clocks_per_bit, control_bits=0b001, reset_free=True):
        self.reset_free = reset_free
        self.dut = dut
        self.clocks_per_bit = clocks_per_bit
        self.control_bits = control_bits

    def elaborate(self, platform):
        m = Module()
        # The reset is free; the monitor's own state resets with it, so every property below
        # holds after a reset as it does after power-up.
        m.domains.sync = ClockDomain()
        m.d.comb += ResetSignal("sync").eq(AnySeq(1) if self.reset_free else 0)
        dut = self.dut
        if hasattr(dut, "_latched"):
            # The real transmitter: elaborated here, so that the helper invariants below can
            # name its clock-into-the-bit counter and shift registers.
            body = Fragment.get(dut, platform)
            internals = {signal.name: signal for statement in body.statements.get("sync", ())
                         for signal in statement._lhs_signals()}
            m.submodules.dut = body
        else:
            m.submodules.dut = dut

        m.d.comb += [
            dut.position.valid.eq(AnySeq(1)),
            dut.position.payload.eq(AnySeq(len(dut.position.payload.as_value()))),
        ]
        has_z = "xy2_z" in dut.signature.members
        if has_z:
            m.d.comb += dut.z.eq(AnySeq(16))

        half = self.clocks_per_bit // 2
        clk, sync, x, y = dut.xy2_clk, dut.xy2_sync, dut.xy2_x, dut.xy2_y
        # (Without a Z line, a constant low one: every property of it holds trivially.)
        z = dut.xy2_z if has_z else Signal(name="no_z")

        # The wires one clock ago; all low at power-up and after reset.
        clk_q, sync_q, x_q, y_q, z_q = (Signal(name=f"{s.name}_q") for s in (clk, sync, x, y, z))
        m.d.sync += [clk_q.eq(clk), sync_q.eq(sync), x_q.eq(x), y_q.eq(y), z_q.eq(z)]
        rise = clk & ~clk_q
        fall = ~clk & clk_q
        sync_rise = sync & ~sync_q

        # --- clock ------------------------------------------------------------------------------
        clk_started = Signal()      # the first rising edge has been seen
        since_toggle = Signal(range(half + 1))
        with m.If(clk != clk_q):
            m.d.sync += [clk_started.eq(1), since_toggle.eq(0)]
        with m.Elif(since_toggle < half):
            m.d.sync += since_toggle.eq(since_toggle + 1)
        with m.If(clk_started):
            m.d.comb += Assert((clk != clk_q) == (since_toggle == half - 1),
                               "xy2_clk toggles every clocks_per_bit/2 system clocks")
        with m.Else():
            m.d.comb += Assert(rise | (since_toggle == 0),
                               "xy2_clk starts on the first clock after power-up")

        # --- edges ------------------------------------------------------------------------------
        m.d.comb += Assert(rise | ((sync == sync_q) & (x == x_q) & (y == y_q)),
                           "SYNC, X and Y change only with a rising xy2_clk")
        if has_z:
            m.d.comb += Assert(rise | (z == z_q), "Z changes only with a rising xy2_clk")

        # --- frames -----------------------------------------------------------------------------
        in_frame = Signal()         # the first SYNC rise has been seen
        bit_no = Signal(range(FRAME_BITS))  # bit on the wire, 0 = C2 (first after SYNC rises)
        with m.If(rise):
            m.d.sync += bit_no.eq(Mux(bit_no == FRAME_BITS - 1, 0, bit_no + 1))
            with m.If(sync_rise):
                m.d.sync += [in_frame.eq(1), bit_no.eq(0)]
        with m.If(rise & in_frame):
            m.d.comb += [
                Assert(sync_rise == (bit_no == FRAME_BITS - 1),
                       "a frame is 20 bits and the next follows with no idle clock"),
                Assert(sync == (bit_no != FRAME_BITS - 2),
                       "SYNC is high for bits 1-19 and low for the parity bit"),
            ]
        # Frames start with the very first bit: no clock goes by without a frame.
        with m.If(rise & ~in_frame):
            m.d.comb += Assert(sync_rise, "the first frame starts with the first clock")

        # --- latching ---------------------------------------------------------------------------
        ready_q = Signal()
        m.d.sync += ready_q.eq(dut.position.ready)
        m.d.comb += Assert(ready_q == sync_rise,
                           "a position is taken only on the clock before a frame starts")

        taken = Signal(FieldPoint, init={"x": FIELD_CENTRE, "y": FIELD_CENTRE})
        with m.If(dut.position.valid & dut.position.ready):
            m.d.sync += taken.eq(dut.position.payload)
        # By the clock on which SYNC rises, `taken` holds the frame's position.
        frame_position = Signal(FieldPoint, init={"x": FIELD_CENTRE, "y": FIELD_CENTRE})
        with m.If(sync_rise):
            m.d.sync += frame_position.eq(taken)
        # Z likewise, whether or not a position is offered.
        taken_z = Signal(16, init=FIELD_CENTRE)
        frame_z = Signal(16, init=FIELD_CENTRE)
        if has_z:
            with m.If(dut.position.ready):
                m.d.sync += taken_z.eq(dut.z)
            with m.If(sync_rise):
                m.d.sync += frame_z.eq(taken_z)
        if hasattr(dut, "_latched"):
            # Helper invariant (proved too): the spec's memory of the last position taken is
            # the transmitter's. It spares the induction looking back over several frames.
            # The bit counters agree (the spec's moves a clock after the PHY's, with the clock
            # edge it counts) and stay in range.
            bit_q = Signal.like(dut._bit)
            m.d.sync += bit_q.eq(dut._bit)
            if has_z:
                m.d.comb += Assert(taken_z == dut._latched_z, "helper: the Z taken is latched")
            m.d.comb += [
                Assert(taken.as_value() == dut._latched.as_value(),
                       "helper: the position taken is the one latched"),
                Assert(dut._bit < FRAME_BITS, "helper: bit counter in range"),
                Assert(~in_frame | (bit_no == bit_q), "helper: the bit counters agree"),
            ]

        # --- content ----------------------------------------------------------------------------
        # Sample like a scan head: on the falling edge.
        rx_x = Signal(FRAME_BITS - 1)
        rx_y = Signal(FRAME_BITS - 1)
        rx_z = Signal(FRAME_BITS - 1)
        with m.If(fall):
            m.d.sync += [rx_x.eq(Cat(x, rx_x)), rx_y.eq(Cat(y, rx_y)), rx_z.eq(Cat(z, rx_z))]
        word_x = Cat(x, rx_x)   # the whole frame, valid on the parity bit's falling edge
        word_y = Cat(y, rx_y)
        word_z = Cat(z, rx_z)
        parity_sampled = fall & in_frame & (bit_no == FRAME_BITS - 1)
        with m.If(parity_sampled):
            m.d.comb += [
                Assert(word_x.xor() == 0, "X frame has even parity"),
                Assert(word_y.xor() == 0, "Y frame has even parity"),
                Assert(word_x[17:20] == self.control_bits, "X control bits"),
                Assert(word_y[17:20] == self.control_bits, "Y control bits"),
                Assert(word_x[1:17] == frame_position.x, "X data is the latched position"),
                Assert(word_y[1:17] == frame_position.y, "Y data is the latched position"),
            ]
            if has_z:
                m.d.comb += [
                    Assert(word_z.xor() == 0, "Z frame has even parity"),
                    Assert(word_z[17:20] == self.control_bits, "Z control bits"),
                    Assert(word_z[1:17] == frame_z, "Z data is the latched Z"),
                ]

        if hasattr(dut, "_latched"):
            # Helper invariants (proved too) that tie every bit of the spec's state to the
            # transmitter's, so that k-induction needs no more than a couple of clocks, whatever
            # the divider: without them it must look back over a whole frame (125 clocks at 6
            # clocks a bit) before the shift registers' contents are pinned down.
            per_bit = self.clocks_per_bit
            tick, bit = internals["tick"], dut._bit
            latched = dut._latched
            started = clk_started
            # Before the first rising edge is seen: power-up (or reset), or the clock after.
            m.d.comb += [
                Assert(in_frame == started, "helper: frames start with the clock"),
                Assert(started | ((tick == per_bit - 1) & (bit == FRAME_BITS - 1) & ~clk_q &
                                  (since_toggle == 0)) |
                       ((tick == 0) & (bit == 0) & ~clk_q & (since_toggle == 1)),
                       "helper: the first two clocks"),
            ]
            # The clock: high for the first half of each bit.
            m.d.comb += [
                Assert(tick < per_bit, "helper: tick in range"),
                Assert(clk == (tick < half), "helper: xy2_clk follows tick"),
                Assert(~started | (clk_q == Mux(tick == 0, 0, Mux(tick == half, 1, clk))),
                       "helper: xy2_clk one clock ago"),
                Assert(~started | (since_toggle == (tick + half - 1) % half),
                       "helper: clocks since xy2_clk toggled"),
                Assert(bit_q == Mux(tick == 0, Mux(bit == 0, FRAME_BITS - 1, bit - 1), bit),
                       "helper: bit one clock ago"),
                Assert(ready_q == ((tick == 0) & (bit == 0)), "helper: taken one clock ago"),
            ]
            # SYNC and the data: the frame of the position latched, bit by bit.
            m.d.comb += [
                Assert(sync == (bit != FRAME_BITS - 1), "helper: SYNC follows the bit"),
                Assert(sync_q == Mux(tick == 0, bit != 0, sync), "helper: SYNC one clock ago"),
                Assert(sync_rise | (frame_position.as_value() == latched.as_value()),
                       "helper: the frame's position is the one latched"),
            ]
            if has_z:
                m.d.comb += Assert(sync_rise | (frame_z == dut._latched_z),
                                   "helper: the frame's Z is the one latched")
            # Bits of the frame the spec has sampled: one a bit, on its falling edge.
            sampled = bit + (tick > half)
            lines = [("x", x, x_q, internals["shift_x"], rx_x, latched.x),
                     ("y", y, y_q, internals["shift_y"], rx_y, latched.y)]
            if has_z:
                lines.append(("z", z, z_q, internals["shift_z"], rx_z, dut._latched_z))
            for axis, wire, wire_q, shift, rx, value in lines:
                word = frame_word(self.control_bits, value)
                m.d.comb += [
                    Assert(~(started | (tick == 0)) |
                           (shift == (word << bit)[:FRAME_BITS]),
                           f"helper: {axis} shift register holds the rest of the frame"),
                    Assert(~(started | (tick == 0)) | (wire == shift[-1]),
                           f"helper: {axis} wire is the shift register's first bit"),
                    Assert((tick == 0) | (wire_q == wire), f"helper: {axis} one clock ago"),
                ]
                for count in range(1, FRAME_BITS):
                    with m.If(started & (sampled == count)):
                        m.d.comb += Assert(rx[:count] == word[FRAME_BITS - count:],
                                           f"helper: {axis} bits sampled so far")

        # --- covers -----------------------------------------------------------------------------
        # Two whole frames with different data on both axes, so the proof is not vacuous.
        frames_done = Signal(2)
        last_x = Signal(16)
        with m.If(parity_sampled):
            m.d.sync += last_x.eq(word_x[1:17])
            with m.If(frames_done != 3):
                m.d.sync += frames_done.eq(frames_done + 1)
        if has_z:
            m.d.comb += Cover(parity_sampled & (frames_done == 1) &
                              (word_z[1:17] != FIELD_CENTRE), "a frame with a new Z")
        m.d.comb += [
            Cover(parity_sampled & (frames_done == 1) & (word_x[1:17] != last_x) &
                  (word_y[1:17] != FIELD_CENTRE), "two frames with new data"),
            Cover(parity_sampled & (frames_done == 1) & (word_x[1:17] == last_x) &
                  (last_x != FIELD_CENTRE),
                  "a position repeated when nothing new is offered"),
        ]
        return m
