"""SkyWriting against the laser delays and against nothing, on the simulated board and through
the galvo model.

The job: an L, a mark of ``length_mm`` along X and one along Y, planned by galvoscan's planner
and marked on the simulated board (the engraver's bitstream, which has pixel lines) three ways:

* **nothing**: every laser and scanner delay 0;
* **delays**: the profile's laser-on, laser-off, mark and polygon delays (its defaults: what
  ``galvoscan analyze --delays`` finds for this galvo at 1 m/s);
* **SkyWriting**: mode 2 (every corner taken apart), Timelag the galvo model's own tracking
  error (2 / ω_n of its critically damped loop), RTC's runs (Nprev and Npost 0.15 and 0.1 ×
  Timelag);
* **SkyWriting, long runs**: the same with Nprev and Npost :data:`LONG_RUNS` × Timelag, long
  enough for the mirror to reach the line's speed (its lag settles in a few 1 / ω_n).

The frames come off the board's XY2-100 wires and go through
:class:`~.galvo.GalvoModel` (the JD1403 galvo of Wan et al.); each laser pulse off the DB25
pins falls where the mirror then is. The dose is taken along the drawn L at spot scale
(Gaussian spots, 1/e² diameter ``spot_mm``), relative to the dose mid-line; and how far the
pulses stray from the L's lines (a corner rounded by the lagging mirror strays).
"""

import math
from dataclasses import replace

import numpy as np

from .figures import _pyplot
from .galvo import FRAME_PERIOD, FULL_RANGE, GalvoModel


__all__ = ["RUNS", "LONG_RUNS", "sky_job_dose", "sky_study", "sky_report", "markdown_table", "plot_sky",
           "model_timelag_us"]


#: The runs, in the figure's order.
RUNS = ("nothing", "delays", "SkyWriting", "SkyWriting, long runs")
#: The long runs' Nprev and Npost, × Timelag.
LONG_RUNS = 2


def model_timelag_us(galvo):
    """The galvo model's tracking error at constant speed, µs (whole): 2 / ω_n."""
    return round(2 / galvo.omega_n * 1e6)


def _profile(run, timelag_us):
    from ..profile.machine import default_profile
    profile = default_profile()
    galvo = replace(profile.galvo, tracking_delay_us=float(timelag_us))
    if run == "nothing":
        galvo = replace(galvo, laser_on_delay_us=0.0, laser_off_delay_us=0.0,
                        mark_delay_us=0.0, polygon_delay_us=0.0)
    return replace(profile, galvo=galvo)


def _plan(run, *, length_mm, speed_mm_s, timelag_us):
    """The L planned for ``run`` (galvoscan's planner: the same plan ``mark`` makes)."""
    from .. import api
    from ..geometry.drawing import Drawing
    from ..geometry.field import Placement
    from ..plan.objects import MarkObject
    profile = _profile(run, timelag_us)
    half = length_mm / 2
    path = np.array([(-half, -half), (half, -half), (half, half)])
    path.setflags(write=False)
    drawing = Drawing("L", paths=(path,), closed=(False,))
    sky = run.startswith("SkyWriting")
    runs = float(LONG_RUNS * timelag_us) if run.endswith("long runs") else None
    # (Off, no SkyWriting setting is given: the API refuses one that would do nothing.)
    job = api.Job(speed_mm_s=speed_mm_s, sky_mode=2 if sky else 0,
                  **(dict(timelag_us=float(timelag_us), nprev_us=runs, npost_us=runs)
                     if sky else {}))
    settings = api.job_settings(job, profile)
    made = MarkObject(drawing, Placement(origin="page"), settings, keep_order=True)
    return api.plan_made([made], job, profile), path


def _board(backend):
    from ..build import simulated_bitstream
    from ..sim.board import SimulatedBoard
    config, contents = simulated_bitstream("icebreaker", preset="engraver")
    return SimulatedBoard(config=config, backend=backend, **contents)


