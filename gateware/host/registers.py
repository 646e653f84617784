"""The register file: state the host writes and reads, built from the register map."""

from amaranth.hdl import Cat, Module
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .regmap import BY_NAME, REGISTERS


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
    """Every register of :data:`~.regmap.REGISTERS`.

    Writable registers are outputs named after them (``dwell``, ``amp_x``, …), set by writes
    on :attr:`bus` and reset to their reset values; read-only ones are inputs (``status``,
    ``errors``) that the bus reads; a strobe register is an output that is high for one clock
    after 1 is written to it (the clock after the write), and reads 0; a queue register is an output holding the last value
    written, with ``<name>_push`` high for one clock per accepted write and ``<name>_ready``
    (an input) refusing writes while low.

    Parameters
    ----------
    resets : dict of str to int
        Reset values that differ from the map's (the scan settings a build starts with).
    choices : dict of str to set of int
        Registers that take only some values of their range (the scan modes a build has).
    leave_out : iterable of str
        Registers this build does not have (those of scan modes left out): their addresses
        are unknown, so frames for them are refused and counted.
    highs : dict of str to int
        Upper limits tighter than the map's (the table size bounds the address ranges).
    """

    def __init__(self, *, resets=None, highs=None, choices=None, leave_out=()):
        self.resets = {r.name: r.reset for r in REGISTERS}
        self.highs = {r.name: r.high for r in REGISTERS}
        for name, value in (resets or {}).items():
            if name not in self.resets:
                raise ValueError(f"no register named {name!r}")
            reg = BY_NAME[name]
            if reg.access != "rw" or not reg.low <= value <= reg.high:
                raise ValueError(f"reset value {value!r} of {name} is outside {reg.low}…{reg.high}")
            self.resets[name] = value
        for name, value in (highs or {}).items():
            if name not in self.highs:
                raise ValueError(f"no register named {name!r}")
            self.highs[name] = min(self.highs[name], value)
        self.choices = {}
        for name, values in (choices or {}).items():
            if name not in self.highs:
                raise ValueError(f"no register named {name!r}")
            values = sorted(set(values))
            if not values or not all(BY_NAME[name].low <= v <= self.highs[name] for v in values):
                raise ValueError(f"choices for {name} must lie in its range, not {values!r}")
            self.choices[name] = values
        for name in leave_out:
            if name not in BY_NAME:
                raise ValueError(f"no register named {name!r}")
        #: The registers this build has.
        self.registers = [r for r in REGISTERS if r.name not in set(leave_out)]
        members = {"bus": In(RegisterBus())}
        for reg in self.registers:
            if reg.access == "rw":
                members[reg.name] = Out(reg.width, init=self.resets[reg.name])
            elif reg.access == "strobe":
                members[reg.name] = Out(reg.width)
            elif reg.access == "queue":
                members[reg.name] = Out(reg.width, init=self.resets[reg.name])
                members[f"{reg.name}_push"] = Out(1)
                members[f"{reg.name}_ready"] = In(1)
            else:
                members[reg.name] = In(reg.width)
        super().__init__(members)

    def elaborate(self, platform):
        m = Module()
        bus = self.bus
        for reg in self.registers:
            if reg.access == "strobe":
                m.d.sync += getattr(self, reg.name).eq(0)     # a pulse, unless written below
        with m.Switch(bus.address):
            for reg in self.registers:
                with m.Case(reg.address):
                    value = getattr(self, reg.name)
                    m.d.comb += bus.read_ok.eq(1)
                    if reg.access == "strobe":
                        # Reads 0 (read_data's default); a write of 1 pulses the output on
                        # the next clock (from a flip-flop: the decoder's checks stay off the
                        # paths into whatever the strobe acts on).
                        m.d.comb += bus.write_ok.eq(bus.write_data <= reg.high)
                        m.d.sync += value.eq(bus.write_en & (bus.write_data == 1))
                    else:
                        m.d.comb += bus.read_data.eq(value)
                    if reg.access in ("rw", "queue"):
                        in_range = (bus.write_data >= reg.low) & \
                                   (bus.write_data <= self.highs[reg.name])
                        if reg.name in self.choices:
                            in_range &= Cat(bus.write_data == v
                                            for v in self.choices[reg.name]).any()
                        if reg.access == "queue":
                            # A full queue refuses the write: nothing is lost silently.
                            in_range &= getattr(self, f"{reg.name}_ready")
                            m.d.comb += getattr(self, f"{reg.name}_push").eq(
                                bus.write_en & in_range)
                        m.d.comb += bus.write_ok.eq(in_range)
                        with m.If(bus.write_en & in_range):
                            m.d.sync += value.eq(bus.write_data)
        return m
