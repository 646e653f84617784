"""``galvoscan analyze``: run the analyses, print the metric table, write the figures."""

import json
import math
from pathlib import Path
import sys

from tqdm import tqdm

from ..gateware.host.regmap import BY_NAME
from ..gateware.sources.spiral_table import DEFAULT_SIGMA, SpiralTable
from . import figures
from .dose import Laser
from .galvo import GalvoModel
from .patterns import INTERPOLATIONS, ScanHead
from .study import (PAPER_FIELDS_MM, SWEEP_SIGMAS, Setup, run_spiral,
                    sigma_sweep, spiral_vs_raster)
from .wobble import WOBBLE_AMPLITUDES_UM, WOBBLE_FREQUENCIES_HZ, wobble_study


__all__ = ["ROWS", "format_table", "run_analyze", "AnalysisInputError"]


class AnalysisInputError(ValueError):
    """A setting the analysis cannot be run with (the command line says it in one line)."""


#: Metric rows of the printed table: key, label, format.
ROWS = (
    ("field_mm", "field (mm)", lambda v: f"{v[0]:g} x {v[1]:g}"),
    ("dwell", "dwell (frames/point)", "{}"),
    ("duration_s", "pass time (s)", "{:.3f}"),
    ("interpolation", "between points", "{}"),
    ("mean_speed_m_s", "mean spot speed (m/s)", "{:.2f}"),
    ("peak_speed_m_s", "peak spot speed (m/s)", "{:.2f}"),
    ("peak_over_mean", "peak / mean speed", "{:.2f}"),
    ("peak_accel_km_s2", "peak axis accel. (km/s²)", "{:.0f}"),
    ("dose_mean_j_cm2", "mean dose/pass (J/cm²)", "{:.2f}"),
    ("cv", "CV, spot scale", "{:.3f}"),
    ("cv_inner", "CV, inner 80 %", "{:.3f}"),
    ("cv_1mm", "CV, 1 mm blocks", "{:.3f}"),
    ("min_max", "min / max", "{:.3f}"),
    ("edge_centre", "edge / centre (mean)", "{:.3f}"),
    ("edge_peak", "edge / centre (p99)", "{:.3f}"),
    ("fill", "fill (≥ 1 spot)", "{:.1%}"),
    ("overlap50", "overlap ≥ 50 %", "{:.1%}"),
    ("revisit_p5_ms", "revisit p5 (ms)", "{:.2f}"),
    ("revisit_median_ms", "revisit median (ms)", "{:.1f}"),
    ("revisit_under_1ms", "revisited < 1 ms", "{:.1%}"),
    ("time_to_mean_dose_s", "time to target, mean (s)", "{:.2f}"),
    ("time_to_dose_1mm_s", "time to target, 1 mm (s)", "{:.2f}"),
    ("time_to_dose_s", "time to target, 99 % (s)", "{:.2f}"),
)


def _cell(value, style):
    if value is None:
        return "-"
    if isinstance(value, float) and math.isinf(value):
        return "never"
    return style(value) if callable(style) else style.format(value)


def format_table(runs, headers=None, *, rows=ROWS):
    """Metrics of several runs as a plain text table, one column per run (``rows``: which
    metrics, labelled and formatted how; default :data:`ROWS`)."""
    headers = headers or [m.get("pattern", str(i + 1)) for i, m in enumerate(runs)]
    rows = [[label] + [_cell(m.get(key), style) for m in runs]
            for key, label, style in rows if any(key in m for m in runs)]
    widths = [max(len(r[i]) for r in rows + [["metric"] + headers])
              for i in range(len(headers) + 1)]
    lines = ["  ".join(h.ljust(w) for h, w in zip(["metric"] + headers, widths))]
    lines.append("  ".join("-" * w for w in widths))
    lines += ["  ".join(c.ljust(w) for c, w in zip(r, widths)) for r in rows]
    return "\n".join(lines)


def _json_ready(metrics):
    return {k: (None if isinstance(v, float) and math.isinf(v) else v)
            for k, v in metrics.items()}


