"""The register file: state the host writes and reads, built from the register map."""

from amaranth.hdl import Cat, Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.memory import Memory
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
        The register at ``address``: what it held on the clock ``address`` was given, on the
        clock after (read through a block RAM).
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
    addresses. A read answers on the clock after the address: the registers that hold a value
    are read back from a copy in block RAM (two RAMs, whatever the map), the read-only ones
    from their inputs.

    Parameters
    ----------
    regmap : :class:`~.regmap.RegisterMap`
        The build's registers, ranges, resets and choices (default: :func:`~.regmap.register_map`
        with its defaults).
    read_back : bool
        Build the read path (default). Without it ``bus.read_data`` is left for the caller to
        drive: the command proofs drive it with any value at all, since none of their
        properties depends on a value read, and the read path's two memories would make every
        step of their search far slower (the read path is simulated against a model instead).
    reads_from_ram : bool
        Read the registers that hold a value back from the block RAM copy (default), or
        through a multiplexer (the smallest boards: few registers, and an HX1K whose placer
        fares better without the RAMs). Either way the value comes a clock after the address.
    """

    def __init__(self, regmap=None, *, read_back=True, reads_from_ram=True):
        regmap = register_map() if regmap is None else regmap
        self.read_back = bool(read_back)
        self.reads_from_ram = bool(reads_from_ram)
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
                # (A signed register holds its low bits, two's complement.)
                members[reg.name] = Out(reg.width, init=reg.encode(reg.reset) % 2 ** reg.width)
            elif reg.access == "strobe":
                members[reg.name] = Out(reg.width)
                if reg.refusable:
                    members[f"{reg.name}_ready"] = In(1)
            elif reg.access == "queue":
                members[reg.name] = Out(reg.width, init=reg.encode(reg.reset) % 2 ** reg.width)
                members[f"{reg.name}_push"] = Out(1)
                members[f"{reg.name}_ready"] = In(1)
            else:
                members[reg.name] = In(reg.width)
        super().__init__(members)

    def elaborate(self, platform):
        m = Module()
        bus = self.bus
        held = [reg for reg in self.regmap if reg.access in ("rw", "queue")]

        # --- writes -------------------------------------------------------------------------
        # Written since the last reset, one bit per register that reads back what it holds.
        written = Signal(len(held))
        for reg in self.regmap:
            if reg.access == "strobe":
                m.d.sync += getattr(self, reg.name).eq(0)     # a pulse, unless written below
        with m.Switch(bus.address):
            for reg in self.regmap:
                with m.Case(reg.address):
                    value = getattr(self, reg.name)
                    m.d.comb += bus.read_ok.eq(1)
                    if reg.access == "strobe":
                        # A write of 1 pulses the output on the next clock (from a flip-flop:
                        # the decoder's checks stay off the paths into whatever the strobe
                        # acts on).
                        ok = bus.write_data <= reg.high
                        if reg.refusable:
                            ok &= getattr(self, f"{reg.name}_ready") | (bus.write_data == 0)
                        m.d.comb += bus.write_ok.eq(ok)
                        m.d.sync += value.eq(bus.write_en & ok & (bus.write_data == 1))
                    if reg.access in ("rw", "queue"):
                        data = bus.write_data.as_signed() if reg.signed else bus.write_data
                        in_range = (data >= reg.low) & (data <= reg.high)
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
                            m.d.sync += [value.eq(bus.write_data),
                                         written[held.index(reg)].eq(1)]

        if not self.read_back:
            return m

        # --- reads --------------------------------------------------------------------------
        # The value read is chosen on the clock of the address and given on the next. A
        # register that holds a value is read back from a copy in block RAM, written with it
        # (on the full build some 90 cells fewer than a multiplexer over every register);
        # until it is written after a reset (which the RAM does not see) its reset value is
        # read, from a second block RAM. Read-only registers, and every register on a build
        # without the RAMs, come through `direct`; a strobe or an unknown address reads 0.
        from_ram = Signal()
        from_copy = Signal()
        direct = Signal(16)
        m.d.sync += [from_ram.eq(0), direct.eq(0)]
        if self.reads_from_ram:
            depth = 2 ** len(bus.address)
            m.submodules.copy = copy = Memory(shape=16, depth=depth, init=[0] * depth)
            resets = [0] * depth
            for reg in held:
                resets[reg.address] = reg.encode(reg.reset)
            m.submodules.resets = reset_values = Memory(shape=16, depth=depth, init=resets)
            copy_write = copy.write_port()
            copy_read = copy.read_port()
            reset_read = reset_values.read_port()
            m.d.comb += [
                copy_write.addr.eq(bus.address),
                copy_write.data.eq(bus.write_data),
                copy_read.addr.eq(bus.address),
                reset_read.addr.eq(bus.address),
            ]
        with m.Switch(bus.address):
            for reg in self.regmap:
                with m.Case(reg.address):
                    if reg in held and self.reads_from_ram:
                        m.d.comb += copy_write.en.eq(bus.write_en & bus.write_ok)
                        m.d.sync += [from_ram.eq(1),
                                     from_copy.eq(written[held.index(reg)])]
                    elif reg.access != "strobe":
                        value = getattr(self, reg.name)
                        m.d.sync += direct.eq(value.as_signed() if reg.signed else value)
        if self.reads_from_ram:
            m.d.comb += bus.read_data.eq(
                Mux(from_ram, Mux(from_copy, copy_read.data, reset_read.data), direct))
        else:
            m.d.comb += bus.read_data.eq(direct)
        return m
