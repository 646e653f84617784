"""Figures of the scan analysis (matplotlib, written as PNG files)."""

import matplotlib
from matplotlib import pyplot
from matplotlib.ticker import ScalarFormatter
import numpy as np

from .study import FILL_STAGES, fill_points


__all__ = ["plot_fill", "plot_dose_maps", "plot_sigma_sweep", "plot_spiral_vs_raster",
           "plot_wobble", "plot_interpolation"]


def _pyplot():
    matplotlib.use("Agg")
    return pyplot


def _frame_field(ax, region):
    (x0, y0), (x1, y1) = region.low, region.high
    ax.plot([x0, x1, x1, x0, x0], [y0, y0, y1, y1, y0], color="tab:red", linewidth=0.6)


def plot_fill(path, results, head, region, *, stages=FILL_STAGES):
    """The mirror path at several shares of the pattern, one row per result (the paper's
    figures 5 and 6: uniform against Gaussian sampling)."""
    plt = _pyplot()
    fig, axes = plt.subplots(len(results), len(stages),
                             figsize=(2.1 * len(stages), 2.1 * len(results) * region.size[1]
                                      / region.size[0] + 0.6 * len(results)),
                             dpi=110, squeeze=False)
    for row, result in zip(axes, results):
        for ax, stage in zip(row, stages):
            x, y = fill_points(result, stage, head)
            ax.plot(x, y, linewidth=0.15, color="black")
            _frame_field(ax, region)
            ax.set_aspect("equal")
            ax.set_xticks([])
            ax.set_yticks([])
            ax.set_title(f"{result.metrics['pattern']}\n{stage:.0%}", fontsize=7)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def _blocks(result, block_mm=1.0):
    """The field's dose averaged over ``block_mm`` squares, and its extent (mm from the field
    centre)."""
    blocks = result.dose.blocks(block_mm)
    size = max(1, int(round(block_mm / result.dose.cell)))
    width, height = (n * size * result.dose.cell for n in blocks.shape)
    return blocks, [-width / 2, width / 2, -height / 2, height / 2]


def _zoom(result, region, size_mm):
    """Spot-scale dose in the field's lower-left corner (``size_mm`` square), mm from the
    field centre."""
    dose = result.dose
    x0, y0 = region.low
    in_x = (dose.x >= x0 - 0.2) & (dose.x <= x0 + size_mm)
    in_y = (dose.y >= y0 - 0.2) & (dose.y <= y0 + size_mm)
    cx, cy = region.centre
    half = dose.cell / 2
    xs, ys = dose.x[in_x], dose.y[in_y]
    return dose.dose[np.ix_(in_x, in_y)], [xs[0] - half - cx, xs[-1] + half - cx,
                                           ys[0] - half - cy, ys[-1] + half - cy]


