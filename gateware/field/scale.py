"""Scale and offset: source offsets to galvo positions, saturating (SPEC §3, §4)."""

from amaranth.hdl import Module, Mux, Signal, signed
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

    Parameters
    ----------
    buffered : bool
        Hold the point in a register (True) or pass it straight through (False).

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

    def __init__(self, *, buffered=True):
        self.buffered = bool(buffered)
        super().__init__()

    def elaborate(self, platform):
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
