"""The register file: state the host writes and reads, built from the register map."""

from amaranth.hdl import Cat, Const, Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from .regmap import RegisterMap, register_map


__all__ = ["RegisterBus", "RegisterFile"]


class RegisterBus(wiring.Signature):
    """One access a clock, from the command decoder's side, in two steps: an access is given
    (``address``, ``write_data``) on one clock and checked, and done on the next.

    Checking on one clock and writing on the next keeps the range checks (a 16-bit compare per
    register, behind the frame's address decode) off the paths into the registers and the
    vector queue: together they were the full build's longest path.

    Members
    -------
    address : ``Out(7)``
    write_data : ``Out(16)``
        The access, given on the clock its frame is taken.
    write_en : ``Out(1)``
        On the clock after: write the value given on the previous clock to the address given
        then; only done when ``write_ok``.
    write_ok : ``In(1)``
        On the clock after the access was given: its address is a writable register and its
        value is in the register's range, and (for a queue or a refusable strobe) the block it
        feeds can take it now.
    read_ok : ``In(1)``
        On the clock the access is given: ``address`` is a register.
    read_data : ``In(16)``
        Two clocks after the access was given: the register at its address, with every write
        given on an earlier clock done (read through a block RAM on the clock after the
        access, when an earlier access's write is done).
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
    an input ``<name>_ready`` too, and a write of 1 is refused while it is low). A queue
    register has ``<name>_push``, high for one clock per accepted write, while the output
    ``<name>`` holds the value pushed (and after it the last value written); ``<name>_ready``
    (an input) refuses writes while low, and ``<name>_refused`` is high for one clock for each
    write in range refused so.

    A write is taken only if its value lies in the register's range (and, for a register with
    choices, such as ``mode``, is one of them); registers the map leaves out are unknown
    addresses. An access is checked on the clock it is given and done on the next (see
    :class:`RegisterBus`); a read answers two clocks after the address: the registers that
    hold a value are read back from a copy in block RAM (two RAMs, whatever the map), the
    read-only ones from their inputs.

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
        fares better without the RAMs). Either way the value comes two clocks after the
        address.
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
                members[f"{reg.name}_refused"] = Out(1)
            elif reg.fixed:
                pass                # (its value is the map's: no port)
            else:
                members[reg.name] = In(reg.width)
        super().__init__(members)
        # The access being done (given on the clock before), made here so that proofs can
        # name the register a write goes to.
        self._write_address = Signal(7, name="write_address")
        self._write_data = Signal(16, name="write_data")

    def elaborate(self, platform):
        m = Module()
        bus = self.bus
        held = [reg for reg in self.regmap if reg.access in ("rw", "queue")]

        # --- checks: on the clock the access is given ----------------------------------------
        # Whether the address is writable and the value in range; what the blocks fed can take
        # is asked on the next clock, when the write is done.
        in_range = Signal()
        address, write_data = self._write_address, self._write_data
        m.d.sync += [address.eq(bus.address), write_data.eq(bus.write_data),
                     in_range.eq(0)]
        with m.Switch(bus.address):
            for reg in self.regmap:
                with m.Case(reg.address):
                    m.d.comb += bus.read_ok.eq(1)
                    if reg.access == "strobe":
                        m.d.sync += in_range.eq(bus.write_data <= reg.high)
                    elif reg.access in ("rw", "queue"):
                        data = bus.write_data.as_signed() if reg.signed else bus.write_data
                        ok = (data >= reg.low) & (data <= reg.high)
                        if reg.name in self.regmap.choices:
                            ok &= Cat(bus.write_data == v
                                      for v in self.regmap.choices[reg.name]).any()
                        m.d.sync += in_range.eq(ok)

        # --- writes: on the clock after -------------------------------------------------------
        # Written since the last reset, one bit per register that reads back what it holds.
        written = Signal(len(held))
        for reg in self.regmap:
            if reg.access == "strobe":
                m.d.sync += getattr(self, reg.name).eq(0)     # a pulse, unless written below
        with m.Switch(address):
            for reg in self.regmap:
                with m.Case(reg.address):
                    value = getattr(self, reg.name, None)     # (none: fixed)
                    if reg.access == "strobe":
                        # A write of 1 pulses the output on the next clock (from a flip-flop:
                        # a refusable strobe's readiness may depend on the strobe itself).
                        ok = in_range
                        if reg.refusable:
                            ok &= getattr(self, f"{reg.name}_ready") | (write_data == 0)
                        m.d.comb += bus.write_ok.eq(ok)
                        m.d.sync += value.eq(bus.write_en & ok & (write_data == 1))
                    elif reg.access in ("rw", "queue"):
                        ok = in_range
                        if reg.access == "queue":
                            # A full queue refuses the write: nothing is lost silently.
                            ready = getattr(self, f"{reg.name}_ready")
                            ok &= ready
                            m.d.comb += [
                                getattr(self, f"{reg.name}_push").eq(bus.write_en & ok),
                                getattr(self, f"{reg.name}_refused").eq(
                                    bus.write_en & in_range & ~ready),
                            ]
                        m.d.comb += bus.write_ok.eq(ok)
                        with m.If(bus.write_en & ok):
                            m.d.sync += written[held.index(reg)].eq(1)
                            if reg.access == "rw":
                                m.d.sync += value.eq(write_data)
        # What each register holds (a queue register's output is the value being pushed while
        # it is, and what it holds otherwise).
        holds = {}
        for reg in self.regmap:
            if reg.access == "queue":
                holds[reg.name] = stored = Signal(reg.width, init=reg.reset,
                                                  name=f"{reg.name}_stored")
                value = getattr(self, reg.name)
                m.d.comb += value.eq(Mux(getattr(self, f"{reg.name}_push"), write_data, stored))
                m.d.sync += stored.eq(value)
            elif reg.fixed:
                holds[reg.name] = Const(reg.reset, reg.width)
            elif reg.access != "strobe":
                holds[reg.name] = getattr(self, reg.name)

        if not self.read_back:
            return m

        # --- reads ----------------------------------------------------------------------------
        # Done on the clock after the access, with the writes: a read then sees the write of a
        # frame taken on the clock before it (the other link's). The value is chosen on that
        # clock and given on the next. A register that holds a value is read back from a copy
        # in block RAM, written with it (on the full build some 90 cells fewer than a
        # multiplexer over every register); until it is written after a reset (which the RAM
        # does not see) its reset value is read, from a second block RAM. Read-only registers,
        # and every register on a build without the RAMs, come through `direct`; a strobe or
        # an unknown address reads 0.
        from_ram = Signal()
        from_copy = Signal()
        direct = Signal(16)
        m.d.sync += [from_ram.eq(0), direct.eq(0)]
        if self.reads_from_ram:
            depth = 2 ** len(bus.address)
            m.submodules.copy = copy = Memory(shape=16, depth=depth, init=[0] * depth)
            resets = [0] * depth
            for reg in held + [reg for reg in self.regmap if reg.fixed]:
                resets[reg.address] = reg.encode(reg.reset)
            m.submodules.resets = reset_values = Memory(shape=16, depth=depth, init=resets)
            copy_write = copy.write_port()
            copy_read = copy.read_port()
            reset_read = reset_values.read_port()
            m.d.comb += [
                copy_write.addr.eq(address),
                copy_write.data.eq(write_data),
                copy_write.en.eq(bus.write_en & bus.write_ok),
                copy_read.addr.eq(address),
                reset_read.addr.eq(address),
            ]
        with m.Switch(address):
            for reg in self.regmap:
                with m.Case(reg.address):
                    if reg in held and self.reads_from_ram:
                        m.d.sync += [from_ram.eq(1),
                                     from_copy.eq(written[held.index(reg)])]
                    elif reg.fixed and self.reads_from_ram:
                        # (Never written: its value is the reset RAM's, at no cost in logic.)
                        m.d.sync += [from_ram.eq(1), from_copy.eq(0)]
                    elif reg.access != "strobe":
                        value = holds[reg.name]
                        m.d.sync += direct.eq(value.as_signed() if reg.signed else value)
        if self.reads_from_ram:
            m.d.comb += bus.read_data.eq(
                Mux(from_ram, Mux(from_copy, copy_read.data, reset_read.data), direct))
        else:
            m.d.comb += bus.read_data.eq(direct)
        return m
