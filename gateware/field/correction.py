"""Field-distortion correction: bilinear offsets from an n × n table on every point.

The arithmetic is defined, and documented, in :mod:`.correction_table`; this module is its
sequential implementation: one block RAM holding the table, one 16 × 16-bit multiplier with an
accumulator, fifteen clocks per point.
"""

from amaranth.hdl import Cat, Module, Mux, Signal, signed
from amaranth.lib import stream, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from ..points import FIELD_MAX, FieldPoint
from .correction_table import CorrectionTable


__all__ = ["FieldCorrection"]


class FieldCorrection(wiring.Component):
    """Adds the table's interpolated offset to each position, saturating at the field edges.

    A point is taken when the stage is idle and its output is empty or being taken, so, like the
    buffer it replaces, it holds one point and adds no frame of latency: the result is ready
    :attr:`CLOCKS` clocks after the point came in, long before the next frame boundary.

    The table is in block RAM, initialised from ``table`` and rewritten one node at a time
    through ``write_*``. A node's ``dx`` and ``dy`` are one RAM word, written in one clock, and
    writes are made only between points: every point is interpolated from one table, never from
    a half-written node or a table that changed while its corners were read.

    Parameters
    ----------
    table : :class:`CorrectionTable`
        What the RAM holds after configuration.

    Interface attributes
    --------------------
    positions_in : ``In(stream.Signature(FieldPoint))``
        Positions in galvo units.
    positions_out : ``Out(stream.Signature(FieldPoint))``
        Corrected positions for the PHY.
    enable : ``In(1)``
        1 = correct; 0 = pass positions unchanged (with the same timing). Sampled with each point.
    write_node : ``In(range(n * n))``; write_dx, write_dy : ``In(16)``
        Node ``iy × n + ix`` and its new offsets (two's complement galvo units).
    write_en : ``In(1)``
        A pulse asks for the write; it is made on that clock if no point is being made, else
        on the clock the point is done, within :attr:`CLOCKS` clocks. ``write_node``,
        ``write_dx`` and ``write_dy`` are taken on the clock of the pulse: the stage keeps its
        own copy while the write waits, so a register changed meanwhile (by the other link)
        does not reach the table. A pulse while a write waits is ignored: the register file
        refuses such a request (see ``write_pending``).
    write_pending : ``Out(1)``
        A write was asked for while a point was being made, and waits for it.
    clipped : ``Out(1)``
        High for one clock when a corrected point had to be clamped at the field edge.
    """

    #: Clocks from taking a point to presenting it (correction enabled). One more than the
    #: arithmetic needs: the RAM's read address is a register, loaded a clock ahead, so that the
    #: corner's address sum is not in series with the RAM's read-during-write check (the
    #: system's critical path when it was: 39 ns).
    CLOCKS = 16

    def __init__(self, table=None):
        self.table = CorrectionTable.identity() if table is None else table
        if not isinstance(self.table, CorrectionTable):
            raise TypeError(f"table must be a CorrectionTable, not {self.table!r}")
        nodes = self.table.n ** 2
        # Internal state the formal spec observes (formal/correction.py): a point is being
        # made; the table RAM is being written.
        self._busy = Signal()
        self._ram_write = Signal()
        self._ram_addr = Signal(range(nodes))
        self._ram_data = Signal(32)
        # The point's step (0 … 14 while busy), and a waiting write's node and offsets.
        self._step = Signal(range(16))
        self._held_node = Signal(range(nodes))
        self._held_data = Signal(32)
        super().__init__({
            "positions_in": In(stream.Signature(FieldPoint)),
            "positions_out": Out(stream.Signature(FieldPoint)),
            "enable": In(1),
            "write_node": In(range(nodes)),
            "write_dx": In(16),
            "write_dy": In(16),
            "write_en": In(1),
            "write_pending": Out(1),
            "clipped": Out(1),
        })

    # The two rules the formal spec checks, as methods, so that the tests can show that a stage
    # breaking either fails the proof (tests/support/broken_correction.py).

    def _may_take(self, busy, out_free):
        """A point is taken only between points, into a free output."""
        return ~busy & out_free

    def _may_write(self, busy):
        """The table is written only between points."""
        return ~busy

    def _write_value(self, pending, held, asked_now):
        """A waiting write stores what was asked for, not what the port shows now."""
        return Mux(pending, held, asked_now)

    def elaborate(self, platform):
        m = Module()
        n, s = self.table.n, self.table.shift
        whole, half = 1 << s, 1 << (s - 1)

        m.submodules.ram = ram = Memory(shape=32, depth=n * n, init=self.table.words())
        read = ram.read_port()                       # data the clock after the address
        write = ram.write_port()

        # --- one point at a time ------------------------------------------------------------
        x = Signal(16)
        y = Signal(16)
        busy = self._busy
        step = self._step
        take = self.positions_in.valid & self.positions_in.ready
        out_free = ~self.positions_out.valid | self.positions_out.ready
        m.d.comb += self.positions_in.ready.eq(self._may_take(busy, out_free))

        with m.If(self.positions_out.valid & self.positions_out.ready):
            m.d.sync += self.positions_out.valid.eq(0)

        # --- table writes, only between points ----------------------------------------------
        # Made at once when no point is being made, else kept until the point is done. (A point
        # taken on the clock of a write reads its corners afterwards: it sees the new node.)
        asked = self.write_pending | self.write_en
        m.d.sync += self.write_pending.eq(asked & busy)
        # The node and offsets of a write that waits, as they were when it was asked for.
        held_node, held_data = self._held_node, self._held_data
        with m.If(self.write_en & ~self.write_pending):
            m.d.sync += [held_node.eq(self.write_node),
                         held_data.eq(Cat(self.write_dx, self.write_dy))]
        m.d.comb += [
            write.addr.eq(self._write_value(self.write_pending, held_node, self.write_node)),
            write.data.eq(self._write_value(self.write_pending, held_data,
                                            Cat(self.write_dx, self.write_dy))),
            write.en.eq(asked & self._may_write(busy)),
            self._ram_write.eq(write.en),
            self._ram_addr.eq(write.addr),
            self._ram_data.eq(write.data),
        ]

        # --- addresses of the cell's corners --------------------------------------------------
        ix, fx = x[s:], x[:s]
        iy, fy = y[s:], y[:s]
        base = Signal(range(n * n))
        m.d.comb += base.eq((iy << (n - 1).bit_length() - 1) + iy + ix)     # iy × n + ix
        corner = {"00": base, "10": base + 1, "01": base + n, "11": base + n + 1}

        # --- the multiply-accumulate ----------------------------------------------------------
        # acc = a × w (first) or acc + a × w (second); rounded results go to top/bottom/result.
        operand = Signal(signed(16))
        weight = Signal(signed(16))
        accumulate = Signal()
        acc = Signal(signed(32))
        product = Signal(signed(32))
        m.d.comb += product.eq(operand * weight)
        # The first product of a pair starts from W/2 rather than 0, so that rounding is a plain
        # shift; yosys folds this multiply-add into the DSP block's own accumulator.
        with m.If(busy):
            m.d.sync += acc.eq(Mux(accumulate, acc, half) + product)
        rounded = Signal(signed(16))
        m.d.comb += rounded.eq(acc >> s)
        top = Signal(signed(16))
        bottom = Signal(signed(16))
        offset_x = Signal(signed(16))

        word_x = read.data[:16].as_signed()
        word_y = read.data[16:].as_signed()

        # The schedule: step -> (corner to read for the next step, operand, weight, first of a
        # pair?, where the rounded previous pair goes). The same for X (steps 1-6, reading the
        # low halves) and Y (steps 7-12, high halves).
        left, right = whole - fx, fx
        down, up = whole - fy, fy
        schedule = {
            0: ("00", None, None, None, None),
            1: ("10", word_x, left, True, None),
            2: ("01", word_x, right, False, None),
            3: ("11", word_x, left, True, top),
            4: (None, word_x, right, False, None),
            5: (None, top, down, True, bottom),
            6: ("00", bottom, up, False, None),
            7: ("10", word_y, left, True, offset_x),
            8: ("01", word_y, right, False, None),
            9: ("11", word_y, left, True, top),
            10: (None, word_y, right, False, None),
            11: (None, top, down, True, bottom),
            12: (None, bottom, up, False, None),
        }
        # Step 0 only loads the first corner's address; step k + 1 does the schedule's step k,
        # with the RAM reading the address loaded on the clock before.
        read_addr = Signal(range(n * n))
        m.d.comb += read.addr.eq(read_addr)
        with m.Switch(step):
            with m.Case(0):
                m.d.sync += read_addr.eq(corner[schedule[0][0]])
            for index, (_, source, w, first, store) in schedule.items():
                with m.Case(index + 1):
                    following = schedule.get(index + 1, (None,))[0]
                    if following is not None:
                        m.d.sync += read_addr.eq(corner[following])
                    if source is not None:
                        m.d.comb += [
                            operand.eq(source),
                            weight.eq(w),
                            accumulate.eq(~first),
                        ]
                    if store is not None:
                        m.d.sync += store.eq(rounded)

        # --- final sum and saturation ---------------------------------------------------------
        def saturate(position, offset):
            wide = Signal(signed(18))
            m.d.comb += wide.eq(position + offset)
            low, high = wide < 0, wide > FIELD_MAX
            return Mux(low, 0, Mux(high, FIELD_MAX, wide[:16])), low | high

        out_x, clip_x = saturate(x, offset_x)
        out_y, clip_y = saturate(y, rounded)

        # The point's own registers hold the result too: the output is (x, y) once valid.
        m.d.comb += [
            self.positions_out.payload.x.eq(x),
            self.positions_out.payload.y.eq(y),
        ]
        with m.If(take):
            m.d.sync += [
                x.eq(self.positions_in.payload.x),
                y.eq(self.positions_in.payload.y),
            ]
            with m.If(self.enable):
                m.d.sync += [busy.eq(1), step.eq(0)]
            with m.Else():
                m.d.sync += self.positions_out.valid.eq(1)
        with m.Elif(busy):
            m.d.sync += step.eq(step + 1)
            with m.If(step == 14):
                m.d.sync += [
                    busy.eq(0),
                    x.eq(out_x),
                    y.eq(out_y),
                    self.positions_out.valid.eq(1),
                ]
                m.d.comb += self.clipped.eq(clip_x | clip_y)

        return m
