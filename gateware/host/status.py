"""The status word and event counters the host reads."""

from amaranth.hdl import Module
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from .regmap import Status


__all__ = ["StatusBlock", "STICKY_FLAGS", "COUNTER_BITS"]


#: Status flags that report an event since the last read of ``status``, not a state: set by
#: the event, cleared by the read, so a clamp between two reads is never missed.
STICKY_FLAGS = ("clipped",)

#: Bits of each counter: one register's worth.
COUNTER_BITS = 16


class StatusBlock(wiring.Component):
    """The ``status`` flags, the sticky ones among them, and event counters.

    Parameters
    ----------
    saturating : iterable of str
        Counters that stop at their largest value (a count that wrapped round would read as
        few events, where there were many): ``vec_rejected``, ``vec_underruns``, ….
    wrapping : iterable of str
        Counters that count modulo ``2 ** COUNTER_BITS`` (the host takes differences):
        ``pulses``.

    Interface attributes
    --------------------
    flags : ``In(Status)``
        Each flag as it is now; for :data:`STICKY_FLAGS`, the event (one clock is enough).
    status_read : ``In(1)``
        High for the clock ``status`` is read: the sticky flags clear after it (an event on the
        same clock keeps its flag set).
    status : ``Out(Status)``
        To the ``status`` register.
    events : ``In(StructLayout)``, one bit per counter
        High for one clock per event to count.
    counts : ``Out(StructLayout)``, ``COUNTER_BITS`` per counter
        To the registers of the same names.
    """

    def __init__(self, *, saturating=(), wrapping=()):
        saturating, wrapping = tuple(saturating), tuple(wrapping)
        names = saturating + wrapping
        if not all(isinstance(name, str) and name.isidentifier() for name in names) or \
                len(set(names)) != len(names):
            raise ValueError(f"counter names must be distinct identifiers, not {names!r}")
        self.saturating = saturating
        self.wrapping = wrapping
        members = {"flags": In(Status), "status_read": In(1), "status": Out(Status)}
        if names:
            members["events"] = In(data.StructLayout({name: 1 for name in names}))
            members["counts"] = Out(data.StructLayout({name: COUNTER_BITS for name in names}))
        super().__init__(members)

    def elaborate(self, platform):
        m = Module()
        for name, _ in Status:
            flag = self.flags[name]
            if name in STICKY_FLAGS:
                with m.If(flag):
                    m.d.sync += self.status[name].eq(1)
                with m.Elif(self.status_read):
                    m.d.sync += self.status[name].eq(0)
            else:
                m.d.comb += self.status[name].eq(flag)
        top = 2 ** COUNTER_BITS - 1
        for name in self.saturating:
            count = self.counts[name]
            with m.If(self.events[name] & (count != top)):
                m.d.sync += count.eq(count + 1)
        for name in self.wrapping:
            with m.If(self.events[name]):
                m.d.sync += self.counts[name].eq(self.counts[name] + 1)
        return m
