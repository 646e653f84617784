"""Pulsed fiber laser over its DB25 port: power latch, MO, PRR and modulation, with interlocks
(Liao & Chen 2016's sequence; galvoscan's safety rules, README "How it is checked")."""

import math

from amaranth.hdl import Const, Module, Signal
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out


__all__ = ["LaserController", "PRR_UNIT_HZ", "Faults", "MAX_ALARMS", "clocks_at_least"]


#: The ``laser_prr`` register counts in steps of this many hertz.
PRR_UNIT_HZ = 100
#: Latched fault causes (:attr:`LaserController.faults`), bit 0 first.
Faults = data.StructLayout({
    "interlock": 1,     # the interlock opened while armed
    "watchdog": 1,      # no accepted command frame for the watchdog time while armed
    "alarm": 1,         # a laser alarm input was active while armed
    "link": 1,          # the host link refused a frame while armed (a damaged or lost frame)
    "head": 1,          # the scan head reported a fault (or none) while armed, with the check on
})

#: Most laser alarm inputs a controller takes (IPG's type-D interface has four alarm pins).
MAX_ALARMS = 4

# Phase accumulator width for the PRR clock.
_PHASE_BITS = 28


def clocks_at_least(seconds, clk_freq):
    """Whole clocks lasting at least ``seconds`` (and at least one)."""
    return max(1, math.ceil(round(seconds * clk_freq, 9)))