def _pulses_on_the_mirror(board, galvo, field_mm):
    """Where each laser pulse fell (mm), the frames off the wires followed by the mirror."""
    in_force = np.array(board.sync_rises[1:len(board.frames) + 1], dtype=float)
    frames = np.array([(x, y) for _, x, y in board.frames[:len(in_force)]], dtype=float)
    pulses = np.array(board.pulses, dtype=float)
    if not len(pulses):
        return np.zeros((0, 2))
    # From some frames before the first pulse (the mirrors at rest) to the last pulse.
    first = max(0, int(np.searchsorted(in_force, pulses[0])) - 200)
    last = min(len(in_force) - 1, int(np.searchsorted(in_force, pulses[-1])) + 2)
    steps = np.diff(in_force[first:last + 1])
    period = FRAME_PERIOD * board.clk_freq
    assert np.all(np.abs(steps - period) < 1), "the frames come every 10 µs"
    window = frames[first:last + 1]
    path = galvo.follow(window[:, 0], window[:, 1], substeps=10)
    t = (pulses - in_force[first]) / board.clk_freq
    px, py = path.at(t)
    units = FULL_RANGE / field_mm
    return np.column_stack([(px - FULL_RANGE / 2) / units, (py - FULL_RANGE / 2) / units])


def _distance_to_lines(points, path):
    """Each point's distance (mm) to the nearest of the lines through ``path``'s segments
    (drawn on past their ends: a pulse just past an end, along its line, is on it; one that
    cuts a corner is not)."""
    best = np.full(len(points), np.inf)
    for a, b in zip(path[:-1], path[1:]):
        d = (b - a) / np.hypot(*(b - a))
        v = points - a
        best = np.minimum(best, np.abs(v[:, 0] * d[1] - v[:, 1] * d[0]))
    return best


def sky_job_dose(run, *, galvo=None, length_mm=2.0, speed_mm_s=1000.0, spot_mm=0.05,
                 sample_mm=0.005, timelag_us=None, backend="auto"):
    """One run of the L (``run``: one of :data:`RUNS`) on the simulated board: a dict of the
    dose along the path (``s_mm``, ``dose`` relative to mid-line), its peak at the ``start``,
    ``corner`` and ``end``, where the marked line starts and ends past its set points
    (``start_shift_mm``, ``end_shift_mm``: the dose crosses half the mid-line's), how far the
    pulses stray from the L's lines at most (``off_path_mm``: a corner cut), the pulses (mm)
    and the plan's
    registers."""
    galvo = GalvoModel.from_step_times() if galvo is None else galvo
    timelag_us = model_timelag_us(galvo) if timelag_us is None else timelag_us
    planned, path = _plan(run, length_mm=length_mm, speed_mm_s=speed_mm_s,
                          timelag_us=timelag_us)
    from .. import api
    board = _board(backend)
    try:
        api.run(planned, board)
        pulses = _pulses_on_the_mirror(board, galvo, planned.profile.field.size_mm)
    finally:
        board.close()
    s = np.arange(-0.3, 2 * length_mm + 0.3, sample_mm)
    on_first = s <= length_mm
    sx = np.where(on_first, path[0][0] + s, path[1][0])
    sy = np.where(on_first, path[0][1], path[1][1] + (s - length_mm))
    w = spot_mm / 2
    dose = np.zeros_like(s)
    for k in range(0, len(pulses), 256):
        dx = sx[:, None] - pulses[None, k:k + 256, 0]
        dy = sy[:, None] - pulses[None, k:k + 256, 1]
        dose += np.exp(-2 * (dx ** 2 + dy ** 2) / w ** 2).sum(axis=1)
    middle = (s > 0.3 * length_mm) & (s < 0.7 * length_mm)
    dose = dose / np.median(dose[middle])

    def peak(low, high):
        return float(dose[(s >= low) & (s <= high)].max())

    marked = np.nonzero(dose >= 0.5)[0]
    return {"run": run, "s_mm": s, "dose": dose, "length_mm": length_mm,
            "start": peak(-0.3, 0.5), "corner": peak(length_mm - 0.3, length_mm + 0.3),
            "end": peak(2 * length_mm - 0.5, 2 * length_mm + 0.3),
            "start_shift_mm": float(s[marked[0]]),
            "end_shift_mm": float(s[marked[-1]] - 2 * length_mm),
            "off_path_mm": float(_distance_to_lines(pulses, path).max()),
            "pulses_mm": pulses, "path_mm": path, "timelag_us": timelag_us,
            "registers": dict(planned.vector_job.registers),
            "sky_s": planned.vector_job.sky_s, "estimate_s": planned.estimate_s}