#: Rows of the wobble table: key, label, format.
WOBBLE_ROWS = (
    ("across_um", "amplitude (µm)", "{:g}"),
    ("hz", "frequency (Hz)", "{:g}"),
    ("turn_um", "a turn every (µm)", "{:.1f}"),
    ("width_mm", "track width (µm)", lambda v: f"{v * 1000:.0f}"),
    ("centre", "dose on the line / peak", "{:.2f}"),
    ("peak_rel", "peak / plain line's", "{:.2f}"),
    ("ripple", "ripple along (CV)", "{:.3f}"),
    ("reach", "mirror reach / commanded", "{:.2f}"),
)


def _run_wobble(args, head, laser, galvo):
    """``analyze --wobble``: the wobble study (:mod:`.wobble`), its table and figure."""
    bar = tqdm(total=len(WOBBLE_AMPLITUDES_UM) - 1 + len(WOBBLE_FREQUENCIES_HZ),
               desc="wobble", unit="run", file=sys.stderr, disable=args.quiet)
    amplitudes, frequencies = wobble_study(head, laser, galvo, speed_mm_s=args.wobble_speed,
                                           progress=bar.update)
    bar.close()
    written = []
    if not args.no_plots:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        figures.plot_wobble(out / "wobble.png", amplitudes, frequencies)
        written.append(out / "wobble.png")
    if args.json:
        print(json.dumps({"amplitudes": [_json_ready(m) for m, _, _ in amplitudes],
                          "frequencies": [_json_ready(m) for m, _, _ in frequencies],
                          "figures": [str(p) for p in written]}, indent=2, ensure_ascii=False))
        return 0
    print(f"a line marked at {args.wobble_speed:g} mm/s, one pulse a point; laser "
          f"{laser.prr_hz / 1e3:g} kHz, spot {laser.spot_mm:g} mm; "
          + ("ideal mirror" if args.ideal_galvo else
             f"galvo model: {galvo.omega_n / (2 * math.pi):.0f} Hz"))
    for title, runs in (("circles, amplitude swept:", amplitudes),
                        ("circles, frequency swept:", frequencies)):
        print(f"\n{title}")
        print(format_table([m for m, _, _ in runs], rows=WOBBLE_ROWS))
    for path in written:
        print(f"wrote {path}")
    return 0


