"""Deliberately broken laser controllers, to show that the safety proof catches each fault."""

from amaranth.hdl import Module, Signal
from amaranth.lib import wiring

from galvoscan.gateware.laser.controller import LaserController


INPUTS = ("arm", "power", "prr", "watchdog_ms", "alive", "link_fault", "fault_clear",
          "marking", "interlock_open", "alarm", "guide", "head_fault")
OUTPUTS = ("laser_power", "laser_latch", "laser_mo", "laser_am", "laser_prr", "laser_enable",
           "faults", "mo_ready", "pulse", "laser_guide")


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
            # MO straight from its register, not through the enable gate.
            outputs["laser_mo"] = inner._mo
        elif self.kind == "power_before_arm":
            # The power register on the pins whether armed or not.
            outputs["laser_power"] = self.power
        elif self.kind == "watchdog_never_fires":
            # The watchdog is told of a frame on every clock.
            inputs["alive"] = 1
        elif self.kind == "mo_stays_on_after_watchdog":
            # Modulation stops on a watchdog fault, but MO and the PRR clock that were on
            # stay on until the fault is cleared.
            mo_q, stuck_q = Signal(), Signal()
            stuck = inner.faults.watchdog & (mo_q | stuck_q)
            m.d.sync += [mo_q.eq(inner.laser_mo), stuck_q.eq(stuck)]
            outputs["laser_mo"] = inner.laser_mo | stuck
            outputs["laser_prr"] = inner.laser_prr | stuck
        elif self.kind == "alarms_ignored":
            # The alarm inputs are not wired to the controller.
            inputs["alarm"] = 0
        elif self.kind == "head_ignored":
            # The head's fault is not wired to the controller.
            inputs["head_fault"] = 0
        elif self.kind == "head_fault_late":
            # The head's fault through a flip-flop, as if it were a pin: the outputs go off a
            # clock after it rises, not on the clock it does.
            late = Signal(init=1)
            m.d.sync += late.eq(self.head_fault)
            inputs["head_fault"] = late
        elif self.kind == "enable_ignores_faults":
            # The buffers' enable follows arm alone.
            outputs["laser_enable"] = self.arm
        elif self.kind == "fault_clears_itself":
            # Faults cleared as soon as the interlock closes again, without a clear command.
            closed = Signal()
            m.d.sync += closed.eq(~self.interlock_open)
            inputs["fault_clear"] = self.fault_clear | closed
        elif self.kind == "link_faults_ignored":
            # Refused frames are not wired to the controller.
            inputs["link_fault"] = 0
        elif self.kind == "guide_while_armed":
            # The guide laser follows its register, armed or not.
            outputs["laser_guide"] = self.guide
        else:
            raise ValueError(f"unknown fault {self.kind!r}")

        for name, value in inputs.items():
            m.d.comb += getattr(inner, name).eq(value)
        for name, value in outputs.items():
            m.d.comb += getattr(self, name).eq(value)
        return m


#: Each fault: how to build it, and the property it must break (or those it may break first:
#: the solver reports the shortest counterexample, whichever property that breaks).
LASER_FAULTS = {
    "mo_ignores_interlock": "laser_enable low: every laser output low",
    "power_before_arm": "after reset all laser outputs low until armed",
    "fault_clears_itself": "a fault stays latched until cleared",
    "short_lead": "modulation only after MO has led for the lead time",
    "watchdog_never_fires": "silence for the watchdog time while armed latches a fault",
    "link_faults_ignored": "a frame the link refused while armed latches a fault",
    "mo_stays_on_after_watchdog":
        "a latched fault keeps every laser output off until cleared and re-armed",
    # Unwired alarms: no alarm fault latches, and a fault is cleared while an alarm is on.
    "alarms_ignored": ("interlock open or alarm: every laser output low",
                       "laser_enable only while armed, no fault, interlock closed, no alarm",
                       "an alarm while armed latches a fault",
                       "a fault stays latched until cleared"),
    # An unwired head: a fault gates nothing and latches nothing.
    "head_ignored": ("a head fault: every laser output low",
                     "laser_enable only while armed, no fault, interlock closed, no alarm",
                     "a head fault while armed latches a fault"),
    # A clock late: the outputs stay on, and the fault latches, a clock after the head's.
    "head_fault_late": ("a head fault: every laser output low",
                        "laser_enable only while armed, no fault, interlock closed, no alarm",
                        "a head fault while armed latches a fault"),
    "enable_ignores_faults": "laser_enable only while armed, no fault, interlock closed, no "
                             "alarm",
    "guide_while_armed": "guide laser off while armed",
}