def plot_dose_maps(path, results, region, *, zoom_mm=3.0, title=None):
    """Dose maps side by side: the field averaged over 1 mm blocks (top, one colour scale) and
    the spot-scale dose in a corner (bottom), J/cm² per pattern."""
    plt = _pyplot()
    blocks = [_blocks(r) for r in results]
    top = max(b.max() for b, _ in blocks)
    zooms = [_zoom(r, region, zoom_mm) for r in results]
    zoom_top = max(np.percentile(z, 99.5) for z, _ in zooms)
    width, height = region.size
    fig, axes = plt.subplots(2, len(results), figsize=(4.6 * len(results),
                                                       4.6 * height / width + 4.2),
                             dpi=110, squeeze=False,
                             gridspec_kw={"height_ratios": [height / width, 0.9]})
    for column, result in enumerate(results):
        m = result.metrics
        ax = axes[0][column]
        image = ax.imshow(blocks[column][0].T, origin="lower", extent=blocks[column][1],
                          cmap="inferno", vmin=0, vmax=top, interpolation="nearest")
        ax.set_title(f"{m['pattern']}: 1 mm blocks, CV {m['cv_1mm']:.2f}\n"
                     f"edge/centre {m['edge_centre']:.2f}, spot-scale CV {m['cv']:.2f}",
                     fontsize=7)
        ax.tick_params(labelsize=6)
        ax.set_xlabel("x from field centre (mm)", fontsize=7)
        fig.colorbar(image, ax=ax, shrink=0.8).ax.tick_params(labelsize=6)
        ax = axes[1][column]
        image = ax.imshow(zooms[column][0].T, origin="lower", extent=zooms[column][1],
                          cmap="inferno", vmin=0, vmax=zoom_top, interpolation="nearest")
        ax.set_title(f"spot scale, lower-left {zoom_mm:g} mm; fill {m['fill']:.0%}",
                     fontsize=7)
        ax.tick_params(labelsize=6)
        fig.colorbar(image, ax=ax, shrink=0.8).ax.tick_params(labelsize=6)
    fig.suptitle(title or "dose per pattern (J/cm²)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def plot_sigma_sweep(path, results, *, chosen_sigma):
    """Uniformity against σ and against the mirror's peak acceleration."""
    plt = _pyplot()
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4), dpi=110)
    gauss = [r for r in results if r.table.sampling == "gaussian"]
    uniform = [r for r in results if r.table.sampling == "uniform"]
    triangle = [r for r in results if r.table.sampling == "triangle"]
    sigmas = [r.table.sigma for r in gauss]
    top = 0.0
    for key, label, style in (("cv_1mm", "CV of 1 mm blocks", "o-"),
                              ("cv_inner", "CV, inner 80 % (spot scale)", "s--"),
                              ("edge_centre", "edge / centre dose", "^:")):
        values = [r.metrics[key] for r in gauss]
        top = max(top, *values)
        if uniform:
            label += f" (uniform: {uniform[0].metrics[key]:.2f})"
        line, = left.plot(sigmas, values, style, label=label, markersize=4)
        if triangle:
            # σ → ∞: the triangle wave, drawn as a level across the plot.
            left.axhline(triangle[0].metrics[key], color=line.get_color(), linewidth=0.6,
                         linestyle=":", alpha=0.8)
    left.axvline(chosen_sigma, color="grey", linewidth=0.8)
    left.annotate(f"default σ = {chosen_sigma:g}", (chosen_sigma, top * 1.05), fontsize=7,
                  xytext=(3, 0), textcoords="offset points")
    left.set_xscale("log")
    left.xaxis.set_major_formatter(ScalarFormatter())
    left.xaxis.set_minor_formatter(ScalarFormatter())
    left.tick_params(axis="x", which="both", labelsize=7)
    left.set_ylim(0, top * 1.15)
    if triangle:
        left.annotate("dotted: triangle wave (σ → ∞)", (sigmas[0], top * 1.08), fontsize=7)
    left.set_xlabel("σ (half-swings)")
    left.legend(fontsize=7, loc="center right")
    left.set_title("uniformity against σ (same dwell)", fontsize=9)
    for n, r in enumerate(results):
        uniform_run = r.table.sampling == "uniform"
        label = {"uniform": "uniform", "triangle": "triangle"}.get(r.table.sampling,
                                                                   f"σ={r.table.sigma:g}")
        colour = "tab:red" if uniform_run else "tab:orange" if r.table.sampling == "triangle" \
            else ("tab:green" if r.table.sigma == chosen_sigma else "tab:blue")
        right.plot(r.metrics["peak_accel_km_s2"], r.metrics["cv_1mm"], "o", color=colour)
        if r.table.sampling != "gaussian" or \
                r.table.sigma in (0.4, 0.5, 0.6, 0.8, 1.0, 1.5, chosen_sigma, 5.0):
            right.annotate(label, (r.metrics["peak_accel_km_s2"], r.metrics["cv_1mm"]),
                           fontsize=7, xytext=(4, -10 if n % 2 else 3),
                           textcoords="offset points")
    right.set_xlabel("mirror peak acceleration at the work piece (km/s²)")
    right.set_ylabel("CV of 1 mm blocks")
    right.set_title("uniformity against mirror effort", fontsize=9)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def plot_spiral_vs_raster(path, pairs, setup):
    """Per field: raster and spiral dose (1 mm blocks), and their revisit intervals."""
    plt = _pyplot()
    fig, axes = plt.subplots(len(pairs), 3, figsize=(13, 4.0 * len(pairs)), dpi=110,
                             squeeze=False)
    for row, (spiral, raster) in zip(axes, pairs):
        maps = [_blocks(r) for r in (raster, spiral)]
        top = max(b.max() for b, _ in maps)
        for ax, result, (blocks, extent) in zip(row[:2], (raster, spiral), maps):
            image = ax.imshow(blocks.T, origin="lower", extent=extent, cmap="inferno",
                              vmin=0, vmax=top, interpolation="nearest")
            m = result.metrics
            ax.set_title(f"{m['pattern']} {m['field_mm'][0]:g}×{m['field_mm'][1]:g} mm, "
                         f"{m['duration_s']:.2f} s/pass\nfill {m['fill']:.0%}, "
                         f"1 mm CV {m['cv_1mm']:.2f}, edge peak {m['edge_peak']:.2f}",
                         fontsize=7)
            ax.tick_params(labelsize=6)
            fig.colorbar(image, ax=ax, shrink=0.7, label="J/cm² per pass (1 mm blocks)")
        ax = row[2]
        bins = np.logspace(-2, 4, 61)
        for result, colour in ((raster, "tab:red"), (spiral, "tab:blue")):
            if len(result.intervals):
                share = np.full(len(result.intervals), 1 / len(result.intervals))
                ax.hist(result.intervals * 1e3, bins=bins, histtype="step", color=colour,
                        label=result.metrics["pattern"], weights=share)
        ax.set_xscale("log")
        ax.set_xlabel("shortest revisit interval of a point (ms)")
        ax.set_ylabel("share of the points reached")
        ax.set_title("time to cool before the spot returns (within 0.1 mm)", fontsize=8)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def plot_wobble(path, amplitudes, frequencies, *, map_runs=None):
    """The wobble study: the dose across the track for each amplitude, the track's width, the
    mirror's reach and the ripple along it against the frequency, and the dose maps of two
    runs (``map_runs``: indices into ``frequencies``; default its first and its middle)."""
    plt = _pyplot()
    fig, axes = plt.subplots(2, 2, figsize=(10, 7), dpi=110)
    ax = axes[0, 0]
    for metrics, dose, profile in amplitudes:
        ax.plot(dose.y * 1000, profile, label=f"±{metrics['across_um']:g} µm" if
                metrics["across_um"] else "no wobble")
    ax.set_xlabel("across the line (µm)")
    ax.set_ylabel("dose, averaged along (J/cm²)")
    ax.set_title(f"circles at {amplitudes[0][0]['hz']:g} Hz, "
                 f"{amplitudes[0][0]['speed_mm_s']:g} mm/s")
    ax.legend(fontsize=8)
    ax = axes[0, 1]
    hz = [m["hz"] for m, _, _ in frequencies]
    ax.semilogx(hz, [m["width_mm"] * 1000 for m, _, _ in frequencies], "o-",
                label="track width (µm)")
    ax.set_xticks(hz, [f"{h:g}" for h in hz])
    ax.minorticks_off()
    ax.set_xlabel("wobble frequency (Hz)")
    ax.set_ylabel("track width at half peak (µm)")
    twin = ax.twinx()
    twin.semilogx(hz, [m["reach"] for m, _, _ in frequencies], "s--", color="tab:green",
                  label="mirror reach / commanded")
    twin.semilogx(hz, [m["ripple"] for m, _, _ in frequencies], "^:", color="tab:red",
                  label="ripple along (CV)")
    twin.set_ylim(0, max(1.05, max(m["ripple"] for m, _, _ in frequencies) * 1.05))
    twin.minorticks_off()
    lines = ax.get_legend_handles_labels()
    more = twin.get_legend_handles_labels()
    ax.legend(lines[0] + more[0], lines[1] + more[1], fontsize=8, loc="center left")
    ax.set_title(f"±{frequencies[0][0]['across_um']:g} µm circles")
    picks = map_runs or (0, len(frequencies) // 2)
    for ax, index in zip(axes[1], picks):
        metrics, dose, _ = frequencies[index]
        keep = np.abs(dose.x) <= 0.5
        image = ax.imshow(dose.dose[keep].T, origin="lower", aspect="auto", cmap="inferno",
                          extent=(dose.x[keep][0], dose.x[keep][-1], dose.y[0] * 1000,
                                  dose.y[-1] * 1000))
        ax.set_xlabel("along the line (mm)")
        ax.set_ylabel("across (µm)")
        ax.set_title(f"{metrics['hz']:g} Hz: a turn every {metrics['turn_um']:.0f} µm")
        fig.colorbar(image, ax=ax, label="J/cm²")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def plot_interpolation(path, held, linear, head, *, stretch_s=1.2e-3):
    """The same spiral held point by point and interpolated: the spot's speed over a stretch,
    and the commanded positions and mirror path over a few points."""
    plt = _pyplot()
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 3.8), dpi=110)
    for result, label, colour, dot in ((held, "held (spiral_interp = 0)", "tab:red", 6),
                                       (linear, "linear (spiral_interp = 1)", "tab:blue", 2)):
        path_ = result.path
        start = int(round(result.warmup_s / path_.dt))
        count = int(round(stretch_s / path_.dt))
        vx, vy = path_.velocity()
        speed = np.hypot(vx[start:start + count], vy[start:start + count])
        speed_m_s = speed * float(head.mm(1)) / 1e3
        t_ms = np.arange(len(speed)) * path_.dt * 1e3
        m = result.metrics
        left.plot(t_ms, speed_m_s, color=colour, linewidth=0.9,
                  label=f"{label}: peak {m['peak_speed_m_s']:.1f} m/s, "
                        f"{m['peak_over_mean']:.2f}× the mean")
        left.axhline(m["mean_speed_m_s"], color=colour, linewidth=0.6, linestyle=":")
        frames = result.frames
        shown = 4 * result.dwell
        right.plot(head.mm(path_.x[start:start + shown * 10]),
                   head.mm(path_.y[start:start + shown * 10]), color=colour, linewidth=0.9)
        right.plot(head.mm(frames.x[:shown]), head.mm(frames.y[:shown]), "o", color=colour,
                   markersize=dot)
    left.set_xlabel("time (ms)")
    left.set_ylabel("spot speed (m/s)")
    left.set_ylim(bottom=0)
    left.legend(fontsize=7, loc="lower right")
    left.set_title(f"spot speed, dwell {linear.dwell} (dotted: mean)", fontsize=9)
    right.set_aspect("equal", adjustable="datalim")
    right.set_xlabel("x (mm)")
    right.set_ylabel("y (mm)")
    right.set_title("four points: commanded frames (dots) and mirror path", fontsize=9)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
