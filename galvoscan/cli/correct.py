"""``galvoscan correct …``: make, convert, inspect and upload distortion correction tables."""

import argparse
import json
from pathlib import Path
import sys

from tqdm import tqdm
import numpy as np

from ..correction.files import load_table, save_table, TableFileError
from ..correction.ftheta import fit_polynomial, PRINTED_COEFFICIENTS, TABLE_1, table_1_rows
from ..correction.measure import MeasurementError, read_pairs, table_from_measurement
from ..correction.model import ftheta_table, synthetic_head
from ..correction.upload import upload_table
from ..gateware.field.correction_table import TABLE_SIZES
from .args import add_link_options, fail as _fail, int_in, number_in as positive, open_link, \
    image_file, output_dir, output_file


__all__ = ["add_parsers"]


def _nodes(text):
    try:
        value = int(text)
    except ValueError:
        value = None
    if value not in TABLE_SIZES:
        raise argparse.ArgumentTypeError(f"nodes must be one of "
                                         f"{', '.join(map(str, TABLE_SIZES))}, not {text!r}")
    return value


def _grid(text):
    try:
        value = int(text)
    except ValueError:
        value = None
    if value is None or not 3 <= value <= 25:
        raise argparse.ArgumentTypeError(f"grid must be an integer from 3 to 25, not {text!r}")
    return value


def _save(path, table, *, source, units_per_mm=None):
    try:
        for warning in save_table(path, table, source=source, units_per_mm=units_per_mm):
            print(f"galvoscan: warning: {warning}", file=sys.stderr)
    except (TableFileError, OSError) as error:
        _fail(error)
    lens_file = Path(path).suffix.lower() in (".ctb", ".cor")
    nodes = 65 if lens_file else table.n
    resampled = f" (resampled from {table.n})" if nodes != table.n else ""
    print(f"{path}: {nodes} × {nodes} nodes{resampled}, dx {table.dx.min()} … {table.dx.max()}, "
          f"dy {table.dy.min()} … {table.dy.max()} galvo units")


def _load(path, nodes=None):
    try:
        return load_table(path, nodes=nodes)
    except TableFileError as error:
        _fail(error)


# --- model / table1 ----------------------------------------------------------------------------

def _cmd_model(args):
    try:
        table = ftheta_table(args.nodes, field_mm=args.field, focal_mm=args.focal, k=args.k,
                             method="polynomial" if args.polynomial else "exact")
    except ValueError as error:
        _fail(error)
    _save(args.output, table, units_per_mm=65536 / args.field,
          source=f"Liao & Chen f-theta {'polynomial' if args.polynomial else 'exact'} model, "
                 f"f = {args.focal} mm, field {args.field} mm, k = {args.k}")


def _cmd_table1(args):
    rows = table_1_rows()
    printed = table_1_rows(PRINTED_COEFFICIENTS)
    if args.json:
        print(json.dumps({"rows": [dict(zip(("x_mm", "y_mm", "exact_x", "exact_y",
                                             "residual_x", "residual_y"), r)) for r in rows],
                          "paper": TABLE_1, "fit": fit_polynomial()}, indent=2))
        return
    print("Liao & Chen (2016) Table 1, recomputed (rad). Paper's values in brackets.")
    print(f"{'X mm':>6} {'Y mm':>6} {'exact dphi_x':>22} {'exact dphi_y':>22} "
          f"{'residual x':>22} {'residual y':>22}")
    for row, paper in zip(rows, TABLE_1):
        cells = " ".join(f"{value:>+10.6f} [{ref:>+9.6f}]" for value, ref in
                         zip(row[2:], paper[2:]))
        print(f"{row[0]:>6} {row[1]:>6} {cells}")
    worst = max(abs(r[4]) for r in printed)
    print(f"\nWith the coefficients as printed in the paper the largest X residual is {worst:.4f} rad:"
          f" the cubic terms and the Y linear term are 10x too large there.")
    a, b, c, d = fit_polynomial()
    print(f"Least-squares fit of the same terms over +-150 mm: a = {a:.4g}, b = {b:.4g}, "
          f"c = {c:.4g}, d = {d:.4g}")


# --- measure / convert / job ------------------------------------------------------------------

