"""The preview of a marking job: marks, the jumps between them, the field and the drawing's box,
in field mm (matplotlib Figure objects on the Agg canvas: no pyplot state, no display).

Marks are drawn as wide as the spot that burns them, in millimetres, so the picture's darkness
is the dose: a photo's dithered cells, 50 µm apart, read as the picture they make, not as
lines of a width in points that would merge its light areas into dark ones."""

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import EllipseCollection, LineCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from ..geometry.speed import path_length_mm


__all__ = ["preview"]


def _jump_lines(paths):
    """The jumps: from the field centre to the first path, then from each path's end to the
    next one's start."""
    ends = [np.zeros(2)] + [p[-1] for p in paths[:-1]]
    return [np.array([end, p[0]]) for end, p in zip(ends, paths)]


class _SpotLines(LineCollection):
    """Marks as strokes the spot's diameter wide in the axes' millimetres, with round ends: a
    line swept by a round spot, exactly. Matplotlib strokes in points, so the width is worked
    out from the axes' scale when drawn, after the layout and the equal aspect have fixed
    it, for the panel it is in (each panel has its own scale). ``most_pt``: a width in
    points the stroke is never wider than (None: none)."""

    def __init__(self, segments, *, spot_mm, most_pt=None, **kwargs):
        kwargs.setdefault("capstyle", "round")
        super().__init__(segments, joinstyle="round", **kwargs)
        self._spot_mm = spot_mm
        self._most_pt = most_pt

    def draw(self, renderer):
        # Display units a millimetre across (pixels, or points in a vector file), and the
        # figure's dpi the same drawing's (savefig sets it): points = mm × that × 72 / dpi.
        per_mm = abs(self.axes.transData.transform([1.0, 0.0]) -
                     self.axes.transData.transform([0.0, 0.0]))[0]
        width = self._spot_mm * per_mm * 72 / self.figure.dpi
        self.set_linewidth(width if self._most_pt is None else min(width, self._most_pt))
        super().draw(renderer)


def _spot_dots(dots, spot_mm, colour, ax):
    """Marks of no length as filled discs of the spot's diameter, in data units (mm)."""
    return EllipseCollection(np.full(len(dots), spot_mm), np.full(len(dots), spot_mm),
                             np.zeros(len(dots)), units="xy", offsets=dots,
                             offset_transform=ax.transData, facecolors=colour,
                             edgecolors="none", linewidths=0, zorder=2)


#: The jumps' ink at most (their length times their width) as a share of the area they
#: cross, where they are densest: a drawing's few jumps stay hairlines, and a photo's,
#: one across its every light gap, are thinned to a fifth of a row (drawn dashed in grey,
#: they darken its light areas by some 5 % of black).
_JUMP_INK = 0.2


#: Pixels apart below which marked lines run together in a panel: there, a detail panel.
_MERGED_PX = 4
#: Lines across a detail panel (its side, in the lines' own spacing).
_DETAIL_LINES = 30


#: Cells a side of the grid the marks' density is taken on, for the detail panel.
_DENSITY_CELLS = 16


def _density(paths, bounds):
    """The length of ``paths`` in each cell of a grid of :data:`_DENSITY_CELLS` a side over
    ``bounds`` (mm per cell; what lies outside is counted in the edge cells), and the cells'
    side, mm."""
    x0, y0, x1, y1 = bounds
    cell = max(x1 - x0, y1 - y0, 1e-6) / _DENSITY_CELLS
    density = np.zeros((_DENSITY_CELLS, _DENSITY_CELLS))
    starts = np.concatenate([p[:-1] for p in paths if len(p) > 1] or [np.zeros((0, 2))])
    ends = np.concatenate([p[1:] for p in paths if len(p) > 1] or [np.zeros((0, 2))])
    lengths = np.hypot(*(ends - starts).T)
    # Each segment as samples a quarter of a cell apart, each carrying its share of length.
    count = np.maximum(1, np.ceil(lengths / (cell / 4))).astype(int)
    share = np.repeat(lengths / count, count)
    t = (np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count) + 0.5) / \
        np.repeat(count, count)
    samples = np.repeat(starts, count, axis=0) + t[:, None] * np.repeat(ends - starts, count,
                                                                          axis=0)
    column = np.clip(((samples[:, 0] - x0) / cell).astype(int), 0, _DENSITY_CELLS - 1)
    row = np.clip(((samples[:, 1] - y0) / cell).astype(int), 0, _DENSITY_CELLS - 1)
    np.add.at(density, (row, column), share)
    return density, cell


