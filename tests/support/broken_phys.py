"""Deliberately broken XY2-100 transmitters, to show that the PHY proof catches each fault.

Each is the real transmitter with one thing tampered with between it and the pins (or the
stream), so everything else about it stays correct and only the targeted property can fail.
"""

from amaranth.hdl import ClockDomain, ClockSignal, DomainRenamer, Module, Mux, Signal
from amaranth.lib import wiring

from galvoscan.gateware.phy.xy2_100 import XY2Transmitter


class TamperedPHY(wiring.Component):
    def __init__(self, kind, *, clk_freq, bit_rate, control_bits=0b001, z=False):
        self.kind = kind
        self.inner = XY2Transmitter(clk_freq=clk_freq, bit_rate=bit_rate,
                                    control_bits=control_bits, z=z)
        super().__init__(self.inner.signature)

    def elaborate(self, platform):
        m = Module()
        inner = self.inner
        if self.kind == "ignores_reset":
            # The transmitter on the same clock, in a domain without a reset: after a reset
            # mid-frame it carries on with the frame it was sending.
            m.domains.free_running = ClockDomain(reset_less=True)
            m.d.comb += ClockSignal("free_running").eq(ClockSignal("sync"))
            m.submodules.inner = DomainRenamer("free_running")(inner)
        else:
            m.submodules.inner = inner
        kind = self.kind
        half = inner.clocks_per_bit // 2

        clk, sync, x, y = inner.xy2_clk, inner.xy2_sync, inner.xy2_x, inner.xy2_y
        payload_x, ready = self.position.payload.x, inner.position.ready
        if inner.z_axis:
            z, z_in = inner.xy2_z, self.z

        # The wrapper's own view of which bit is on the wires, aligned with them: on the clock
        # where xy2_clk rises it is already the new bit.
        clk_q, sync_q = Signal(), Signal()
        m.d.sync += [clk_q.eq(clk), sync_q.eq(sync)]
        rise = clk & ~clk_q
        sync_rise = sync & ~sync_q
        bit_q = Signal(range(32))
        bit = Mux(rise, Mux(sync_rise, 0, bit_q + 1), bit_q)
        m.d.sync += bit_q.eq(bit)
        started_q = Signal()
        m.d.sync += started_q.eq(started_q | sync_rise)
        started = started_q | sync_rise

        if kind == "bad_parity":
            # X inverted during the parity bit.
            x = x ^ (~sync & started)
        elif kind == "data_on_falling_edge":
            # X delayed by half a bit: it changes when the scan head samples.
            for i in range(half):
                delayed = Signal(name=f"x_delay{i}")
                m.d.sync += delayed.eq(x)
                x = delayed
        elif kind == "sync_low_early":
            # SYNC drops for bit 19 as well as for the parity bit.
            sync = sync & ~(started & (bit == 18))
        elif kind == "sync_late":
            # After the first frame SYNC rises a bit late: the frames are 21 bits apart.
            after_first = Signal()
            with m.If(started & (bit == 19)):
                m.d.sync += after_first.eq(1)
            sync = sync & ~(after_first & (bit == 0))
        elif kind == "corrupt_data":
            # The position sent is not the one taken from the stream.
            payload_x = payload_x ^ 0x0100
        elif kind == "mid_frame_latch":
            # The stream is also ready in the middle of a frame.
            ready = ready | (started & (bit == 9) & rise)
        elif kind == "ignores_reset":
            pass
        elif kind == "z_bad_parity":
            # Z inverted during the parity bit.
            z = z ^ (~sync & started)
        elif kind == "z_corrupt":
            # The Z sent is not the one taken.
            z_in = z_in ^ 0x0100
        elif kind == "z_late":
            # Z a clock old when the frame's position is taken: a Z that changes on that clock
            # goes out a frame late.
            z_q = Signal(16)
            m.d.sync += z_q.eq(z_in)
            z_in = z_q
        elif kind == "idle_clock":
            # One clock pulse a frame is swallowed.
            clk = clk & ~(started & (bit == 10))
        else:
            raise ValueError(f"unknown fault {kind!r}")

        m.d.comb += [
            inner.position.valid.eq(self.position.valid),
            inner.position.payload.x.eq(payload_x),
            inner.position.payload.y.eq(self.position.payload.y),
            self.position.ready.eq(ready),
            self.frame_strobe.eq(inner.frame_strobe),
            self.xy2_clk.eq(clk),
            self.xy2_sync.eq(sync),
            self.xy2_x.eq(x),
            self.xy2_y.eq(y),
        ]
        if inner.z_axis:
            m.d.comb += [inner.z.eq(z_in), self.xy2_z.eq(z)]
        return m


#: Each fault of the Z line (a transmitter built with it) and the property it must break.
Z_FAULTS = {
    "z_bad_parity": "Z frame has even parity",
    "z_corrupt": "Z data is the latched Z",
    "z_late": "Z data is the latched Z",
}

#: Each fault and the property (the Assert message in formal/xy2_100.py) it must break.
FAULTS = {
    "bad_parity": "X frame has even parity",
    "data_on_falling_edge": "SYNC, X and Y change only with a rising xy2_clk",
    "sync_low_early": "SYNC is high for bits 1-19 and low for the parity bit",
    "sync_late": "a frame is 20 bits and the next follows with no idle clock",
    "corrupt_data": "X data is the latched position",
    "mid_frame_latch": "a position is taken only on the clock before a frame starts",
    "idle_clock": "xy2_clk toggles every clocks_per_bit/2 system clocks",
    # After a reset the monitor starts again and sees the old frame's remains first.
    "ignores_reset": ("xy2_clk starts on the first clock after power-up",
                      "the first frame starts with the first clock",
                      "SYNC, X and Y change only with a rising xy2_clk",
                      "xy2_clk toggles every clocks_per_bit/2 system clocks",
                      "a position is taken only on the clock before a frame starts"),
}
