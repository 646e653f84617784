"""The correction study in docs/user/correction.md: Zhu & Zhang's experiment on a synthetic head.

A head with Liao & Chen's f-theta distortion, scaled to Zhu & Zhang's size (1400 units at
worst over the 50 000-unit calibrated square), is calibrated with 3 × 3 … 11 × 11 grids of
measured points (with measurement noise), by bilinear tables and by polynomial fits, and
through the photo pipeline; each table is then judged on a dense grid of targets through the
gateware's own arithmetic. The f-theta model table (Liao & Chen 2016) is judged the same way.
"""

import numpy as np

from .measure import GRID_SIZES, METHODS, calibration_grid, residuals, table_from_measurement
from .model import ftheta_table, synthetic_head
from .photo import calibration_job, measure_photo, render_photo


__all__ = ["PAPER_004", "STUDY_STEPS", "run_study", "markdown_table", "photo_sentence_values", "NOISE_UNITS"]


#: Zhu & Zhang's result: errors before and after their bilinear correction, galvo units.
PAPER_004 = {"before_max": 1411, "before_mean": 259, "after_max": 194, "after_mean": 36.5}

#: Standard deviation of the synthetic measurement noise per axis, galvo units (≈ 25 µm on a
#: 110 mm field, a camera's half pixel).
NOISE_UNITS = 15.0


#: Steps ``run_study`` reports to ``progress``: each grid and method, the model, the photo.
STUDY_STEPS = len(GRID_SIZES) * len(METHODS) + 2


def run_study(*, nodes=17, seed=1, photo_grid=9, progress=None):
    """Residuals per grid size and method, the model table's and the photo pipeline's.

    Returns a dict: ``head`` (its field and error), ``grids`` (rows of grid, method, residual
    figures), ``model`` (the exact f-theta table's residuals), ``photo`` (centre errors,
    residuals).
    """
    head = synthetic_head()
    rng = np.random.default_rng(seed)
    before = residuals(head.land)
    rows = []
    for grid in GRID_SIZES:
        cx, cy = calibration_grid(grid)
        lx, ly = head.land(cx, cy)
        mx = lx + rng.normal(0.0, NOISE_UNITS, lx.shape)
        my = ly + rng.normal(0.0, NOISE_UNITS, ly.shape)
        for method in METHODS:
            table = table_from_measurement(cx, cy, mx, my, nodes=nodes, method=method)
            rows.append({"grid": grid, "method": method, **residuals(head.land, table)})
            if progress:
                progress(1)

    model = residuals(head.land, ftheta_table(nodes, field_mm=head.field_mm,
                                              focal_mm=head.focal_mm))
    if progress:
        progress(1)

    job = calibration_job(photo_grid)
    image, camera = render_photo(job, head.land, grid=photo_grid, seed=seed)
    cx, cy, mx, my = measure_photo(image, photo_grid)
    lx, ly = head.land(cx, cy)
    centre_error = np.hypot(mx - lx, my - ly)
    table = table_from_measurement(cx, cy, mx, my, nodes=nodes)
    photo = {"grid": photo_grid, "segments": len(job), "pixels": image.shape[0],
             "units_per_px": float(1 / np.linalg.norm(camera[:2, 0])),
             "centre_error_max": float(centre_error.max()),
             "centre_error_mean": float(centre_error.mean()),
             **residuals(head.land, table)}
    if progress:
        progress(1)
    return {"head": {"field_mm": head.field_mm, "focal_mm": head.focal_mm, **before},
            "nodes": nodes, "noise_units": NOISE_UNITS, "grids": rows, "model": model,
            "photo": photo, "photo_image": image, "photo_table": table}


def photo_sentence_values(study):
    """The photo figures the docs quote, formatted as it quotes them."""
    photo = study["photo"]
    return {"PHOTO_MAX": f"{photo['centre_error_max']:.0f}",
            "PHOTO_MEAN": f"{photo['centre_error_mean']:.0f}",
            "PHOTO_UPP": f"{photo['units_per_px']:.0f}",
            "PHOTO_REMOVED": f"{photo['removed']:.0%}"}


def markdown_table(study):
    """The docs' residual table."""
    head = study["head"]
    lines = ["| calibration | max error | mean error | mean removed |",
             "|---|---:|---:|---:|",
             f"| none (synthetic head) | {head['before_max']:.0f} | {head['before_mean']:.1f} "
             f"| — |",
             f"| Zhu & Zhang (paper), bilinear grid | {PAPER_004['after_max']} | "
             f"{PAPER_004['after_mean']} | "
             f"{1 - PAPER_004['after_mean'] / PAPER_004['before_mean']:.0%} |"]
    for row in study["grids"]:
        lines.append(f"| {row['grid']} × {row['grid']} {row['method']} | "
                     f"{row['after_max']:.0f} | {row['after_mean']:.1f} | "
                     f"{row['removed']:.1%} |")
    model, photo = study["model"], study["photo"]
    lines.append(f"| f-theta model table (Liao & Chen, exact) | {model['after_max']:.0f} | "
                 f"{model['after_mean']:.1f} | {model['removed']:.1%} |")
    lines.append(f"| photo, {photo['grid']} × {photo['grid']} bilinear | "
                 f"{photo['after_max']:.0f} | {photo['after_mean']:.1f} | "
                 f"{photo['removed']:.1%} |")
    return "\n".join(lines)
