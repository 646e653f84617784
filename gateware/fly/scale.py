"""The fly offset: where the belt has carried the part, in galvo units, from an encoder's
count.

RTC5/RTC6's ``set_fly_x/y`` scale is in bits per count; every 10 µs the board adds scale ×
count to the position, after wobble and before the field correction. Here the product is made
by shift-and-add, one scale bit a clock, the two axes in turn: the UP5K has no DSP block to
spare (its eight multiply the spiral's amplitude and the correction), and the offset is wanted
once a frame (120 clocks at 12 MHz), not every clock.
"""

from amaranth.hdl import Cat, Const, Module, Mux, Signal, signed
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .encoder import COUNT_BITS


__all__ = ["SCALE_BITS", "SCALE_FRACTION", "OFFSET_BITS", "OFFSET_LIMIT", "FlyScale",
           "fly_offset"]


#: Bits of a fly scale: signed, in galvo units per count.
SCALE_BITS = 24
#: Of which fraction bits: a scale of 1.0 unit a count is ``1 << 16``. Fine enough for 0.001 mm
#: a count on a 110 mm field (0.596 units: 39,045 steps of 2^-16), to 13 µm after 1 m of belt.
SCALE_FRACTION = 16
#: Bits of an offset: signed galvo units.
OFFSET_BITS = 18
#: The largest offset either way: past a whole field (65,535 units) a point is off it whatever
#: its position, so larger products stop here rather than wrap.
OFFSET_LIMIT = 2 ** (OFFSET_BITS - 1) - 1


def fly_offset(count, scale):
    """The offset (galvo units) the stage gives for ``count`` and ``scale`` (both integers, the
    scale in 2^-16 units a count): the product rounded down, held within ±:data:`OFFSET_LIMIT`."""
    return max(-OFFSET_LIMIT, min(OFFSET_LIMIT, (count * scale) >> SCALE_FRACTION))


class FlyScale(wiring.Component):
    """Each axis's fly offset, ``floor(count × scale / 2^16)``, held within
    ±:data:`OFFSET_LIMIT` (never wrapped), made again and again from the counts and scales of
    the moment.

    The product is made by shift-and-add with a right-shifting partial product (Booth-free:
    the scale's top bit weighs −2^23), one scale bit a clock: an axis takes
    :attr:`CLOCKS_PER_AXIS` clocks, and both offsets are renewed every
    ``2 × CLOCKS_PER_AXIS`` clocks. The count and scale are sampled when an axis starts, and
    the offset changes all at once when it ends.

    Interface attributes
    --------------------
    count_x, count_y : ``In(signed(32))``
        The encoders' counts.
    scale_x, scale_y : ``In(signed(24))``
        Galvo units a count, 16 fraction bits (``1 << 16`` = one unit a count).
    enable : ``In(1)``
        While low the offsets are 0 (``fly_return``), from the next clock.
    offset_x, offset_y : ``Out(signed(18))``
        Galvo units.
    renewed : ``Out(1)``
        High for one clock when the Y offset (the second) has been renewed.
    """

    #: Clocks to make one axis's offset: a scale bit each, and one to take the inputs.
    CLOCKS_PER_AXIS = SCALE_BITS + 1

    def __init__(self):
        super().__init__({
            "count_x": In(signed(COUNT_BITS)), "count_y": In(signed(COUNT_BITS)),
            "scale_x": In(signed(SCALE_BITS)), "scale_y": In(signed(SCALE_BITS)),
            "enable": In(1),
            "offset_x": Out(signed(OFFSET_BITS)), "offset_y": Out(signed(OFFSET_BITS)),
            "renewed": Out(1),
        })

    def elaborate(self, platform):
        m = Module()
        axis = Signal()                                 # 0: X, 1: Y
        step = Signal(range(SCALE_BITS + 1))            # 0: take the inputs; k + 1: bit k
        count = Signal(signed(COUNT_BITS))
        scale = Signal(SCALE_BITS)                      # its bits, the top one's weight negative
        # The partial product, shifted right a bit a clock: |partial| < |count| after each shift,
        # so before it (one count added) two more bits than the count hold it.
        partial = Signal(signed(COUNT_BITS + 2))
        # The last bits shifted out (the newest on top): the top seven, with the last step's
        # own, are the offset's low bits; those before them are the fraction it drops.
        shifted = Signal(SCALE_BITS - SCALE_FRACTION)

        m.d.sync += self.renewed.eq(0)
        with m.If(step == 0):
            m.d.sync += [
                count.eq(Mux(axis, self.count_y, self.count_x)),
                scale.eq(Mux(axis, self.scale_y, self.scale_x)),
                partial.eq(0),
                step.eq(1),
            ]
        with m.Else():
            bit = scale[0]
            last = step == SCALE_BITS
            added = Signal(signed(COUNT_BITS + 2))
            with m.If(~bit):
                m.d.comb += added.eq(partial)
            with m.Elif(last):
                m.d.comb += added.eq(partial - count)   # the sign bit's weight is −2^23
            with m.Else():
                m.d.comb += added.eq(partial + count)
            m.d.sync += [
                scale.eq(scale >> 1),
                partial.eq(added >> 1),
                shifted.eq(Cat(shifted[1:], added[0])),
                step.eq(Mux(last, 0, step + 1)),
            ]
            with m.If(last):
                # product = added × 2^23 + (the 23 bits shifted out before, the first lowest);
                # the offset is floor(product / 2^16): added × 2^7 and the 7 of those bits shifted
                # out last.
                product_high = Signal(signed(COUNT_BITS + 2 + SCALE_BITS - SCALE_FRACTION))
                m.d.comb += product_high.eq(Cat(shifted[1:], added[0], added[1:]).as_signed())
                limit = Const(OFFSET_LIMIT, signed(OFFSET_BITS))
                held = Mux(product_high > OFFSET_LIMIT, limit,
                           Mux(product_high < -OFFSET_LIMIT, -limit, product_high))
                m.d.sync += axis.eq(~axis)
                with m.If(axis):
                    m.d.sync += [self.offset_y.eq(held), self.renewed.eq(1)]
                with m.Else():
                    m.d.sync += self.offset_x.eq(held)
        with m.If(~self.enable):
            m.d.sync += [self.offset_x.eq(0), self.offset_y.eq(0)]
        return m