def _cmd_measure(args):
    try:
        cx, cy, mx, my = read_pairs(args.pairs)
    except MeasurementError as error:
        _fail(error)
    try:
        table = table_from_measurement(cx, cy, mx, my, nodes=args.nodes, method=args.method)
    except MeasurementError as error:
        _fail(f"{args.pairs}: {error}")
    error = np.hypot(mx - cx, my - cy)
    print(f"{args.pairs}: {cx.shape[0]} × {cx.shape[0]} points, measured error max "
          f"{error.max():.1f}, mean {error.mean():.1f} galvo units; {args.method} table")
    _save(args.output, table, source=f"measured grid {args.pairs} ({args.method})")


def _cmd_convert(args):
    table = _load(args.input, args.nodes)
    _save(args.output, table, source=f"converted from {args.input}",
          units_per_mm=args.units_per_mm)


def _cmd_job(args):
    # Here: correction.photo takes 1.1 s to import; `galvoscan --help` need not wait.
    from ..correction.photo import calibration_job, job_text
    try:
        segments = calibration_job(args.grid, span=args.span, line_width=args.line_width)
    except MeasurementError as error:
        _fail(error)
    Path(args.output).write_text(job_text(
        segments, title=f"{args.grid} x {args.grid} spiral-filled circles over {args.span} "
                        f"units, line width {args.line_width}"))
    print(f"{args.output}: {len(segments)} segments ({args.grid * args.grid} circles); run "
          f"it with pitch = {args.line_width}")


# --- photo ----------------------------------------------------------------------------------

def _cmd_photo(args):
    # Here: correction.photo takes 1.1 s to import; `galvoscan --help` need not wait.
    import matplotlib.image
    from ..correction.photo import PhotoError, table_from_photo
    try:
        image = matplotlib.image.imread(args.image)
    except (OSError, ValueError, SyntaxError) as error:
        _fail(f"{args.image}: cannot read the photo ({error})")
    try:
        table = table_from_photo(image, args.grid, nodes=args.nodes, method=args.method,
                                 span=args.span, dark_marks=not args.light_marks)
    except PhotoError as error:
        _fail(f"{args.image}: {error}")
    _save(args.output, table, source=f"photo {args.image}, {args.grid} x {args.grid} grid")


def _cmd_synth_photo(args):
    # Here: matplotlib takes 0.4 s to import; `galvoscan --help` need not wait.
    import matplotlib
    matplotlib.use("Agg")
    # Here: matplotlib.pyplot takes 1.4 s to import; `galvoscan --help` need not wait.
    import matplotlib.pyplot as plt
    from ..correction.photo import calibration_job, render_photo
    head = synthetic_head(args.max_error)
    image, _ = render_photo(calibration_job(args.grid), head.land, grid=args.grid,
                            seed=args.seed)
    plt.imsave(args.output, image, cmap="gray", vmin=0.0, vmax=1.0)
    print(f"{args.output}: {args.grid} x {args.grid} plate marked by a head with "
          f"{args.max_error:g} units of f-theta distortion")


# --- show / study / upload --------------------------------------------------------------------

def _cmd_show(args):
    table = _load(args.table)
    print(f"{args.table}: {table.n} × {table.n} nodes, {table.node_spacing} units apart; dx "
          f"{table.dx.min()} … {table.dx.max()}, dy {table.dy.min()} … {table.dy.max()}")
    if args.png:
        # Here: correction.figures takes 1.4 s to import; `galvoscan --help` need not wait.
        from ..correction.figures import plot_table
        plot_table(args.png, table, title=str(args.table))
        print(f"  png: {args.png}")


def _cmd_study(args):
    # Here: correction.study takes 1.1 s to import; `galvoscan --help` need not wait.
    from ..correction.study import STUDY_STEPS, markdown_table, run_study
    with tqdm(total=STUDY_STEPS, desc="correction study", disable=args.quiet or None,
              file=sys.stderr) as bar:
        study = run_study(nodes=args.nodes, progress=bar.update)
    if args.json:
        print(json.dumps({k: v for k, v in study.items()
                          if k not in ("photo_image", "photo_table")}, indent=2))
    else:
        head = study["head"]
        print(f"Synthetic head: Liao & Chen f-theta distortion, f = {head['focal_mm']:g} mm on a "
              f"{head['field_mm']:.1f} mm field; measurement noise {study['noise_units']:g} "
              f"units per axis; tables of {study['nodes']} × {study['nodes']} nodes.\n")
        print(markdown_table(study))
        photo = study["photo"]
        print(f"\nPhoto pipeline ({photo['pixels']} px, {photo['units_per_px']:.1f} units/px): "
              f"circle centres within {photo['centre_error_max']:.0f} units (mean "
              f"{photo['centre_error_mean']:.1f}).")
    if not args.no_plots:
        # Here: correction.figures takes 1.4 s to import; `galvoscan --help` need not wait.
        from ..correction.figures import plot_study
        for path in plot_study(study, args.out):
            print(f"  figure: {path}", file=sys.stderr)


