"""Scale and offset: source offsets to galvo positions, saturating: a point past the field
edge is clamped and flagged, never wrapped."""

from amaranth.hdl import Cat, Module, Mux, Signal, signed
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out

from ..points import FIELD_MAX, FieldPoint, OffsetPoint


__all__ = ["ScaleOffset", "AMP_ONE"]


#: The amplitude register value for a gain of 1.0: amplitudes are unsigned Q1.15.
AMP_ONE = 1 << 15


class ScaleOffset(wiring.Component):
    """Per-axis amplitude and centre, saturating at the field edges.

    For each axis ``position = clamp(center + floor(offset × amp / 32768), 0, 65535)``. A
    point that had to be clamped is still sent, at the field edge, and flagged on
    :attr:`clipped`: positions never wrap around.

    Buffered (the default), one point is held at a time: the stage takes a point when its output
    is empty or being taken, so it never adds a frame of latency to points paced by frame
    strobes. Unbuffered, it is combinational between two streams, for a following stage that
    holds the point instead (the distortion correction).

    With ``multiplier="serial"`` (for FPGAs without DSP blocks, such as the iCEstick's HX1K)
    the products are made by shift-and-add, one amplitude bit a clock, both axes at once: the
    point is presented 17 clocks after it was taken (a frame is at least 40), with the same
    results. Amplitude and centre are sampled when the point is taken.

    Parameters
    ----------
    buffered : bool
        Hold the point in a register (True) or pass it straight through (False; only with the
        DSP multiplier).
    multiplier : str
        ``"dsp"`` (a 16 × 16 product per axis, one iCE40 DSP each) or ``"serial"``.

    Interface attributes
    --------------------
    offsets : ``In(stream.Signature(OffsetPoint))``
        Points from a position source, signed, 0 = field centre.
    positions : ``Out(stream.Signature(FieldPoint))``
        Points in galvo units for the PHY.
    amp_x, amp_y : ``In(16)``
        Amplitude, unsigned Q1.15: 32768 = 1.0 (the table's full swing reaches the field edge),
        65535 ≈ 2.0. Sampled with each point.
    center_x, center_y : ``In(16)``
        Centre of the pattern in galvo units (32768 = field centre). Sampled with each point.
    clipped : ``Out(1)``
        High for one clock when a point is taken that had to be clamped on either axis.
    """

    offsets: In(stream.Signature(OffsetPoint))
    positions: Out(stream.Signature(FieldPoint))
    amp_x: In(16)
    amp_y: In(16)
    center_x: In(16)
    center_y: In(16)
    clipped: Out(1)

    #: Clocks from taking a point to presenting it, with the serial multiplier.
    SERIAL_CLOCKS = 17

    def __init__(self, *, buffered=True, multiplier="dsp"):
        if multiplier not in ("dsp", "serial"):
            raise ValueError(f"multiplier must be dsp or serial, not {multiplier!r}")
        if multiplier == "serial" and not buffered:
            raise ValueError("the serial multiplier holds its point: it is always buffered")
        self.buffered = bool(buffered)
        self.multiplier = multiplier
        super().__init__()

    def elaborate(self, platform):
        if self.multiplier == "serial":
            return self._elaborate_serial()
        m = Module()

        def scale(offset, amp, center):
            # A signed × unsigned 16 × 16-bit product: one iCE40 DSP, which takes the two
            # operands' signedness separately. The arithmetic shift rounds towards minus
            # infinity, like the formula.
            step = (offset * amp) >> 15
            wide = Signal(signed(19))
            m.d.comb += wide.eq(center + step)
            low, high = wide < 0, wide > FIELD_MAX
            return Mux(low, 0, Mux(high, FIELD_MAX, wide[:16])), low | high

        x, clip_x = scale(self.offsets.payload.x, self.amp_x, self.center_x)
        y, clip_y = scale(self.offsets.payload.y, self.amp_y, self.center_y)

        take = self.offsets.valid & self.offsets.ready
        if not self.buffered:
            m.d.comb += [
                self.positions.payload.x.eq(x),
                self.positions.payload.y.eq(y),
                self.positions.valid.eq(self.offsets.valid),
                self.offsets.ready.eq(self.positions.ready),
                self.clipped.eq(take & (clip_x | clip_y)),
            ]
            return m

        m.d.comb += [
            self.offsets.ready.eq(~self.positions.valid | self.positions.ready),
            self.clipped.eq(take & (clip_x | clip_y)),
        ]
        with m.If(take):
            m.d.sync += [
                self.positions.payload.x.eq(x),
                self.positions.payload.y.eq(y),
                self.positions.valid.eq(1),
            ]
        with m.Elif(self.positions.ready):
            m.d.sync += self.positions.valid.eq(0)

        return m

    def _elaborate_serial(self):
        m = Module()
        busy = Signal()
        steps = Signal(range(17))
        out_free = ~self.positions.valid | self.positions.ready
        take = self.offsets.valid & self.offsets.ready
        m.d.comb += self.offsets.ready.eq(~busy & out_free)
        with m.If(self.positions.valid & self.positions.ready):
            m.d.sync += self.positions.valid.eq(0)

        # Shift-and-add, high half first: each clock adds the offset to the upper part of the
        # product when the next amplitude bit is 1, and halves it; the bit that falls off the
        # bottom goes into the top of the amplitude register as its used bits leave at the
        # bottom. After 16 clocks the product is {high, bits}: its 17 bits above bit 15 are the
        # step (the arithmetic shift floors, as the formula).
        axes = []
        for axis in ("x", "y"):
            offset = Signal(signed(16), name=f"offset_{axis}")
            high = Signal(signed(18), name=f"high_{axis}")       # product >> 16 so far
            bits = Signal(16, name=f"bits_{axis}")     # amplitude bits left | product's low bits
            center = Signal(16, name=f"center_{axis}")
            total = Signal(signed(19), name=f"total_{axis}")
            m.d.comb += total.eq(high + Mux(bits[0], offset, 0))
            with m.If(take):
                m.d.sync += [
                    offset.eq(getattr(self.offsets.payload, axis)),
                    high.eq(0),
                    bits.eq(getattr(self, f"amp_{axis}")),
                    center.eq(getattr(self, f"center_{axis}")),
                ]
            with m.Elif(busy & (steps != 16)):
                m.d.sync += [high.eq(total >> 1), bits.eq(Cat(bits[1:], total[0]))]
            step = Cat(bits[15], high).as_signed()                # product >> 15
            wide = Signal(signed(19), name=f"wide_{axis}")
            m.d.comb += wide.eq(center + step)
            low, above = wide < 0, wide > FIELD_MAX
            axes.append((axis, Mux(low, 0, Mux(above, FIELD_MAX, wide[:16])), low | above))

        with m.If(take):
            m.d.sync += [busy.eq(1), steps.eq(0)]
        with m.Elif(busy):
            m.d.sync += steps.eq(steps + 1)
            with m.If(steps == 16):
                m.d.sync += [busy.eq(0), self.positions.valid.eq(1)]
                for axis, value, _ in axes:
                    m.d.sync += getattr(self.positions.payload, axis).eq(value)
                m.d.comb += self.clipped.eq(axes[0][2] | axes[1][2])
        return m
