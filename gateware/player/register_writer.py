"""The job player's register writer: one write at a time to the register file, through the
bus arbiter, each checked by the register file as a host's is."""

from amaranth.hdl import Module, Mux, Signal
from amaranth.lib import data, stream, wiring
from amaranth.lib.wiring import In, Out

from ..host.registers import RegisterBus
from ..host.regmap import BY_NAME


__all__ = ["RegisterWriter", "TARGETS"]


#: The registers the player writes, by the code it names them with: None, a setting's own
#: address; from "vec_x" on, the value is the word read.
TARGETS = ("arm", "mode", "run", "vec_flush", None, "vec_x", "vec_y", "vec_op")


class RegisterWriter(wiring.Component):
    """Writes the registers the player asks for, one at a time.

    A write asked for waits for a clock the arbiter grants (:attr:`grant`), and is done (or
    refused) on the next. Its value is the image's word being played (:attr:`word`, which the
    player holds meanwhile) for the targets from ``vec_x`` on and a setting's, or a small
    constant for the registers the player drives itself; the register is named by its code in
    :data:`TARGETS` (a setting's address comes in :attr:`setting_address`). A new request
    replaces a write not yet done (the player's laser-first stop asks for ``arm`` 0 whatever
    write is under way).

    Interface attributes
    --------------------
    request : ``In(stream.Signature(target, constant))``
        A write to ask for: ``target``, the code in :data:`TARGETS`; ``constant``, the value
        of the targets before ``vec_x``. Always taken (``ready`` is not used): ask only while
        :attr:`free`, but for the stop.
    word : ``In(16)``; setting_address : ``In(7)``
        The image's word being played; the register a setting writes.
    bus : ``Out(RegisterBus())``; grant : ``In(1)``
        To the register file, through the arbiter, on the clocks it grants.
    free : ``Out(1)``
        No write under way.
    refused : ``Out(1)``
        The last write was refused (cleared by the next request).
    wrote : ``Out(1)``
        A write done this clock: progress, for the laser's watchdog.
    """

    def __init__(self):
        self.request_layout = data.StructLayout({"target": range(len(TARGETS)),
                                                 "constant": 2})
        super().__init__({
            "request": In(stream.Signature(self.request_layout, always_ready=True)),
            "word": In(16), "setting_address": In(7),
            "bus": Out(RegisterBus()), "grant": In(1),
            "free": Out(1), "refused": Out(1), "wrote": Out(1),
        })

    def elaborate(self, platform):
        m = Module()
        target = Signal(range(len(TARGETS)))
        constant = Signal(2)
        waiting = Signal()          # given, not yet granted
        checking = Signal()         # granted: done or refused on this clock
        m.d.comb += self.free.eq(~waiting & ~checking)
        address = Signal(7)
        with m.Switch(target):
            for code, name in enumerate(TARGETS):
                with m.Case(code):
                    m.d.comb += address.eq(self.setting_address if name is None else
                                           BY_NAME[name].address)
        from_word = target >= TARGETS.index(None)
        m.d.comb += [
            self.bus.address.eq(address),
            self.bus.write_data.eq(Mux(from_word, self.word, constant)),
            self.bus.write_en.eq(checking),
            self.wrote.eq(checking & self.bus.write_ok),
        ]
        with m.If(waiting & self.grant):
            m.d.sync += [waiting.eq(0), checking.eq(1)]
        with m.If(checking):
            m.d.sync += [checking.eq(0), self.refused.eq(~self.bus.write_ok)]
        # (After the above: a request on the clock a write is granted or checked replaces it.)
        with m.If(self.request.valid):
            m.d.sync += [target.eq(self.request.payload.target),
                         constant.eq(self.request.payload.constant),
                         waiting.eq(1), self.refused.eq(0)]
        return m
