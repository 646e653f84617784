"""Laser safety, as properties of the DB25 pins (galvoscan's safety rules, README "How it is
checked")."""

from amaranth.asserts import AnySeq
from amaranth.hdl import Assert, ClockDomain, Cover, Elaboratable, Module, ResetSignal, Signal

from ..gateware.laser.controller import Faults


__all__ = ["LaserSafetySpec"]


class LaserSafetySpec(Elaboratable):
    """Safety of a laser controller, for every input sequence and every reset.

    All inputs (arm, power, PRR, watchdog time, accepted frames, fault clear, marking, the
    interlock pin) and the reset are free on every clock. Proved:

    * **interlock**: while the interlock pin is open, MO, modulation and the PRR clock are low;
    * **lead**: modulation is on only while MO is on and has been on for at least the lead time;
    * **reset**: after reset every laser output (power pins, latch, MO, modulation, PRR) stays
      low until ``arm`` has been set;
    * **faults**: a latched fault stays latched until ``fault_clear`` is pulsed while the
      interlock is closed (as seen through two synchroniser clocks) or the system is reset;
      and once a fault is latched, modulation is off from the next clock on.

    Parameters
    ----------
    controller : a :class:`~galvoscan.gateware.laser.controller.LaserController` (or a broken one)
    lead_clocks : int
        The lead the spec demands, in clocks.
    """

    def __init__(self, controller, *, lead_clocks):
        self.controller = controller
        self.lead_clocks = lead_clocks

    def elaborate(self, platform):
        m = Module()
        m.domains.sync = ClockDomain()
        m.submodules.dut = dut = self.controller
        m.d.comb += ResetSignal("sync").eq(AnySeq(1))
        for name in ("arm", "power", "prr", "watchdog_ms", "alive", "fault_clear", "marking",
                     "interlock_open"):
            port = getattr(dut, name)
            m.d.comb += port.eq(AnySeq(len(port)))

        mo, am, prr = dut.laser_mo, dut.laser_am, dut.laser_prr

        # --- interlock ----------------------------------------------------------------------
        m.d.comb += Assert(~dut.interlock_open | ~(mo | am | prr),
                           "interlock open: no MO, no modulation, no PRR")

        # --- lead ---------------------------------------------------------------------------
        mo_on_for = Signal(range(self.lead_clocks + 1))    # clocks MO has been on, before now
        with m.If(mo):
            with m.If(mo_on_for != self.lead_clocks):
                m.d.sync += mo_on_for.eq(mo_on_for + 1)
        with m.Else():
            m.d.sync += mo_on_for.eq(0)
        m.d.comb += Assert(~am | (mo & (mo_on_for == self.lead_clocks)),
                           "modulation only after MO has led for the lead time")

        # --- reset --------------------------------------------------------------------------
        armed_seen = Signal()
        with m.If(dut.arm):
            m.d.sync += armed_seen.eq(1)
        quiet = ~(mo | am | prr | dut.laser_latch) & (dut.laser_power == 0)
        m.d.comb += Assert(armed_seen | quiet, "after reset all laser outputs low until armed")

        # --- faults -------------------------------------------------------------------------
        interlock_d1 = Signal(init=1)
        interlock_d2 = Signal(init=1)
        m.d.sync += [interlock_d1.eq(dut.interlock_open), interlock_d2.eq(interlock_d1)]
        faults_q = Signal(Faults)
        cleared_q = Signal()
        m.d.sync += [faults_q.eq(dut.faults), cleared_q.eq(dut.fault_clear & ~interlock_d2)]
        for cause, _ in Faults:
            m.d.comb += Assert(~faults_q[cause] | dut.faults[cause] | cleared_q,
                               "a fault stays latched until cleared")
        m.d.comb += Assert(~faults_q.as_value().any() | ~am, "a latched fault stops modulation")

        # --- covers -------------------------------------------------------------------------
        emitted = Signal()
        with m.If(am):
            m.d.sync += emitted.eq(1)
        m.d.comb += [
            Cover(am & (dut.laser_power != 0), "modulation with power latched"),
            Cover(emitted & dut.faults.interlock & ~am,
                  "interlock opened after emission: fault latched, modulation off"),
            Cover(emitted & faults_q.as_value().any() & ~dut.faults.as_value().any(),
                  "a fault cleared after emission"),
            Cover(dut.pulse, "a laser pulse"),
        ]
        return m