class LaserController(wiring.Component):
    """Liao & Chen's laser sequence, made safe.

    Emission needs, all at once: ``arm`` set, no latched fault, the interlock closed, and the
    master oscillator on for at least ``mo_lead`` seconds. Then modulation (the emission gate,
    DB25 pin 19) follows ``marking``. The sequence:

    1. **arm** rises (with no fault): the power goes onto pins 1-8 and, ``latch_setup`` later, a
       ``latch_pulse`` long pulse on pin 9 takes it; ``latch_setup`` of hold follows;
    2. **MO** (pin 18) goes high; the **PRR** clock (pin 20, 50 % duty) starts;
    3. after ``mo_lead`` (5 ms, as the paper), **modulation** follows ``marking``;
    4. **arm** falls: :attr:`laser_enable` falls and with it every laser output, on the same
       clock (as the buffers it enables do); the power register returns to 0.

    A power change while armed goes out through a new latch pulse; the power pins never change
    without one following.

    Safety: every laser output is gated by :attr:`laser_enable`, which is high only while
    ``arm`` is set, no fault is latched, the interlock is closed and no alarm input is active
    (the last two as seen through two synchroniser flip-flops), and after a fault only once
    ``arm`` has been seen low again. So ``laser_enable`` low means every laser output low, and
    whatever opens the gate also latches a fault if armed: an interlock opening or an alarm
    that reaches the outputs at all has passed the synchroniser, and the synchroniser's output
    is what latches the fault (a glitch too short to be sampled reaches nothing). The pins
    react within three clocks of the interlock opening (two synchroniser stages and the I/O
    flip-flop the board puts on every laser line: 250 ns at 12 MHz). No accepted command frame
    for ``watchdog_ms`` while armed latches a fault too, at most ``watchdog_ms`` ms and one
    clock after the last one. A fault drops ``laser_enable`` on the clock it is latched and
    stays latched until ``fault_clear`` is pulsed with the interlock closed and no alarm
    active; even then the laser stays off until ``arm`` has been seen low and set again. Reset
    switches everything off.

    Parameters
    ----------
    clk_freq : float
        System clock in Hz.
    mo_lead : float
        Seconds MO leads modulation (the laser's warm-up); 5 ms by default.
    latch_setup, latch_pulse : float
        Seconds the power pins are stable before the latch pulse (and held after it), and the
        latch pulse width. 1 µs each by default, well inside TTL lasers' needs (tens of ns).
    lookahead : int
        Clocks by which :attr:`pulse_ahead` leads the PRR clock's rising edges.
    alarms : int
        Laser alarm inputs, 0 … :data:`MAX_ALARMS`.
    head : bool
        Take the scan head's fault (:attr:`head_fault`): it gates the outputs and latches the
        ``head`` fault as the interlock does, from the clock it rises (it comes from the
        status receiver, in this clock domain: no synchroniser).

    Interface attributes
    --------------------
    arm : ``In(1)``
    power : ``In(8)``
        Power, 0 … 255 of full scale.
    prr : ``In(11)``
        Pulse repetition rate in units of :data:`PRR_UNIT_HZ` (checked by the register map).
    watchdog_ms : ``In(16)``
        Milliseconds without an accepted frame before a fault, while armed.
    link_fault : ``In(1)``
        Pulse: the host link refused a frame; while armed it latches a ``link`` fault.
    alive : ``In(1)``
        Pulses with each accepted command frame.
    fault_clear : ``In(1)``
        Pulse: clear latched faults if the interlock is closed.
    marking : ``In(1)``
        The scan wants emission now (running and marking, not jumping or parked).
    interlock_open : ``In(1)``
        The interlock pin, asynchronous; 1 = open (unsafe).
    alarm : ``In(alarms)``, when ``alarms`` > 0
        The laser's alarm outputs, asynchronous; 1 = alarm. They reset to 1 (and the board
        pulls them up), so an unconnected input reads as an alarm.
    head_fault : ``In(1, init=1)``, with ``head``
        The scan head is not fit to mark: with the head check on, its Temp OK or Power OK is
        low, or it is missing (the top's :class:`~..phy.xy2_status.XY2StatusReceiver`).
    laser_power : ``Out(8)``, laser_latch, laser_mo, laser_am, laser_prr : ``Out(1)``
        The DB25 signals (pins 1-8, 9, 18, 19, 20), for 5 V TTL buffers.
    laser_enable : ``Out(1)``
        Armed, no fault, interlock closed, no alarm: drives the output enable of those buffers
        (pulled down on the board, so the buffers are off before configuration). Every laser
        output is low while it is low.
    guide : ``In(1)``
        The host wants the guide (red pointer) laser on.
    laser_guide : ``Out(1)``
        The guide laser: ``guide`` while disarmed, off while ``arm`` is set (the pointer frames
        a job with the mirrors; it must not shine into a marking beam's path). Not gated by
        ``laser_enable``: it works with the marking laser off, which is its point.
    faults : ``Out(Faults)``
        Latched fault causes.
    mo_ready : ``Out(1)``
        MO has led long enough: modulation may follow ``marking``.
    pulse : ``Out(1)``
        One clock per laser pulse emitted (PRR rising edge while modulating).
    pulse_ahead : ``Out(1)``
        One clock ``lookahead`` clocks before each rising edge of the PRR clock, whether or not
        the laser is on: what pulse-synchronous position sources time their points by. Exact
        while ``prr`` is unchanged (the PRR clock is free-running and gated onto its pin).
    """

    def __init__(self, *, clk_freq, mo_lead=5e-3, latch_setup=1e-6, latch_pulse=1e-6,
                 lookahead=0, alarms=0, head=False):
        for name, value in (("mo_lead", mo_lead), ("latch_setup", latch_setup),
                            ("latch_pulse", latch_pulse)):
            if not value > 0:
                raise ValueError(f"{name} must be a positive time in seconds, not {value!r}")
        if not isinstance(lookahead, int) or lookahead < 0:
            raise ValueError(f"lookahead must be a whole number of clocks, not {lookahead!r}")
        if not isinstance(alarms, int) or isinstance(alarms, bool) or \
                not 0 <= alarms <= MAX_ALARMS:
            raise ValueError(f"alarms must be a whole number from 0 to {MAX_ALARMS}, not "
                             f"{alarms!r}")
        self.alarms = alarms
        self.head = bool(head)
        self.clk_freq = clk_freq
        self.lookahead = lookahead
        #: Clocks MO leads modulation (at least ``mo_lead``).
        self.lead_clocks = clocks_at_least(mo_lead, clk_freq)
        self.setup_clocks = clocks_at_least(latch_setup, clk_freq)
        self.pulse_clocks = clocks_at_least(latch_pulse, clk_freq)
        self.ms_clocks = round(clk_freq / 1000)
        members = {
            "arm": In(1),
            "power": In(8),
            "prr": In(11),
            "watchdog_ms": In(16),
            "alive": In(1),
            "link_fault": In(1),
            "fault_clear": In(1),
            "marking": In(1),
            "interlock_open": In(1, init=1),
            "guide": In(1),
        }
        if alarms:
            members["alarm"] = In(alarms, init=2 ** alarms - 1)
        if self.head:
            members["head_fault"] = In(1, init=1)
        members.update({
            "laser_power": Out(8),
            "laser_latch": Out(1),
            "laser_mo": Out(1),
            "laser_am": Out(1),
            "laser_prr": Out(1),
            "laser_enable": Out(1),
            "laser_guide": Out(1),
            "faults": Out(Faults),
            "mo_ready": Out(1),
            "pulse": Out(1),
            "pulse_ahead": Out(1),
        })
        super().__init__(members)
        # State the proofs refer to in their helper invariants (made here, not in elaborate,
        # so the proof harness can name them).
        self._mo = Signal()                 # MO, before the enable gate
        # Clocks of MO still to go before modulation may start on the next clock.
        self._lead_left = Signal(range(self.lead_clocks), init=self.lead_clocks - 1)
        # The watchdog: clocks into the current millisecond, milliseconds left.
        self._tick_ms = Signal(range(self.ms_clocks))
        self._ms_left = Signal(16)
        # After a fault (or an opening) arm must be seen low before the laser may start.
        self._rearm_needed = Signal()

    def elaborate(self, platform):
        m = Module()

        # The interlock and alarm pins through two synchroniser stages (FFSynchronizer's
        # structure, written out so that the proof can follow them). Only the second stage is
        # used: whatever gates the outputs is what latches the fault, so an opening cannot cut
        # the outputs without latching one (a glitch the first stage missed reaches nothing).
        interlock_meta = Signal(init=1)
        interlock_open = Signal(init=1)
        m.d.sync += [interlock_meta.eq(self.interlock_open), interlock_open.eq(interlock_meta)]
        if self.alarms:
            alarm_meta = Signal(self.alarms, init=2 ** self.alarms - 1)
            alarm_now = Signal(self.alarms, init=2 ** self.alarms - 1)
            m.d.sync += [alarm_meta.eq(self.alarm), alarm_now.eq(alarm_meta)]
            alarm_active = alarm_now.any()
        else:
            alarm_active = Const(0, 1)
        # The head's fault is the status receiver's, already in this clock domain: it acts as
        # the interlock does, with no synchroniser's delay.
        head_fault = self.head_fault if self.head else Const(0, 1)
        # Whatever gates the outputs now; each also latches its fault while armed.
        unsafe_now = interlock_open | alarm_active | head_fault

        # --- faults -------------------------------------------------------------------------
        watchdog_fired = Signal()
        faults = self.faults
        any_fault = faults.as_value().any()
        with m.If(self.fault_clear & ~unsafe_now):
            m.d.sync += faults.eq(0)
        # Opening the interlock while disarmed (to load a part) is no fault: nothing can emit
        # then, and arming needs it closed. Likewise an alarm while disarmed.
        with m.If(interlock_open & self.arm):
            m.d.sync += faults.interlock.eq(1)
        with m.If(watchdog_fired):
            m.d.sync += faults.watchdog.eq(1)
        # A frame refused while armed: one the host sent is lost (damaged, or out of step), so
        # what the laser does next is not what the host planned.
        with m.If(self.link_fault & self.arm):
            m.d.sync += faults.link.eq(1)
        if self.alarms:
            with m.If(alarm_active & self.arm):
                m.d.sync += faults.alarm.eq(1)
        if self.head:
            with m.If(head_fault & self.arm):
                m.d.sync += faults.head.eq(1)

        # After a fault, arm must be seen low before the laser may start again.
        rearm_needed = self._rearm_needed
        with m.If(any_fault | unsafe_now):
            m.d.sync += rearm_needed.eq(1)
        with m.Elif(~self.arm):
            m.d.sync += rearm_needed.eq(0)

        enabled = Signal()
        m.d.comb += enabled.eq(self.arm & ~any_fault & ~unsafe_now & ~rearm_needed)

        # --- watchdog -----------------------------------------------------------------------
        tick_ms, ms_left = self._tick_ms, self._ms_left
        with m.If(self.alive | ~self.arm):
            m.d.sync += [tick_ms.eq(0), ms_left.eq(self.watchdog_ms)]
        with m.Elif(tick_ms == self.ms_clocks - 1):
            m.d.sync += tick_ms.eq(0)
            with m.If(ms_left != 0):
                m.d.sync += ms_left.eq(ms_left - 1)
        with m.Else():
            m.d.sync += tick_ms.eq(tick_ms + 1)
        m.d.comb += watchdog_fired.eq(self.arm & (ms_left == 0) & ~self.alive)

        # --- power latch --------------------------------------------------------------------
        # The power on the pins, and the value the laser last latched.
        latched = Signal(8)
        power = Signal(8)          # the power pins, before the enable gate
        latch = Signal()           # the latch pin, likewise
        latch_timer = Signal(range(2 * self.setup_clocks + self.pulse_clocks + 1))
        latching = latch_timer != 0
        power_latched = Signal()    # the laser holds the current power
        with m.If(~enabled):
            m.d.sync += [power.eq(0), latch_timer.eq(0), power_latched.eq(0), latch.eq(0)]
        with m.Elif(~latching & (~power_latched | (self.power != latched))):
            # New power: onto the pins now, latch pulse after the set-up time.
            m.d.sync += [
                power.eq(self.power),
                latched.eq(self.power),
                latch_timer.eq(2 * self.setup_clocks + self.pulse_clocks),
                power_latched.eq(0),
            ]
        with m.Elif(latching):
            m.d.sync += latch_timer.eq(latch_timer - 1)
            # Pulse high from set-up time on, for the pulse width; then the hold time.
            in_pulse = (latch_timer <= self.setup_clocks + self.pulse_clocks) & \
                       (latch_timer > self.setup_clocks)
            m.d.sync += latch.eq(in_pulse)
            with m.If(latch_timer == 1):
                m.d.sync += power_latched.eq(1)

        # --- master oscillator and lead time ---------------------------------------------------
        mo, lead_left = self._mo, self._lead_left
        with m.If(~enabled):
            # (The enable gate has already cut both on the pins.)
            m.d.sync += [mo.eq(0), lead_left.eq(self.lead_clocks - 1)]
        with m.Elif(power_latched | mo):
            m.d.sync += mo.eq(1)
            with m.If(mo & (lead_left != 0)):
                m.d.sync += lead_left.eq(lead_left - 1)
        m.d.comb += self.mo_ready.eq(mo & (lead_left == 0))

        # --- PRR clock: a phase accumulator, 50 % duty ---------------------------------------
        # With a lookahead it runs free, so that position sources can time points by the
        # pulses (through pulse_ahead) whether or not the laser is on; MO gates it onto the
        # pin. Its first high half after MO rises may then be short, but modulation is still
        # off then (MO lead).
        step = round(PRR_UNIT_HZ * 2 ** _PHASE_BITS / self.clk_freq)   # per unit of prr
        # The increment has a register of its own, so the multiply and the add do not share
        # a clock.
        increment = Signal(_PHASE_BITS)
        m.d.sync += increment.eq(self.prr * step)
        phase = Signal(_PHASE_BITS)
        if self.lookahead:
            m.d.sync += phase.eq(phase + increment)
            # The same phase `lookahead` clocks on: its rising edges lead the PRR clock's.
            # (lookahead + 1) × increment (one increment more because `ahead` is a register,
            # a clock behind the phase it is made from), as prr × a constant: on the UP5K two
            # DSP blocks rather than a hundred logic cells of shifted adds.
            # (From prr a clock late, so that it follows a new prr on the clock the increment
            # does.)
            prr_q = Signal.like(self.prr)
            ahead_offset = Signal(_PHASE_BITS)
            m.d.sync += [prr_q.eq(self.prr),
                         ahead_offset.eq(prr_q * (step * (self.lookahead + 1)))]
            ahead = Signal(_PHASE_BITS)
            m.d.sync += ahead.eq(phase + ahead_offset)     # = phase, lookahead clocks on
            ahead_q = Signal()
            m.d.sync += ahead_q.eq(ahead[-1])
            m.d.comb += self.pulse_ahead.eq(ahead[-1] & ~ahead_q)
        else:
            # Nobody times points by the pulses: the clock starts with MO, at phase 0.
            with m.If(mo):
                m.d.sync += phase.eq(phase + increment)
            with m.Else():
                m.d.sync += phase.eq(0)
        prr_clock = phase[-1]
        prr_q = Signal()
        m.d.sync += prr_q.eq(prr_clock)

        # --- outputs ------------------------------------------------------------------------
        am = Signal()       # modulation, before the enable gate
        m.d.sync += am.eq(self.mo_ready & enabled & self.marking)
        # Every output through the enable gate: off on the clock enable falls, whatever the
        # registers behind it still hold.
        m.d.comb += [
            self.laser_enable.eq(enabled),
            self.laser_power.eq(power & enabled.replicate(8)),
            self.laser_latch.eq(latch & enabled),
            self.laser_mo.eq(mo & enabled),
            self.laser_am.eq(am & enabled),
            self.laser_prr.eq(prr_clock & mo & enabled),
            self.pulse.eq(am & enabled & prr_clock & ~prr_q),
            # The guide laser is for framing with the marking laser off; never both.
            self.laser_guide.eq(self.guide & ~self.arm),
        ]
        return m
