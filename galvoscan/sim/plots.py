"""Plots of simulated runs: the spiral's path and a vector job's marked points."""


# A Figure of its own, not pyplot's: no global backend or figure list to set or close.
from matplotlib.figure import Figure


__all__ = ["plot_path", "plot_job"]


def plot_path(path, frames, *, title="Simulated XY2-100 output"):
    """Plot the path through the frames' positions over the whole field."""
    xs = [f.x for f in frames]
    ys = [f.y for f in frames]
    fig = Figure(figsize=(6, 6), dpi=120)
    ax = fig.subplots()
    ax.plot(xs, ys, linewidth=0.25, color="tab:blue")
    ax.plot(xs, ys, ".", markersize=0.8, color="black")
    ax.set_xlim(0, 65535)
    ax.set_ylim(0, 65535)
    ax.set_aspect("equal")
    ax.set_xlabel("X (galvo units)")
    ax.set_ylabel("Y (galvo units)")
    ax.set_title(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path)


def plot_job(path, result, *, title):
    """Plot a vector job's path: jumps grey, marked points coloured by their pulses."""
    points = result.points
    xs = [p[0] for p in points]
    ys = [p[1] for p in points]
    fig = Figure(figsize=(6, 6), dpi=120)
    ax = fig.subplots()
    ax.plot(xs, ys, linewidth=0.4, color="lightgrey")
    marked = [p for p in points if p[2]]
    if marked:
        dots = ax.scatter([p[0] for p in marked], [p[1] for p in marked],
                          c=[p[2] for p in marked], s=4, cmap="viridis")
        fig.colorbar(dots, ax=ax, label="pulses on the point", shrink=0.8)
    ax.set_aspect("equal")
    ax.set_xlabel("X (galvo units)")
    ax.set_ylabel("Y (galvo units)")
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path)
