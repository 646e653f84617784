"""Laser safety, as properties of the DB25 pins and the buffers' enable (galvoscan's safety
rules, README "Safety")."""

from amaranth.asserts import AnySeq
from amaranth.hdl import (Assert, ClockDomain, Const, Cover, Elaboratable, Module, Mux,
                          ResetSignal, Signal)

from ..gateware.laser.controller import Faults


__all__ = ["LaserSafetySpec"]


class LaserSafetySpec(Elaboratable):
    """Safety of a laser controller, for every input sequence and every reset.

    All inputs (arm, power, PRR, watchdog time, accepted frames, fault clear, marking, the
    interlock and alarm pins) and the reset are free on every clock. The spec reads the pins as
    the design must: through two flip-flops ("seen" below). Proved:

    * **enable**: ``laser_enable`` is high only while ``arm`` is set, no fault is latched, the
      interlock is seen closed and no alarm is seen; while it is low, every laser output (power
      pins, latch, MO, modulation, PRR) is low;
    * **interlock, alarms**: while the interlock is seen open or an alarm is seen, every laser
      output is low; and if armed, the fault is latched on the next clock (so whatever cut the
      outputs also needs a clear and a re-arm);
    * **head**: while the head's fault is high (``head``), every laser output is low on that
      very clock; if armed, the ``head`` fault is latched on the next clock;
    * **link**: a frame the host link refused while armed latches the link fault on the next
      clock (and with it, below, every laser output off);
    * **watchdog**: armed with no sign of progress (``alive``: a segment queued, a keepalive,
      the player's next word; see :class:`~galvoscan.gateware.host.progress.ProgressFeed`,
      proved to be fed by nothing else) for the watchdog time (the value in force when the
      last sign came or arm was set) latches the watchdog fault at most that many
      milliseconds and one clock after it;
    * **faults**: a latched fault stays latched until ``fault_clear`` is pulsed while the
      interlock is seen closed and no alarm is seen (or the system is reset); from the clock a
      fault is latched, every laser output is low, and stays low until the fault is cleared and
      ``arm`` has been seen low;
    * **lead**: modulation is on only while MO is on and has been on for at least the lead time;
    * **reset**: after reset every laser output stays low until ``arm`` has been set.

    Parameters
    ----------
    controller : a :class:`~galvoscan.gateware.laser.controller.LaserController` (or a broken one)
    lead_clocks : int
        The lead the spec demands, in clocks.
    ms_clocks : int
        Clocks per millisecond of the watchdog.
    alarms : int
        Alarm inputs the controller has.
    head : bool
        The controller takes the scan head's fault (``head_fault``), which it must obey as it
        does the interlock, from the clock it rises (it is in the controller's clock domain).
    helpers : bool
        State the helper invariants (on the controller's counters). The broken controllers'
        checks leave them out, so that their counterexamples break the properties themselves.
    """

    def __init__(self, controller, *, lead_clocks, ms_clocks, alarms, head=False, helpers=True):
        self.helpers = helpers
        self.controller = controller
        self.lead_clocks = lead_clocks
        self.ms_clocks = ms_clocks
        self.alarms = alarms
        self.head = head

    def elaborate(self, platform):
        m = Module()
        m.domains.sync = ClockDomain()
        m.submodules.dut = dut = self.controller
        m.d.comb += ResetSignal("sync").eq(AnySeq(1))
        inputs = ["arm", "power", "prr", "watchdog_ms", "alive", "link_fault", "fault_clear",
                  "marking", "interlock_open", "guide"] + (["alarm"] if self.alarms else []) + (["head_fault"] if self.head else [])
        for name in inputs:
            port = getattr(dut, name)
            m.d.comb += port.eq(AnySeq(len(port)))

        mo, am, prr, enable = dut.laser_mo, dut.laser_am, dut.laser_prr, dut.laser_enable
        quiet = ~(mo | am | prr | dut.laser_latch) & (dut.laser_power == 0)

        # The pins as the design may see them: two clocks late (reset to "unsafe").
        def seen(pin):
            ones = 2 ** len(pin) - 1
            first, second = Signal(len(pin), init=ones), Signal(len(pin), init=ones)
            m.d.sync += [first.eq(pin), second.eq(first)]
            return second.any()
        interlock_seen = seen(dut.interlock_open)
        alarm_seen = seen(dut.alarm) if self.alarms else Const(0, 1)
        # The head's fault comes from the status receiver, in the design's clock domain: the
        # outputs must obey it on the clock it rises, with no synchroniser's delay.
        head_seen = dut.head_fault if self.head else Const(0, 1)

        # --- enable -------------------------------------------------------------------------
        m.d.comb += [
            Assert(~enable | (dut.arm & ~dut.faults.as_value().any() & ~interlock_seen &
                              ~alarm_seen & ~head_seen),
                   "laser_enable only while armed, no fault, interlock closed, no alarm"),
            Assert(enable | quiet, "laser_enable low: every laser output low"),
            # The pointer frames jobs with the marking laser off, never while it may fire.
            Assert(~dut.laser_guide | ~dut.arm, "guide laser off while armed"),
        ]

        # --- interlock and alarms -----------------------------------------------------------
        m.d.comb += Assert(~(interlock_seen | alarm_seen) | quiet,
                           "interlock open or alarm: every laser output low")
        if self.head:
            m.d.comb += Assert(~head_seen | quiet, "a head fault: every laser output low")
            head_due = Signal()
            m.d.sync += head_due.eq(head_seen & dut.arm)
            m.d.comb += Assert(~head_due | dut.faults.head,
                               "a head fault while armed latches a fault")
        interlock_due, alarm_due = Signal(), Signal()
        m.d.sync += [interlock_due.eq(interlock_seen & dut.arm),
                     alarm_due.eq(alarm_seen & dut.arm)]
        m.d.comb += Assert(~interlock_due | dut.faults.interlock,
                           "an interlock opening while armed latches a fault")
        if self.alarms:
            m.d.comb += Assert(~alarm_due | dut.faults.alarm,
                               "an alarm while armed latches a fault")

        # --- faults -------------------------------------------------------------------------
        faults_q = Signal(Faults)
        cleared_q = Signal()
        m.d.sync += [faults_q.eq(dut.faults),
                     cleared_q.eq(dut.fault_clear & ~interlock_seen & ~alarm_seen & ~head_seen)]
        for cause, _ in Faults:
            m.d.comb += Assert(~faults_q[cause] | dut.faults[cause] | cleared_q,
                               "a fault stays latched until cleared")
        link_due = Signal()
        m.d.sync += link_due.eq(dut.link_fault & dut.arm)
        m.d.comb += Assert(~link_due | dut.faults.link | cleared_q,
                           "a frame the link refused while armed latches a fault")
        any_fault = dut.faults.as_value().any()
        # From a fault on, off until cleared and arm seen low.
        off_owed = Signal()
        with m.If(any_fault):
            m.d.sync += off_owed.eq(1)
        with m.Elif(~dut.arm):
            m.d.sync += off_owed.eq(0)
        m.d.comb += Assert(
            ~(any_fault | off_owed) | (quiet & ~enable),
            "a latched fault keeps every laser output off until cleared and re-armed")

        # --- watchdog -----------------------------------------------------------------------
        # Clocks since the last accepted frame (or disarmed clock), and the watchdog time then.
        limit = (2 ** len(dut.watchdog_ms) - 1) * self.ms_clocks + 1
        silent = Signal(range(limit + 1))
        silent_ms = Signal.like(dut.watchdog_ms)
        with m.If(dut.alive | ~dut.arm):
            m.d.sync += [silent.eq(0), silent_ms.eq(dut.watchdog_ms)]
        with m.Elif(silent != limit):
            m.d.sync += silent.eq(silent + 1)
        timeout = silent_ms * self.ms_clocks
        m.d.comb += Assert(~(silent > timeout) | dut.faults.watchdog | cleared_q,
                           "silence for the watchdog time while armed latches a fault")
        if self.helpers:
            # Helper invariants (proved too): the watchdog's counters follow the silence.
            with m.If(silent <= timeout):
                m.d.comb += [
                    Assert(dut._tick_ms == silent % self.ms_clocks, "helper: watchdog tick"),
                    Assert(dut._ms_left == silent_ms - silent // self.ms_clocks,
                           "helper: watchdog milliseconds left"),
                ]
            with m.Else():
                m.d.comb += Assert(dut._ms_left == 0, "helper: watchdog expired")
            m.d.comb += Assert(~off_owed | dut._rearm_needed, "helper: re-arm owed")

        # --- lead ---------------------------------------------------------------------------
        mo_on_for = Signal(range(self.lead_clocks + 1))    # clocks MO has been on, before now
        with m.If(mo):
            with m.If(mo_on_for != self.lead_clocks):
                m.d.sync += mo_on_for.eq(mo_on_for + 1)
        with m.Else():
            m.d.sync += mo_on_for.eq(0)
        m.d.comb += Assert(~am | (mo & (mo_on_for == self.lead_clocks)),
                           "modulation only after MO has led for the lead time")
        if self.helpers:
            # Helper invariant (proved too): the controller's lead counter counts down as the
            # spec counts up, so the induction need not look back over the whole lead.
            lead = self.lead_clocks
            m.d.comb += Assert(
                ~mo | Mux(mo_on_for >= lead - 1, dut._lead_left == 0,
                          dut._lead_left + mo_on_for == lead - 1),
                "helper: the lead counters agree")

        # --- reset --------------------------------------------------------------------------
        armed_seen = Signal()
        with m.If(dut.arm):
            m.d.sync += armed_seen.eq(1)
        m.d.comb += Assert(armed_seen | quiet, "after reset all laser outputs low until armed")

        # --- covers -------------------------------------------------------------------------
        emitted = Signal()
        with m.If(am):
            m.d.sync += emitted.eq(1)
        m.d.comb += [
            Cover(am & (dut.laser_power != 0), "modulation with power latched"),
            Cover(emitted & dut.faults.interlock & ~am,
                  "interlock opened after emission: fault latched, modulation off"),
            Cover(emitted & dut.faults.watchdog & ~faults_q.watchdog,
                  "the watchdog fires after emission"),
            Cover(emitted & faults_q.as_value().any() & ~dut.faults.as_value().any(),
                  "a fault cleared after emission"),
            Cover(dut.pulse, "a laser pulse"),
            Cover(emitted & dut.laser_guide, "the guide laser on after emission"),
        ]
        if self.alarms:
            m.d.comb += Cover(emitted & dut.faults.alarm & ~faults_q.alarm,
                              "an alarm after emission")
        m.d.comb += Cover(emitted & dut.faults.link & ~faults_q.link,
                          "a refused frame after emission")
        if self.head:
            m.d.comb += Cover(emitted & dut.faults.head & ~faults_q.head,
                              "a head fault after emission")
        return m
