"""The register bus shared by the host's command decoder and the job player."""

from amaranth.hdl import Cat, Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .registers import RegisterBus
from .regmap import BY_NAME


__all__ = ["BusArbiter", "TAKE_OVER"]


#: Registers a host's write of which takes the machine back from the player.
TAKE_OVER = ("arm", "run", "mode")


class BusArbiter(wiring.Component):
    """Puts the host's accesses and the player's writes on the one register bus.

    The host goes first: its decoder gives an access on any clock a frame is taken
    (:attr:`host_given`), and cannot wait. The player may give a write on any other clock
    (:attr:`grant`), and waits otherwise; each access is done on the clock after it is given
    (:class:`~.registers.RegisterBus`), so the two never meet. Both get the register file's
    answers; each looks only at its own.

    Interface attributes
    --------------------
    host : ``In(RegisterBus())``; host_given : ``In(1)``
        The command decoder's accesses, and a frame taken on this clock.
    player : ``In(RegisterBus())``; grant : ``Out(1)``
        The player's writes, given only on a clock ``grant`` is high.
    bus : ``Out(RegisterBus())``
        To the register file.
    host_took_over : ``Out(1)``
        High for one clock when a host's write of one of :data:`TAKE_OVER` is done.
    """

    host: In(RegisterBus())
    host_given: In(1)
    player: In(RegisterBus())
    grant: Out(1)
    bus: Out(RegisterBus())
    host_took_over: Out(1)

    def elaborate(self, platform):
        m = Module()
        m.d.comb += [
            self.grant.eq(~self.host_given),
            self.bus.address.eq(Mux(self.host_given, self.host.address, self.player.address)),
            self.bus.write_data.eq(Mux(self.host_given, self.host.write_data,
                                       self.player.write_data)),
            self.bus.write_en.eq(self.host.write_en | self.player.write_en),
        ]
        for port in (self.host, self.player):
            m.d.comb += [port.write_ok.eq(self.bus.write_ok), port.read_ok.eq(self.bus.read_ok),
                         port.read_data.eq(self.bus.read_data)]
        host_takes = Signal()
        m.d.sync += host_takes.eq(Cat(self.host.address == BY_NAME[name].address
                                      for name in TAKE_OVER).any())
        m.d.comb += self.host_took_over.eq(self.host.write_en & self.bus.write_ok & host_takes)
        return m