def run_analyze(args):
    """The ``analyze`` command (args from the CLI parser)."""
    if args.wobble:
        try:
            head = ScanHead(args.lens_field)
            laser = Laser(power_w=args.power, prr_hz=args.prr * 1e3, spot_mm=args.spot)
            if laser.prr_hz > 100e3:
                raise ValueError("vector mode fires at most one pulse a 10 µs frame: --prr "
                                 "must be at most 100 kHz with --wobble")
            galvo = GalvoModel.ideal() if args.ideal_galvo else GalvoModel.from_step_times()
        except ValueError as error:
            raise AnalysisInputError(str(error)) from None
        return _run_wobble(args, head, laser, galvo)

    try:
        head = ScanHead(args.lens_field)
        laser = Laser(power_w=args.power, prr_hz=args.prr * 1e3, spot_mm=args.spot)
        galvo = GalvoModel.ideal() if args.ideal_galvo else GalvoModel.from_step_times()
        setup = Setup(head=head, laser=laser, galvo=galvo, speed_m_s=args.speed / 1e3,
                      line_spacing_mm=args.line_spacing, target_dose_j_cm2=args.target_dose)
        table = SpiralTable(points=args.table_points, sampling=args.sampling, sigma=args.sigma)
        other = SpiralTable(points=args.table_points, sampling="uniform") \
            if table.sampling == "gaussian" else \
            SpiralTable(points=args.table_points, sigma=DEFAULT_SIGMA)
        field = tuple(args.field)
        interpolation = args.interp or INTERPOLATIONS[BY_NAME["spiral_interp"].reset]
        steps = 3 + (2 + len(SWEEP_SIGMAS) if args.sweep else 0) + \
            (2 * len(PAPER_FIELDS_MM) if args.compare else 0)
        bar = tqdm(total=steps, desc="analyse", unit="run", file=sys.stderr,
                   disable=args.quiet)
        chosen = run_spiral(setup, field_mm=field, table=table, dwell=args.dwell,
                            interpolation=interpolation)
        bar.update(1)
        contrast = run_spiral(setup, field_mm=field, table=other, dwell=chosen.dwell,
                              interpolation=interpolation)
        bar.update(1)
        # The same pattern held point by point and interpolated (the spiral_interp register).
        otherwise = run_spiral(setup, field_mm=field, table=table, dwell=chosen.dwell,
                               interpolation=INTERPOLATIONS[1 - INTERPOLATIONS.index(
                                   interpolation)])
        held, linear = (chosen, otherwise) if interpolation == "off" else (otherwise, chosen)
        bar.update(1)
        sweep = sigma_sweep(setup, field_mm=field, progress=bar.update,
                            interpolation=interpolation) if args.sweep else []
        pairs = spiral_vs_raster(setup, progress=bar.update,
                                 interpolation=interpolation) if args.compare else []
        bar.close()
    except ValueError as error:
        raise AnalysisInputError(str(error)) from None

    written = []
    if not args.no_plots:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        region = setup.region(field)
        pair = [contrast, chosen] if table.sampling == "gaussian" else [chosen, contrast]
        figures.plot_fill(out / "fill.png", pair, head, region)
        figures.plot_dose_maps(out / "dose.png", pair, region)
        figures.plot_interpolation(out / "interpolation.png", held, linear, head)
        written += [out / "fill.png", out / "dose.png", out / "interpolation.png"]
        if sweep:
            figures.plot_sigma_sweep(out / "sigma_sweep.png", sweep, chosen_sigma=DEFAULT_SIGMA)
            written.append(out / "sigma_sweep.png")
        if pairs:
            figures.plot_spiral_vs_raster(out / "spiral_vs_raster.png", pairs, setup)
            written.append(out / "spiral_vs_raster.png")

    setup_summary = {
        "lens_field_mm": head.field_mm, "power_w": laser.power_w, "prr_hz": laser.prr_hz,
        "spot_mm": laser.spot_mm, "speed_mm_s": setup.speed_m_s * 1e3,
        "line_spacing_mm": setup.line_spacing_mm, "target_dose_j_cm2": setup.target_dose_j_cm2,
        "galvo": {"omega_n_rad_s": galvo.omega_n, "v_max_units_s": galvo.v_max},
    }
    if args.json:
        print(json.dumps({
            "setup": _json_ready(setup_summary),
            "runs": [_json_ready(r.metrics) for r in (chosen, contrast)],
            "interpolation": [_json_ready(r.metrics) for r in (held, linear)],
            "sweep": [_json_ready(r.metrics) for r in sweep],
            "compare": [[_json_ready(s.metrics), _json_ready(r.metrics)] for s, r in pairs],
            "figures": [str(p) for p in written],
        }, indent=2, ensure_ascii=False))
        return 0
    print(f"scan head {head.field_mm:g} mm field; laser {laser.power_w:g} W, "
          f"{laser.prr_hz / 1e3:g} kHz, spot {laser.spot_mm:g} mm; axes held to "
          f"{setup.speed_m_s * 1e3:g} mm/s; target dose {setup.target_dose_j_cm2:.3g} J/cm²; "
          + ("ideal mirror" if args.ideal_galvo else
             f"galvo model: {galvo.omega_n / (2 * math.pi):.0f} Hz, "
             f"{float(head.mm(galvo.v_max)) / 1e3:.1f} m/s top speed"))
    print()
    print(format_table([chosen.metrics, contrast.metrics]))
    print("\nheld points against linear interpolation (same table and dwell):")
    print(format_table([held.metrics, linear.metrics], ["held (off)", "linear"]))
    if sweep:
        print("\nσ sweep (same dwell):")
        print(format_table([r.metrics for r in sweep],
                           [r.metrics["pattern"].replace("spiral gaussian ", "")
                            .replace("spiral ", "") for r in sweep]))
    for spiral, raster in pairs:
        print(f"\nspiral vs raster, {spiral.metrics['field_mm'][0]:g} x "
              f"{spiral.metrics['field_mm'][1]:g} mm:")
        print(format_table([spiral.metrics, raster.metrics]))
    for path in written:
        print(f"wrote {path}")
    return 0
