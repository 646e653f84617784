"""Marking select: which scan mode's laser decision reaches the laser controller, and when.

Each mode decides differently whether the laser marks:

* the spiral marks while it runs, from its first point on (not while it parks the mirrors);
* the raster fill and vector mode decide each frame, and a frame's decision must reach the
  laser when that frame's point reaches the head: two frame strobes after it was made (into
  the scale stage's buffer, then onto the wires);
* vector mode with the RTC delays decides through :class:`~..sources.laser_delays.LaserDelays`
  instead, which moves the same two frames by the laser-on and laser-off delays.
"""

from amaranth.hdl import Cat, Module, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from ..fields import Mode


__all__ = ["MarkingSelect"]


class MarkingSelect(wiring.Component):
    """The ``marking`` input of the laser controller, from the selected mode's decision.

    Parameters
    ----------
    modes : iterable of :class:`~..fields.Mode`
        The scan modes built.
    vector_delays : bool
        Vector mode's decision comes through its delays (:attr:`vector_delayed`) rather than
        frame by frame.

    Interface attributes
    --------------------
    mode : ``In(Mode)``
        The ``mode`` register.
    frame_strobe : ``In(1)``
        One clock as the PHY starts a frame.
    spiral_selected, raster_selected, vector_selected : ``In(1)``, for the modes built
        The source select's: that mode's source is the one running.
    spiral_run : ``In(1)``; spiral_point : ``In(1)``, with the spiral
        The spiral sequencer runs; it hands a point on (valid and ready) this clock.
    raster_laser, vector_laser : ``In(1)``, for the modes decided frame by frame
        That source's laser decision for the frame it is making.
    vector_delayed : ``In(1)``, with the vector delays
        Vector mode's marking as its delays give it.
    marking : ``Out(1)``
        Whether the laser marks now.
    """

    def __init__(self, *, modes, vector_delays=False):
        self.modes = tuple(Mode.named(mode) for mode in modes)
        self.vector_delays = bool(vector_delays) and Mode.VECTOR in self.modes
        #: The modes whose laser is decided frame by frame.
        self.framed = tuple(mode for mode in (Mode.RASTER, Mode.VECTOR) if mode in self.modes
                            and not (mode == Mode.VECTOR and self.vector_delays))
        members = {"mode": In(Mode), "frame_strobe": In(1), "marking": Out(1)}
        for mode in self.modes:
            members[f"{mode.label}_selected"] = In(1)
        if Mode.SPIRAL in self.modes:
            members.update(spiral_run=In(1), spiral_point=In(1))
        for mode in self.framed:
            members[f"{mode.label}_laser"] = In(1)
        if self.vector_delays:
            members["vector_delayed"] = In(1)
        super().__init__(members)

    def elaborate(self, platform):
        m = Module()
        # (Later assignments take precedence: the spiral's, then the framed modes', then the
        # delayed vector mode's, each while its mode is the one selected.)
        if Mode.SPIRAL in self.modes:
            spiral_marking = Signal()
            with m.If(~self.spiral_run):
                m.d.sync += spiral_marking.eq(0)
            with m.Elif(self.spiral_point):
                m.d.sync += spiral_marking.eq(1)
            with m.If(self.spiral_selected):
                m.d.comb += self.marking.eq(spiral_marking)
        if self.framed:
            decided = Signal()
            frame_marking = Signal()
            with m.If(self.frame_strobe):
                m.d.sync += [
                    decided.eq(Cat(getattr(self, f"{mode.label}_selected") &
                                   getattr(self, f"{mode.label}_laser")
                                   for mode in self.framed).any()),
                    frame_marking.eq(decided),
                ]
            with m.If(self.mode != Mode.SPIRAL):
                m.d.comb += self.marking.eq(frame_marking)
        if self.vector_delays:
            with m.If(self.vector_selected):
                m.d.comb += self.marking.eq(self.vector_delayed)
        return m
