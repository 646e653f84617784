"""Deliberately broken laser controllers, to show that the safety proof catches each fault."""

from amaranth.hdl import Module, Signal
from amaranth.lib import wiring

from galvoscan.gateware.laser.controller import LaserController


INPUTS = ("arm", "power", "prr", "watchdog_ms", "alive", "fault_clear", "marking",
          "interlock_open")
OUTPUTS = ("laser_power", "laser_latch", "laser_mo", "laser_am", "laser_prr", "faults",
           "mo_ready", "pulse")


class TamperedLaser(wiring.Component):
    def __init__(self, kind, **kwargs):
        self.kind = kind
        self.inner = LaserController(**kwargs)
        super().__init__(self.inner.signature)

    def elaborate(self, platform):
        m = Module()
        m.submodules.inner = inner = self.inner
        inputs = {name: getattr(self, name) for name in INPUTS}
        outputs = {name: getattr(inner, name) for name in OUTPUTS}

        if self.kind == "mo_ignores_interlock":
            # MO straight from its register, not through the interlock gate.
            outputs["laser_mo"] = inner._mo
        elif self.kind == "power_before_arm":
            # The power register on the pins whether armed or not.
            outputs["laser_power"] = self.power
        elif self.kind == "fault_clears_itself":
            # Faults cleared as soon as the interlock closes again, without a clear command.
            closed = Signal()
            m.d.sync += closed.eq(~self.interlock_open)
            inputs["fault_clear"] = self.fault_clear | closed
        else:
            raise ValueError(f"unknown fault {self.kind!r}")

        for name, value in inputs.items():
            m.d.comb += getattr(inner, name).eq(value)
        for name, value in outputs.items():
            m.d.comb += getattr(self, name).eq(value)
        return m


#: Each fault: how to build it, and the property it must break.
LASER_FAULTS = {
    "mo_ignores_interlock": "interlock open: no MO, no modulation, no PRR",
    "power_before_arm": "after reset all laser outputs low until armed",
    "fault_clears_itself": "a fault stays latched until cleared",
    "short_lead": "modulation only after MO has led for the lead time",
}
