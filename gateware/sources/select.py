"""Source select: the scan mode register picks which position source reaches the head."""

from amaranth.hdl import Const, Module
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out

from ..fields import Mode
from ..points import OffsetPoint


__all__ = ["SourceSelect"]


class SourceSelect(wiring.Component):
    """Hands the selected position source's points on; the other sources are stopped.

    Only the selected source runs, so a mode change always starts the new mode from its
    beginning (the spiral from ``x_first``/``y_first``, the raster from its first line) and the
    others keep nothing half done, except the vector queue, which is kept.

    Parameters
    ----------
    modes : iterable of :class:`~..host.regmap.Mode`
        The mode of each source, in the order of :attr:`sources`.

    Interface attributes
    --------------------
    mode : ``In(Mode)``
        The ``mode`` register.
    run : ``In(1)``
        The ``run`` register.
    sources : ``In(stream.Signature(OffsetPoint)).array(len(modes))``
        The sources' points.
    points : ``Out(stream.Signature(OffsetPoint))``
        The selected source's points, to the scale stage.
    source_run : ``Out(1).array(len(modes))``
        To each source's ``run``: high for the selected one while ``run`` is.
    selected : ``Out(1).array(len(modes))``
        Each source is the one selected (whether or not it runs).
    running : ``Out(1)``
        The selected source runs (the ``running`` status flag).
    """

    def __init__(self, modes):
        modes = tuple(modes)
        if not modes or not all(isinstance(mode, Mode) for mode in modes) or \
                len(set(modes)) != len(modes):
            raise ValueError(f"modes must be distinct Mode members, at least one, not {modes!r}")
        self.modes = modes
        super().__init__({
            "mode": In(Mode),
            "run": In(1),
            "sources": In(stream.Signature(OffsetPoint)).array(len(modes)),
            "points": Out(stream.Signature(OffsetPoint)),
            "source_run": Out(1).array(len(modes)),
            "selected": Out(1).array(len(modes)),
            "running": Out(1),
        })

    def elaborate(self, platform):
        m = Module()
        for index, (mode, source) in enumerate(zip(self.modes, self.sources)):
            # (A build of one mode: its mode register takes that one alone.)
            selected = self.mode == mode if len(self.modes) > 1 else Const(1)
            m.d.comb += [
                self.selected[index].eq(selected),
                self.source_run[index].eq(self.run & selected),
            ]
            with m.If(selected):
                m.d.comb += [
                    self.points.valid.eq(source.valid),
                    self.points.payload.eq(source.payload),
                    source.ready.eq(self.points.ready),
                    self.running.eq(self.run),
                ]
        return m
