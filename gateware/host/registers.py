"""The register file: state the host writes and reads, built from the register map."""

from amaranth.hdl import Cat, Module
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .regmap import RegisterMap, register_map


__all__ = ["RegisterBus", "RegisterFile"]


class RegisterBus(wiring.Signature):
    """One access per clock, from the command decoder's side.

    Members
    -------
    address : ``Out(7)``
    write_data : ``Out(16)``
    write_en : ``Out(1)``
        Write ``write_data`` to ``address``; only done when ``write_ok``.
    write_ok : ``In(1)``
        ``address`` is a writable register and ``write_data`` is in its range.
    read_data : ``In(16)``
        The register at ``address``, now.
    read_ok : ``In(1)``
        ``address`` is a register.
    """

    def __init__(self):
        super().__init__({
            "address": Out(7),
            "write_data": Out(16),
            "write_en": Out(1),
            "write_ok": In(1),
            "read_data": In(16),
            "read_ok": In(1),
        })


class RegisterFile(wiring.Component):
    """Every register of one build's :class:`~.regmap.RegisterMap`.

    Writable registers are outputs named after them (``dwell``, ``amp_x``, …), set by writes
    on :attr:`bus` and reset to their reset values; read-only ones are inputs (``status``,
    ``errors``) that the bus reads; a strobe register is an output that is high for one clock
    after 1 is written to it (the clock after the write), and reads 0 (a ``refusable`` one has
    an input ``<name>_ready`` too, and a write of 1 is refused while it is low); a queue register is an
    output holding the last value written, with ``<name>_push`` high for one clock per accepted
    write and ``<name>_ready`` (an input) refusing writes while low.

    A write is taken only if its value lies in the register's range (and, for a register with
    choices, such as ``mode``, is one of them); registers the map leaves out are unknown
    addresses.

    Parameters
    ----------
    regmap : :class:`~.regmap.RegisterMap`
        The build's registers, ranges, resets and choices (default: :func:`~.regmap.register_map`
        with its defaults).
    """

    def __init__(self, regmap=None):
        regmap = register_map() if regmap is None else regmap
        if not isinstance(regmap, RegisterMap):
            raise TypeError(f"regmap must be a RegisterMap, not {regmap!r}")
        for name in regmap.choices:
            if name not in regmap:
                raise ValueError(f"choices for {name!r}, which the map does not have")
        #: The build's map.
        self.regmap = regmap
        members = {"bus": In(RegisterBus())}
        for reg in regmap:
            if reg.access == "rw":
                members[reg.name] = Out(reg.width, init=reg.reset)
            elif reg.access == "strobe":
                members[reg.name] = Out(reg.width)
                if reg.refusable:
                    members[f"{reg.name}_ready"] = In(1)
            elif reg.access == "queue":
                members[reg.name] = Out(reg.width, init=reg.reset)
                members[f"{reg.name}_push"] = Out(1)
                members[f"{reg.name}_ready"] = In(1)
            else:
                members[reg.name] = In(reg.width)
        super().__init__(members)

    def elaborate(self, platform):
        m = Module()
        bus = self.bus
        for reg in self.regmap:
            if reg.access == "strobe":
                m.d.sync += getattr(self, reg.name).eq(0)     # a pulse, unless written below
        with m.Switch(bus.address):
            for reg in self.regmap:
                with m.Case(reg.address):
                    value = getattr(self, reg.name)
                    m.d.comb += bus.read_ok.eq(1)
                    if reg.access == "strobe":
                        # Reads 0 (read_data's default); a write of 1 pulses the output on
                        # the next clock (from a flip-flop: the decoder's checks stay off the
                        # paths into whatever the strobe acts on).
                        ok = bus.write_data <= reg.high
                        if reg.refusable:
                            ok &= getattr(self, f"{reg.name}_ready") | (bus.write_data == 0)
                        m.d.comb += bus.write_ok.eq(ok)
                        m.d.sync += value.eq(bus.write_en & ok & (bus.write_data == 1))
                    else:
                        m.d.comb += bus.read_data.eq(value)
                    if reg.access in ("rw", "queue"):
                        in_range = (bus.write_data >= reg.low) & (bus.write_data <= reg.high)
                        if reg.name in self.regmap.choices:
                            in_range &= Cat(bus.write_data == v
                                            for v in self.regmap.choices[reg.name]).any()
                        if reg.access == "queue":
                            # A full queue refuses the write: nothing is lost silently.
                            in_range &= getattr(self, f"{reg.name}_ready")
                            m.d.comb += getattr(self, f"{reg.name}_push").eq(
                                bus.write_en & in_range)
                        m.d.comb += bus.write_ok.eq(in_range)
                        with m.If(bus.write_en & in_range):
                            m.d.sync += value.eq(bus.write_data)
        return m
