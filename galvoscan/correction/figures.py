"""Plots of correction tables and of the calibration study."""

from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
import numpy as np


__all__ = ["plot_table", "plot_study"]


def _pyplot():
    matplotlib.use("Agg")
    return plt


def plot_table(path, table, *, title):
    """Arrows from each node to where the table sends it (offsets exaggerated to be seen)."""
    plt = _pyplot()
    nodes = table.node_positions()
    x, y = np.meshgrid(nodes, nodes)
    largest = max(int(np.abs(table.dx).max()), int(np.abs(table.dy).max()), 1)
    scale = 0.4 * table.node_spacing / largest
    fig, ax = plt.subplots(figsize=(6, 6))
    ax.quiver(x, y, table.dx * scale, table.dy * scale, angles="xy", scale_units="xy", scale=1,
              width=0.003)
    ax.set_aspect("equal")
    ax.set_xlabel("X (galvo units)")
    ax.set_ylabel("Y (galvo units)")
    ax.set_title(f"{title}\n{table.n} × {table.n} nodes; arrows × {scale:.1f} "
                 f"(largest offset {largest} units)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_study(study, out):
    """The study's figures: residual against grid size, and the photo with its detections."""
    plt = _pyplot()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths = []

    fig, ax = plt.subplots(figsize=(6.4, 4))
    for method, marker, colour in (("bilinear", "o", "tab:blue"),
                                   ("polynomial", "s", "tab:green")):
        rows = [r for r in study["grids"] if r["method"] == method]
        ax.plot([r["grid"] for r in rows], [r["after_mean"] for r in rows], marker=marker,
                color=colour, label=f"{method}: mean")
        ax.plot([r["grid"] for r in rows], [r["after_max"] for r in rows], marker=marker,
                color=colour, linestyle="--", label=f"{method}: max")
    ax.axhline(36.5, color="grey", linestyle=":", label="Zhu & Zhang mean after (36.5)")
    ax.axhline(194, color="grey", linestyle="-.", label="Zhu & Zhang max after (194)")
    ax.set_yscale("log")
    ax.set_xlabel("calibration grid (points per side)")
    ax.set_ylabel("landing error after correction (galvo units)")
    head = study["head"]
    ax.set_title(f"Synthetic head: {head['before_max']:.0f} max / {head['before_mean']:.0f} "
                 f"mean units before")
    ax.legend(fontsize=7)
    fig.tight_layout()
    paths.append(out / "residuals.png")
    fig.savefig(paths[-1], dpi=110)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(6, 6))
    ax.imshow(study["photo_image"], cmap="gray", vmin=0, vmax=1)
    ax.set_title(f"Synthetic photo of the {study['photo']['grid']} × {study['photo']['grid']} "
                 f"calibration plate")
    ax.set_axis_off()
    fig.tight_layout()
    paths.append(out / "photo.png")
    fig.savefig(paths[-1], dpi=80)
    plt.close(fig)

    plot_table(out / "photo_table.png", study["photo_table"],
               title="Table from the photo")
    paths.append(out / "photo_table.png")
    return paths