def sky_study(*, galvo=None, say=None, **job):
    """The L's runs (:data:`RUNS`), each :func:`sky_job_dose`'s; ``say(line)`` before each
    (each is a second or two of the simulated board)."""
    galvo = GalvoModel.from_step_times() if galvo is None else galvo
    results = []
    for number, run in enumerate(RUNS, 1):
        if say is not None:
            say(f"run {number} of {len(RUNS)}: {run}, on the simulated board")
        results.append(sky_job_dose(run, galvo=galvo, **job))
    return results


def sky_report(results):
    """Rows of plain numbers for the docs' table and ``--json``."""
    rows = []
    for result in results:
        regs = result["registers"]
        rows.append({"run": result["run"], "laser_on_delay_us": regs["laser_on_delay"],
                     "laser_off_delay_us": regs["laser_off_delay"],
                     "mark_delay_us": regs["mark_delay"],
                     "polygon_delay_us": regs["polygon_delay"],
                     "start_peak": round(result["start"], 2),
                     "corner_peak": round(result["corner"], 2),
                     "end_peak": round(result["end"], 2),
                     "start_shift_um": round(result["start_shift_mm"] * 1000),
                     "end_shift_um": round(result["end_shift_mm"] * 1000),
                     "off_path_um": round(result["off_path_mm"] * 1000, 1),
                     "estimate_ms": round(result["estimate_s"] * 1000, 2)})
    return rows


def markdown_table(rows):
    """The docs' table of :func:`sky_report`'s rows (generated, never written by hand)."""
    lines = ["| run | laser on / off µs | mark / polygon µs | peak dose: start, corner, end | "
             "line starts, ends (µm past its set points) | pulses off the L's lines, at most (µm) | "
             "time (ms) |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['run']} | {r['laser_on_delay_us']} / {r['laser_off_delay_us']} | "
                     f"{r['mark_delay_us']} / {r['polygon_delay_us']} | "
                     f"{r['start_peak']:.2f}, {r['corner_peak']:.2f}, {r['end_peak']:.2f} | "
                     f"{r['start_shift_um']:+d}, {r['end_shift_um']:+d} | "
                     f"{r['off_path_um']:.1f} | {r['estimate_ms']:.2f} |")
    return "\n".join(lines)


_COLOURS = {"nothing": "tab:red", "delays": "tab:orange", "SkyWriting": "tab:cyan",
            "SkyWriting, long runs": "tab:blue"}


def plot_sky(path, results):
    """Dose along the L for each run, and where the pulses fell at its start and corner."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.6), dpi=110,
                             gridspec_kw={"width_ratios": [2.2, 1, 1]})
    ax = axes[0]
    length = results[0]["length_mm"]
    for result in results:
        ax.plot(result["s_mm"], result["dose"], color=_COLOURS[result["run"]], linewidth=0.9,
                label=result["run"])
    for at in (0, length, 2 * length):
        ax.axvline(at, color="0.5", linewidth=0.5, linestyle=":")
    ax.set_xlabel("along the L, mm (start, corner, end dotted)")
    ax.set_ylabel("dose / mid-line dose")
    ax.legend(fontsize=7, loc="upper center")
    start, corner = results[0]["path_mm"][0], results[0]["path_mm"][1]
    for ax, (cx, cy), title in ((axes[1], start, "start"), (axes[2], corner, "corner")):
        ax.plot(*results[0]["path_mm"].T, color="0.7", linewidth=0.8)
        for result, marker in zip(results, ("o", "s", "^", ".")):
            px, py = result["pulses_mm"].T
            near = (np.abs(px - cx) < 0.2) & (np.abs(py - cy) < 0.2)
            ax.plot(px[near], py[near], marker, color=_COLOURS[result["run"]], markersize=3,
                    alpha=0.6)
        ax.set_xlim(cx - 0.2, cx + 0.2)
        ax.set_ylim(cy - 0.2, cy + 0.2)
        ax.set_aspect("equal")
        ax.set_title(f"pulses at the {title} (mirror's position)", fontsize=9)
        ax.set_xlabel("mm")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
