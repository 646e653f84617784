"""``galvoscan analyze``: how a scan pattern doses a part, before burning one."""

import json
import sys
from pathlib import Path

from ..analysis.galvo import GalvoModel
from .args import (INTERPOLATIONS, add_table_options, fail, field_mm, number_in, output_dir,
                   register_int)


__all__ = ["add_parsers"]


def _cmd_analyze(args):
    if args.delays:
        return _cmd_delays(args)
    if args.sky:
        return _cmd_sky(args)
    # Here: analysis.report takes 1.7 s to import; `galvoscan --help` need not wait.
    from ..analysis.report import AnalysisInputError, run_analyze
    try:
        return run_analyze(args)
    except AnalysisInputError as error:
        fail(error)


def _cmd_delays(args):
    """The RTC delays on an L-shaped mark: dose at its ends and corner, without and with."""
    # Here: analysis.delays takes 2.9 s to import; `galvoscan --help` need not wait.
    from ..analysis.delays import delay_report, delay_study, plot_delays
    galvo = GalvoModel.ideal() if args.ideal_galvo else GalvoModel.from_step_times()
    without, chosen = delay_study(galvo=galvo, field_mm=args.lens_field,
                                  speed_mm_s=args.mark_speed, prr_hz=args.prr * 1e3,
                                  spot_mm=args.spot)
    rows = delay_report(without, chosen)
    if args.json:
        print(json.dumps(rows, indent=2))
    else:
        for row in rows:
            print(f"{row['run']:12} on {row['laser_on_delay_us']:4g} off "
                  f"{row['laser_off_delay_us']:4g} mark {row['mark_delay_us']:4g} polygon "
                  f"{row['polygon_delay_us']:4g} µs: peak dose / mid-line at the start "
                  f"{row['start_peak']:.2f}, corner {row['corner_peak']:.2f}, end "
                  f"{row['end_peak']:.2f}; line starts {row['start_shift_um']:+.0f} µm, ends "
                  f"{row['end_shift_um']:+.0f} µm from its set points")
    if not args.no_plots:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        plot_delays(out / "delays.png", without, chosen)
    return 0


def _cmd_sky(args):
    """SkyWriting against the delays and nothing on an L, on the simulated board."""
    from ..analysis.sky import markdown_table, plot_sky, sky_report, sky_study
    galvo = GalvoModel.ideal() if args.ideal_galvo else GalvoModel.from_step_times()
    say = None if args.quiet else (lambda line: print(line, file=sys.stderr))
    results = sky_study(galvo=galvo, speed_mm_s=args.mark_speed, spot_mm=args.spot,
                        backend=getattr(args, "backend", None) or "auto", say=say)
    rows = sky_report(results)
    if args.json:
        print(json.dumps(rows, indent=2))
    else:
        print(f"an L of 2 × {results[0]['length_mm']:g} mm at {args.mark_speed:g} mm/s on the "
              f"simulated board, its frames through the galvo model (Timelag "
              f"{results[0]['timelag_us']} µs, its tracking error):")
        print(markdown_table(rows))
    if not args.no_plots:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        plot_sky(out / "sky.png", results)
        if say is not None:
            say(f"wrote {out / 'sky.png'}")
    return 0


def add_parsers(commands):
    analyze = commands.add_parser(
        "analyze", help="measure how a scan pattern doses a part (before burning one)",
        description="Run the spiral the gateware emits (its Python model, proved equal by the "
                    "full replay test) through a galvo model and a pulsed laser; print dose "
                    "uniformity, speed, revisit and time figures and write plots. The "
                    "comparison column is the other sampling at the same dwell.")
    add_table_options(analyze)
    job = analyze.add_argument_group("pattern and machine")
    job.add_argument("--field", type=field_mm, default=(50.0, 20.0), metavar="WxH",
                     help="field to clean, mm (default: 50x20, the paper's test piece)")
    job.add_argument("--dwell", type=register_int("dwell"), default=None,
                     help="frames per spiral point (default: the smallest that keeps each "
                          "axis at --speed)")
    job.add_argument("--interp", choices=INTERPOLATIONS, default=None,
                     help="between spiral points: off (held, then a jump) or linear (default: "
                          "the spiral_interp register's reset); the other is printed beside it")
    job.add_argument("--speed", type=number_in("speed", 10, 100_000), default=5000.0,
                     metavar="MM_S", help="per-axis speed limit for the patterns, mm/s "
                                          "(default: 5000, the paper's galvo maximum)")
    job.add_argument("--lens-field", type=number_in("lens field", 1, 2000), default=110.0,
                     metavar="MM", help="scan head field across 65536 units, mm "
                                        "(default: 110)")
    job.add_argument("--spot", type=number_in("spot", 0.001, 100), default=0.05, metavar="MM",
                     help="spot 1/e² diameter, mm (default: 0.05)")
    job.add_argument("--power", type=number_in("power", 0.001, 1e5), default=50.0,
                     metavar="W", help="average laser power, W (default: 50)")
    job.add_argument("--prr", type=number_in("PRR (kHz)", 0.001, 100_000), default=100.0,
                     metavar="KHZ", help="pulse repetition rate, kHz (default: 100)")
    job.add_argument("--line-spacing", type=number_in("line spacing", 0.0001, 10),
                     default=None, metavar="MM",
                     help="raster line spacing, mm (default: the spot diameter)")
    job.add_argument("--target-dose", type=number_in("target dose", 1e-6, 1e6), default=None,
                     metavar="J_CM2", help="dose to reach for the time figures, J/cm² "
                                           "(default: one raster pass)")
    job.add_argument("--ideal-galvo", action="store_true",
                     help="mirror exactly where commanded (no speed limit, no lag)")
    what = analyze.add_argument_group("what to run")
    what.add_argument("--sweep", action="store_true",
                      help="also sweep σ (and uniform) at one dwell: uniformity against "
                           "mirror acceleration")
    what.add_argument("--compare", action="store_true",
                      help="also spiral against line-by-line raster on 50x20 and 20x80 mm")
    what.add_argument("--wobble", action="store_true",
                      help="instead: a line marked in vector mode with the wobble figure "
                           "(circles), amplitude and frequency swept: track width, dose "
                           "across and along it, how far the mirror follows")
    what.add_argument("--wobble-speed", type=number_in("wobble speed", 1, 10_000),
                      default=50.0, metavar="MM_S",
                      help="line speed for --wobble, mm/s (default: 50)")
    what.add_argument("--delays", action="store_true",
                      help="instead: the RTC laser and scanner delays on an L-shaped vector "
                           "mark (dose at its ends and corner without and with the delays "
                           "that keep them within 20 %% of mid-line; figure delays.png)")
    what.add_argument("--sky", action="store_true",
                      help="instead: SkyWriting (mode 2, Timelag the galvo's tracking error) "
                           "against the delays and against nothing on an L-shaped mark, marked "
                           "on the simulated board and its frames run through the galvo model: "
                           "dose at its ends and corner, pulses off the L (figure sky.png)")
    what.add_argument("--mark-speed", type=number_in("mark speed", 1, 10_000), default=1000.0,
                      metavar="MM_S", help="marking speed for --delays and --sky, mm/s "
                                           "(default: 1000)")
    what.add_argument("--out", type=output_dir, default="build/analysis", metavar="DIR",
                      help="where figures go (default: %(default)s)")
    what.add_argument("--no-plots", action="store_true", help="write no figures")
    what.add_argument("--json", action="store_true", help="print the numbers as JSON")
    what.add_argument("--quiet", action="store_true", help="no progress bar")
    analyze.set_defaults(run=_cmd_analyze)