def _detail_window(paths, bounds, px_per_mm):
    """``(cx, cy, side)`` of a detail panel, mm, where the marks are too close together to
    tell apart at ``px_per_mm``: their spacing (a cell's area over the length marked in it)
    in the densest cell of a grid over the drawing under :data:`_MERGED_PX`; None where they
    are not."""
    x0, y0 = bounds[:2]
    density, cell = _density(paths, bounds)
    if not density.sum() > 0:
        return None
    r, c = np.unravel_index(np.argmax(density), density.shape)
    spacing = cell * cell / density[r, c]
    if not spacing * px_per_mm < _MERGED_PX:
        return None
    # On the marked point nearest the densest cell's centre, so the window holds marks.
    centre = np.array([x0 + (c + 0.5) * cell, y0 + (r + 0.5) * cell])
    points = np.concatenate(paths)
    cx, cy = points[np.argmin(np.hypot(*(points - centre).T))]
    return cx, cy, max(_DETAIL_LINES * spacing, 1e-3)


def preview(path, paths_mm, *, jumps=True, field_mm, spot_mm, title="", groups=None):
    """Write the picture of a job.

    Parameters
    ----------
    path : str or os.PathLike
        Output file; its suffix picks the format (``.png``, ``.svg``, ``.pdf`` …).
    paths_mm : sequence of array-like
        The paths in marking order, ``(n, 2)`` in field mm ((0, 0) the field centre, Y up).
    jumps : bool
        Draw the jumps as thin dashed grey lines.
    field_mm : float
        The field's size (the lens's): its square is outlined.
    spot_mm : float
        The laser spot's diameter, mm: marks are drawn this wide (a dot this across).
    title : str
        Above the picture.
    groups : sequence of (str, colour, paths), optional
        The marks in parts of their own colour (a job's layers): each ``(label, colour,
        paths)``, drawn in its colour and named in the legend; ``paths_mm`` then is all of
        them, in marking order, for the jumps.

    Returns
    -------
    mark_mm, jump_mm : float
        The lengths the legend gives.

    Raises
    ------
    ValueError
        When matplotlib cannot write the file (an unknown suffix, a folder that does not exist).
    """

    paths = [np.asarray(p, dtype=float).reshape(-1, 2) for p in paths_mm]
    paths = [p for p in paths if len(p)]
    mark_mm = path_length_mm(paths)
    jump_lines = _jump_lines(paths) if paths else []
    jump_mm = path_length_mm(jump_lines)
    half = field_mm / 2
    bounds = None
    if paths:
        points = np.concatenate(paths)
        bounds = (*points.min(axis=0), *points.max(axis=0))
    if groups is None:
        groups = [(f"marks {mark_mm:.1f} mm ({len(paths)} paths)", "black", paths)]
    else:
        groups = [(label, colour, [np.asarray(p, dtype=float).reshape(-1, 2) for p in part])
                  for label, colour, part in groups]
    # A drawing much smaller than the field gets a second panel, zoomed in on it; marks too
    # close together to tell apart there (a fine hatch) a third, on a detail of them.
    size = max(bounds[2] - bounds[0], bounds[3] - bounds[1]) if bounds else field_mm
    zoom = bounds is not None and size < field_mm * 0.8
    panel_px = 5.3 * 110                            # a panel's width, about, in pixels
    detail = _detail_window(paths, bounds, panel_px / (size * 1.15 if zoom else field_mm)) \
        if bounds is not None else None
    # The jumps' width: their ink a share of the cell they are densest in.
    jump_width_mm = 0.0
    if jump_mm > 0:
        density, cell = _density(jump_lines, bounds)
        jump_width_mm = _JUMP_INK * cell * cell / density.max()
    count = 1 + zoom + (detail is not None)
    figure = Figure(figsize=(6.2 * count, 7.4) if count > 1 else (7, 7.6), dpi=110,
                    layout="constrained")
    FigureCanvasAgg(figure)
    axes = list(figure.subplots(1, count)) if count > 1 else [figure.add_subplot()]
    kinds = ["field"] + (["zoom"] if zoom else []) + (["detail"] if detail else [])
    handles = []
    for index, (ax, kind) in enumerate(zip(axes, kinds)):
        first = index == 0

        def keep(handle):
            if first:
                handles.append(handle)
        ax.plot([-half, half, half, -half, -half], [-half, -half, half, half, -half],
                color="0.35", linewidth=0.8, linestyle="-.")
        # (Grey, dash-dotted: a layer's colour may be any, red too.)
        keep(Line2D([], [], color="0.35", linewidth=0.8, linestyle="-.",
                    label=f"field {field_mm:g} mm"))
        if jumps and jump_lines:
            # Under the marks: a jump is where the laser is off, the marks are what matters.
            # A hairline, but never so wide that the jumps' ink passes a share of the square
            # the drawing spans: a photo's jumps cross its every light gap, and even a
            # spot wide they would grey the light areas as the marks do the dark.
            ax.add_collection(_SpotLines(jump_lines, spot_mm=jump_width_mm, most_pt=0.5,
                                         colors="0.55", linestyles=(0, (4, 3)),
                                         capstyle="butt", zorder=1, snap=False))
            keep(Line2D([], [], color="0.55", linewidth=0.5, linestyle=(0, (4, 3)),
                        label=f"jumps {jump_mm:.1f} mm"))
        if paths:
            for label, colour, part in groups:
                # Not snapped to pixels: a photo's lines are finer than a pixel of a panel,
                # and snapped they would pile onto whole pixel rows.
                # A dot (a mark of no length: a code's module, a photo's lone pixel) as the
                # spot's disc (a stroke of no length draws nothing).
                still = [not np.ptp(p, axis=0).any() for p in part]
                ax.add_collection(_SpotLines([p for p, s in zip(part, still) if not s],
                                             spot_mm=spot_mm, colors=colour, zorder=2,
                                             snap=False))
                dots = np.array([p[0] for p, s in zip(part, still) if s])
                if len(dots):
                    ax.add_collection(_spot_dots(dots, spot_mm, colour, ax))
                    label += f", {len(dots)} dots"
                if kind == "detail":
                    # The detail is where the marks are too close to tell apart: there, each
                    # mark's path as a hairline over its spot-wide stroke, so the lines can
                    # be counted where their spots run together.
                    ax.add_collection(LineCollection(part, colors="white", linewidths=0.4,
                                                     alpha=0.8, zorder=2.5))
                keep(Line2D([], [], color=colour, linewidth=0.7, label=label))
            x0, y0, x1, y1 = bounds
            ax.plot([x0, x1, x1, x0, x0], [y0, y0, y1, y1, y0], color="tab:blue",
                    linewidth=0.6, linestyle=":")
            keep(Line2D([], [], color="tab:blue", linewidth=0.6, linestyle=":",
                        label=f"drawing {x1 - x0:.2f} × {y1 - y0:.2f} mm"))
        if first:
            # The whole field, and whatever of the drawing lies outside it.
            reach = max(half, *np.abs(points).max(axis=0)) if paths else half
            margin = 0.04 * reach
            ax.set_xlim(-reach - margin, reach + margin)
            ax.set_ylim(-reach - margin, reach + margin)
        elif kind == "detail":
            cx, cy, side = detail
            ax.set_xlim(cx - side / 2, cx + side / 2)
            ax.set_ylim(cy - side / 2, cy + side / 2)
            ax.set_title(f"a detail, {side:.2g} mm wide", fontsize=9)
        else:
            x0, y0, x1, y1 = bounds
            side = max(x1 - x0, y1 - y0, 1e-3) * 1.15
            cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
            ax.set_xlim(cx - side / 2, cx + side / 2)
            ax.set_ylim(cy - side / 2, cy + side / 2)
            ax.set_title("the drawing, zoomed in", fontsize=9)
        ax.set_aspect("equal")
        ax.set_xlabel("X (mm)")
        ax.set_ylabel("Y (mm)")
        ax.grid(True, linewidth=0.3, alpha=0.5)
    if title:
        figure.suptitle(title)
    axes[0].legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.08), ncol=2,
                   fontsize=8, frameon=False)
    try:
        figure.savefig(path)
    except (ValueError, OSError) as error:
        message = " ".join(str(error).split())
        raise ValueError(f"{path}: cannot write the preview ({message})") from None
    return mark_mm, jump_mm