def _cmd_upload(args):
    # Here: link.client takes 0.1 s to import; `galvoscan --help` need not wait.
    from ..link.client import ClientError, HostClient
    table = _load(args.table)
    with open_link(args) as link:
        board = HostClient(link)
        try:
            nodes = board.read("cor_nodes")
            if nodes != table.n:
                table = table.resampled(nodes)
                print(f"resampled to the board's {nodes} × {nodes} nodes")
            upload_table(board, table, verify=args.verify)
        except (ClientError, ValueError) as error:
            _fail(error)
    print(f"{args.table}: {table.n * table.n} nodes written")


def add_parsers(commands):
    """The ``correct`` command and its steps."""
    correct = commands.add_parser(
        "correct", help="make, convert, inspect and upload distortion correction tables",
        description="Field-distortion correction tables: from the f-theta lens model (Liao & "
                    "Chen 2016), from measured points or a photo of a calibration plate (Zhu & "
                    "Zhang), from SCANLAB .ctb and JCZ .cor files. Tables are galvoscan .json, "
                    ".ctb or .cor by the file name's suffix.")
    steps = correct.add_subparsers(dest="step", required=True, metavar="STEP")
    nodes_help = "nodes per axis of the table: 5, 9, 17, 33 or 65 (default: %(default)s)"
    method_help = ("bilinear grid of the measured errors, or a least-squares cubic polynomial "
                   "(default: %(default)s)")

    def output(parser, what, metavar="FILE"):
        parser.add_argument("-o", "--output", type=output_file, required=True, metavar=metavar,
                            help=f"{what} to write (its folder is made if missing)")

    model = steps.add_parser("model", help="table from the f-theta lens model",
                             description="A table from the f-theta lens model of Liao & Chen "
                                         "(2016): its exact formula, or its fitted polynomial.")
    model.add_argument("--field", type=positive("field", 1, 2000), required=True, metavar="MM",
                       help="lens field: the width 65536 galvo units span")
    model.add_argument("--focal", type=positive("focal length", 10, 5000), default=300.0,
                       metavar="MM", help="f-theta focal length (default: %(default)s)")
    model.add_argument("--k", type=positive("k", 0.5, 2.0), default=1.0,
                       help="the model's focal-length trim factor for --polynomial "
                            "(0.9706 … 1.0306; default: %(default)s)")
    model.add_argument("--polynomial", action="store_true",
                       help="use the paper's fitted polynomial instead of its exact formula")
    model.add_argument("--nodes", type=_nodes, default=17, help=nodes_help)
    output(model, "the table (.json, .ctb or .cor)")
    model.set_defaults(run=_cmd_model)

    table1 = steps.add_parser("table1", help="recompute the f-theta model's Table 1",
                              description="Recompute Table 1 of Liao & Chen (2016) and show "
                                          "where its printed coefficients are off.")
    table1.add_argument("--json", action="store_true", help="print the rows as JSON")
    table1.set_defaults(run=_cmd_table1)

    measure = steps.add_parser("measure", help="table from measured grid points (CSV)",
                               description="PAIRS: CSV rows cmd_x, cmd_y, meas_x, meas_y in "
                                           "galvo units, one per point of an n x n grid.")
    measure.add_argument("pairs", metavar="PAIRS", help="the CSV of commanded and measured "
                                                        "points")
    measure.add_argument("--method", choices=["bilinear", "polynomial"], default="bilinear",
                         help=method_help)
    measure.add_argument("--nodes", type=_nodes, default=17, help=nodes_help)
    output(measure, "the table (.json, .ctb or .cor)")
    measure.set_defaults(run=_cmd_measure)

    convert = steps.add_parser("convert", help="convert between .json, .ctb and .cor",
                               description="Read a table and write it in the format of the "
                                           "output's suffix.")
    convert.add_argument("input", metavar="IN", help="the table to read (.json, .ctb, .cor)")
    output(convert, "the table (.json, .ctb or .cor)", metavar="OUT")
    convert.add_argument("--nodes", type=_nodes, default=None,
                         help="resample to this many nodes per axis (default: keep)")
    convert.add_argument("--units-per-mm", type=positive("units per mm", 1e-3, 1e6),
                         default=None, help="lens scale recorded in a .cor file")
    convert.set_defaults(run=_cmd_convert)

    job = steps.add_parser("job", help="write the calibration job (spiral-filled circles)",
                           description="A vector job that marks an n x n grid of spiral-filled "
                                       "circles and four reference marks (Zhu & Zhang's plate).")
    job.add_argument("--grid", type=_grid, default=9, help="circles per side (default: 9)")
    job.add_argument("--span", type=positive("span", 1000, 65000), default=50000.0,
                     help="calibrated square in galvo units (default: 50000)")
    job.add_argument("--line-width", type=int_in(1, 10000, "line width"), default=60,
                     help="galvo units between spiral turns (default: 60 = the pitch)")
    output(job, "the job")
    job.set_defaults(run=_cmd_job)

    photo = steps.add_parser("photo", help="table from a photo of the calibration plate",
                             description="Find the circles and reference marks on a photo of "
                                         "the marked plate, and make a table from them.")
    photo.add_argument("image", metavar="PHOTO", help="PNG of the marked plate")
    photo.add_argument("--grid", type=_grid, required=True, help="circles per side")
    photo.add_argument("--span", type=positive("span", 1000, 65000), default=50000.0,
                       help="calibrated square the job spanned, galvo units (default: 50000)")
    photo.add_argument("--method", choices=["bilinear", "polynomial"], default="bilinear",
                       help=method_help)
    photo.add_argument("--nodes", type=_nodes, default=17, help=nodes_help)
    photo.add_argument("--light-marks", action="store_true",
                       help="marks are lighter than the plate (default: darker)")
    output(photo, "the table (.json, .ctb or .cor)")
    photo.set_defaults(run=_cmd_photo)

    synth = steps.add_parser("synth-photo", help="render a synthetic calibration photo",
                             description="Render the plate a distorting head would mark, as a "
                                         "photo, to try the photo step without a camera.")
    synth.add_argument("--grid", type=_grid, default=9, help="circles per side (default: 9)")
    synth.add_argument("--max-error", type=positive("max error", 1, 10000), default=1400.0,
                       help="head distortion at worst, galvo units (default: 1400, as Zhu & "
                            "Zhang measured)")
    synth.add_argument("--seed", type=int_in(0, 2**32 - 1, "seed"), default=0,
                       help="noise seed (default: 0)")
    synth.add_argument("-o", "--output", type=image_file, required=True, metavar="PNG",
                       help="the photo to write (.png; its folder is made if missing)")
    synth.set_defaults(run=_cmd_synth_photo)

    show = steps.add_parser("show", help="summarise (and plot) a table",
                            description="Print a table's size and offsets; plot them.")
    show.add_argument("table", metavar="FILE", help="the table (.json, .ctb, .cor)")
    show.add_argument("--png", type=image_file, metavar="FILE",
                      help="plot the offsets (.png, .svg, .pdf, …)")
    show.set_defaults(run=_cmd_show)

    study = steps.add_parser("study", help="the docs' calibration study (synthetic head)",
                             description="Calibrate a synthetic head every way galvoscan can "
                                         "and tabulate the residual errors.")
    study.add_argument("--nodes", type=_nodes, default=17, help=nodes_help)
    study.add_argument("--out", type=output_dir, default="build/correction", metavar="DIR",
                       help="where figures go (default: %(default)s)")
    study.add_argument("--no-plots", action="store_true", help="write no figures")
    study.add_argument("--json", action="store_true", help="print the numbers as JSON")
    study.add_argument("--quiet", action="store_true", help="no progress bar")
    study.set_defaults(run=_cmd_study)

    upload = steps.add_parser("upload", help="write a table into a running board",
                              description="Write every node of a table through the host link "
                                          "(resampled to the board's node count).")
    upload.add_argument("table", metavar="FILE", help="the table (.json, .ctb, .cor)")
    upload.add_argument("--verify", action="store_true",
                        help="check the board rejected no frame")
    add_link_options(upload)
    upload.set_defaults(run=_cmd_upload)
