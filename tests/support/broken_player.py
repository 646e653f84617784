"""Deliberately broken job players, to show that the player's proof catches each fault: the
real player, with what it is told of the flash, or what it writes, tampered with."""

from amaranth.hdl import Module, Mux, Signal
from amaranth.lib import wiring

from galvoscan.gateware.fields import PlayerState
from galvoscan.gateware.host.regmap import BY_NAME
from galvoscan.gateware.player.image_format import MAGIC
from galvoscan.gateware.player.player import JobPlayer


#: Each fault, and what it does.
PLAYER_FAULTS = {
    "magic_not_checked": "every image's first four bytes reach the check as the magic",
    "length_short": "the check is told a length one word shorter than the image's",
    "byte_unchecked": "a byte of the repeats is changed between the flash and the check",
    "arms_on_start": "arm is written on the clock after a start, before any check",
}

PASSED_THROUGH = ("read_address", "read_start", "read_stop", "read_idle", "grant", "start",
                  "queue_ready", "queue_empty", "vector_busy", "laser_ready", "fault",
                  "host_took_over", "state", "result", "refused", "armed", "alive")


class TamperedPlayer(wiring.Component):
    def __init__(self, kind, **kwargs):
        if kind not in PLAYER_FAULTS:
            raise ValueError(f"unknown fault {kind!r}")
        self.kind = kind
        self.inner = JobPlayer(**kwargs)
        super().__init__(self.inner.signature)

    def elaborate(self, platform):
        m = Module()
        m.submodules.inner = inner = self.inner
        for name in PASSED_THROUGH:
            outer, inside = getattr(self, name), getattr(inner, name)
            if name in ("read_address", "read_start", "read_stop", "state", "result",
                        "refused", "armed", "alive"):
                m.d.comb += outer.eq(inside)
            else:
                m.d.comb += inside.eq(outer)
        m.d.comb += [
            inner.read_data.valid.eq(self.read_data.valid),
            self.read_data.ready.eq(inner.read_data.ready),
            inner.bus.write_ok.eq(self.bus.write_ok),
            inner.bus.read_ok.eq(self.bus.read_ok),
            inner.bus.read_data.eq(self.bus.read_data),
        ]
        # The index of each byte taken since the last read start.
        index = Signal(8)
        with m.If(self.read_start):
            m.d.sync += index.eq(0)
        with m.Elif(self.read_data.valid & self.read_data.ready):
            m.d.sync += index.eq(index + 1)
        byte = self.read_data.payload
        if self.kind == "magic_not_checked":
            for k in range(4):
                byte = Mux(index == k, MAGIC[k], byte)
        elif self.kind == "length_short":
            byte = Mux(index == 6, self.read_data.payload - 2, self.read_data.payload)
        elif self.kind == "byte_unchecked":
            byte = Mux(index == 14, self.read_data.payload ^ 0x02, self.read_data.payload)
        m.d.comb += inner.read_data.payload.eq(byte)

        address, data, enable = inner.bus.address, inner.bus.write_data, inner.bus.write_en
        if self.kind == "arms_on_start":
            started = Signal()
            m.d.sync += started.eq(self.start & (inner.state == PlayerState.IDLE))
            address = Mux(started, BY_NAME["arm"].address, address)
            data = Mux(started, 1, data)
            enable = enable | started
        m.d.comb += [self.bus.address.eq(address), self.bus.write_data.eq(data),
                     self.bus.write_en.eq(enable)]
        return m
