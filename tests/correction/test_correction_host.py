"""Correction tables on the host: the f-theta model (Liao & Chen 2016), measured grids, lens
files, the photo pipeline and ``galvoscan correct``."""

import csv
import json
import struct

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st, HealthCheck

from galvoscan.cli import main
from galvoscan.correction import ftheta
from galvoscan.correction.files import TableFileError, load_table, read_cor, read_ctb, \
    read_json, save_table, write_cor, write_ctb, write_json
from galvoscan.correction.measure import GRID_SIZES, MeasurementError, calibration_grid, \
    error_model, residuals, table_from_measurement
from galvoscan.correction.model import ScanHeadModel, ftheta_table, synthetic_head
from galvoscan.correction.photo import PhotoError, apply_homography, calibration_job, \
    find_marks, homography, measure_photo, render_photo, table_from_photo
from galvoscan.gateware.field.correction_table import CorrectionTable
from galvoscan.inputs.job_file import parse_job


# --- Liao & Chen 2016: the f-theta model ---------------------------------------------------------

def test_table_1_exact_columns_match_the_paper():
    for row, paper in zip(ftheta.table_1_rows(), ftheta.TABLE_1):
        assert row[:2] == paper[:2]
        # The paper prints 4 decimals.
        assert round(row[2], 4) == paper[2] and round(row[3], 4) == paper[3]


def test_table_1_residuals_match_with_the_corrected_exponents():
    rows = ftheta.table_1_rows()
    mismatches = []
    for row, paper in zip(rows, ftheta.TABLE_1):
        for ours, theirs in zip(row[4:], paper[4:]):
            if round(ours, 6) != theirs:
                mismatches.append((row[:2], ours, theirs))
    # One entry differs: (-100, -100) dy, printed 0.000059, 0.000089 by the formula and by the
    # table's own symmetry (its (100, -100) entry).
    assert len(mismatches) == 1 and mismatches[0][0] == (-100, -100)
    assert round(mismatches[0][1], 6) == 0.000089 == ftheta.TABLE_1[6][5]
    # With the coefficients as printed the residual at (150, 150) is ~0.1 rad, not 0.0004.
    printed = ftheta.table_1_rows(ftheta.PRINTED_COEFFICIENTS)
    assert abs(printed[0][4]) > 0.09
    # A least-squares fit of the four terms lands near the corrected values.
    a, b, c, d = ftheta.fit_polynomial()
    assert a == pytest.approx(-3.242e-9, rel=0.01) and c == pytest.approx(6.515e-9, rel=0.01)
    assert max(abs(r[4]) for r in rows) < 0.0005         # "residual < 0.0004 rad" (about)


def test_exact_compensation_inverts_the_landing_formula():
    rng = np.random.default_rng(0)
    x, y = rng.uniform(-150, 150, (2, 500))
    dx, dy = ftheta.exact_compensation(x, y)
    lx, ly = ftheta.landing(x / 600 + dx, y / 600 + dy)
    assert np.allclose(lx, x, atol=1e-9) and np.allclose(ly, y, atol=1e-9)
    # On the axis both are regular: no correction, no error.
    assert ftheta.exact_compensation(0.0, 0.0) == (0.0, 0.0)
    assert ftheta.landing(0.0, 0.0) == (0.0, 0.0)


def test_synthetic_head_has_004s_size_and_the_model_table_undoes_it():
    head = synthetic_head()
    before = residuals(head.land)
    assert before["before_max"] == pytest.approx(1400, abs=1)
    assert 200 < before["before_mean"] < 300                  # Zhu & Zhang: 259
    # On the axes the f-theta lens is exact; at a corner X is pulled out (pincushion) and Y
    # pulled in (barrel), as Liao & Chen and Zhu & Zhang describe.
    lx, ly = head.land(np.array([57768.0, 57768.0]), np.array([32768.0, 57768.0]))
    assert abs(lx[0] - 57768) < 1e-6 and abs(ly[0] - 32768) < 1e-6
    assert lx[1] - 57768 > 500 and ly[1] - 57768 < -1000
    exact = residuals(head.land, ftheta_table(17, field_mm=head.field_mm))
    assert exact["after_max"] < 15 and exact["removed"] > 0.98
    finer = residuals(head.land, ftheta_table(65, field_mm=head.field_mm))
    assert finer["after_mean"] < exact["after_mean"]
    poly = residuals(head.land, ftheta_table(17, field_mm=head.field_mm, method="polynomial"))
    # Liao & Chen's polynomial is fitted to a 300 mm lens over ±150 mm: on this 302 mm field,
    # close.
    assert poly["removed"] > 0.9


@pytest.mark.parametrize("kwargs, message", [
    ({"field_mm": -1}, "field_mm must be a positive number"),
    ({"field_mm": 100, "k": 1.01}, "k trims the polynomial"),
    ({"field_mm": 100, "k": 7}, "k must be a number near 1"),
    ({"field_mm": 100, "method": "spline"}, "method must be exact or polynomial"),
    ({"field_mm": 1800}, "too wide for that lens"),
])
def test_model_table_rejects_bad_parameters(kwargs, message):
    with pytest.raises(ValueError, match=message):
        ftheta_table(17, **kwargs)


# --- Zhu & Zhang: tables from measured points ----------------------------------------------------

def test_affine_error_is_removed_exactly_by_a_3x3_bilinear_table():
    """A head that scales, shears and shifts: bilinear interpolation represents it exactly, so
    the table leaves only rounding."""
    def land(x, y):
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        return 1.01 * (x - 32768) + 0.004 * (y - 32768) + 32768 + 40, \
            0.995 * (y - 32768) - 0.003 * (x - 32768) + 32768 - 25
    cx, cy = calibration_grid(3)
    mx, my = land(cx, cy)
    table = table_from_measurement(cx, cy, mx, my, nodes=17)
    result = residuals(land, table)
    assert result["before_max"] > 200 and result["after_max"] < 2.5


def test_denser_grids_and_fits_help_on_the_synthetic_head():
    head = synthetic_head()
    rng = np.random.default_rng(2)
    means = {}
    for grid in GRID_SIZES:
        cx, cy = calibration_grid(grid)
        lx, ly = head.land(cx, cy)
        mx, my = lx + rng.normal(0, 15, lx.shape), ly + rng.normal(0, 15, ly.shape)
        for method in ("bilinear", "polynomial"):
            table = table_from_measurement(cx, cy, mx, my, method=method)
            means[grid, method] = residuals(head.land, table)["after_mean"]
    assert means[3, "bilinear"] > means[5, "bilinear"] > means[11, "bilinear"]
    assert means[11, "bilinear"] < 36.5                     # Zhu & Zhang's result after correction
    # On this smooth (f-theta) distortion a cubic fit beats piecewise-bilinear at every size.
    assert all(means[g, "polynomial"] < means[g, "bilinear"] for g in GRID_SIZES)


@pytest.mark.parametrize("change, message", [
    (lambda cx, cy, mx, my: (cx[:, :2], cy, mx, my), "square grid"),
    (lambda cx, cy, mx, my: (cx[::-1], cy[::-1], mx, my), "rows in Y"),
    (lambda cx, cy, mx, my: (cx, cy, mx[:, ::-1], my), "more than a grid spacing"),
    (lambda cx, cy, mx, my: (cx, cy, mx * np.nan, my), "finite numbers"),
    (lambda cx, cy, mx, my: (cx + np.arange(3)[:, None], cy, mx, my), "not on a grid"),
])
def test_measurement_rejects_bad_points(change, message):
    cx, cy = calibration_grid(3)
    mx, my = cx + 5.0, cy - 5.0
    with pytest.raises(MeasurementError, match=message):
        error_model(*change(cx, cy, mx, my))


# --- lens files ---------------------------------------------------------------------------------

def in_field_table(n=65, seed=0):
    rng = np.random.default_rng(seed)
    dx = rng.integers(-800, 801, (n, n))
    dy = rng.integers(-800, 801, (n, n))
    # Keep outputs inside 0 … 65535 at the edges, as a real lens file's are.
    dx[:, 0] = np.abs(dx[:, 0])
    dx[:, -1] = -np.abs(dx[:, -1]) - 1
    dy[0, :] = np.abs(dy[0, :])
    dy[-1, :] = -np.abs(dy[-1, :]) - 1
    return CorrectionTable(dx, dy)


def test_ctb_layout_written_by_hand():
    """A .ctb made here word by word (absolute outputs, X table then Y, X index fastest)."""
    identity = [min(i * 1024, 65535) for i in range(65)]
    words = []
    for table in ("x", "y"):
        for iy in range(65):
            for ix in range(65):
                base = identity[ix] if table == "x" else identity[iy]
                bump = 7 if (table, ix, iy) == ("x", 3, 1) else \
                    -9 if (table, ix, iy) == ("y", 64, 2) else 0
                words.append(base + bump)
    table = read_ctb(struct.pack("<8450H", *words))
    assert table.n == 65
    assert table.dx[1, 3] == 7 and table.dy[2, 64] == -9
    assert np.count_nonzero(table.dx) == 1 and np.count_nonzero(table.dy) == 1
    assert write_ctb(table) == struct.pack("<8450H", *words)


def test_lens_files_round_trip():
    table = in_field_table()
    assert read_ctb(write_ctb(table)) == table
    assert read_ctb(write_ctb(table, signed=True), signed=True) == table
    again, scale = read_cor(write_cor(table, units_per_mm=595.78))
    assert again == table and scale == 595.78
    assert read_json(write_json(table, source="test")) == table
    small = in_field_table(17, seed=1)
    assert read_ctb(write_ctb(small)).resampled(17) == small


def test_cor_version_1_is_read():
    header = "LMC1COR_1.0".encode("utf-16-le").ljust(0x16, b"\0") + bytes(2)
    values = [0.0] * 63
    values[43] = 480.5
    pairs = np.zeros((65, 65, 2))
    pairs[10, 20] = (12.4, -3.6)
    data = header + struct.pack("<63d", *values) + pairs.astype("<f8").tobytes()
    table, scale = read_cor(data)
    assert scale == 480.5 and table.dx[10, 20] == 12 and table.dy[10, 20] == -4


def test_files_by_name(tmp_path):
    table = in_field_table(17, seed=3)
    for suffix in (".json", ".ctb", ".cor"):
        path = tmp_path / f"t{suffix}"
        assert save_table(path, table, units_per_mm=500.0) == []
        assert load_table(path, nodes=17) == table
    with pytest.raises(TableFileError, match="unknown table format .txt"):
        load_table(tmp_path / "t.txt")
    with pytest.raises(TableFileError, match="No such file"):
        load_table(tmp_path / "missing.json")
    with pytest.raises(TableFileError, match="give units_per_mm"):
        save_table(tmp_path / "x.cor", table)
    # A table aiming beyond the field loses those nodes in a .ctb, and says so.
    wide = CorrectionTable(np.full((17, 17), -500), np.zeros((17, 17), dtype=int))
    warnings = save_table(tmp_path / "wide.ctb", wide)
    assert warnings and "65 of 4225 nodes aim beyond the field" in warnings[0]


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.binary(max_size=40000), st.sampled_from(["ctb", "cor", "json"]))
def test_random_bytes_give_a_clear_error(data, kind):
    """Truncated, garbage or random files: a TableFileError, never anything else."""
    try:
        if kind == "ctb":
            read_ctb(data)
        elif kind == "cor":
            read_cor(data)
        else:
            read_json(data)
    except TableFileError:
        pass


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 8449 * 2), st.sampled_from(["ctb", "cor"]))
def test_cut_short_lens_files_are_refused(cut, kind):
    table = in_field_table(65, seed=4)
    data = write_ctb(table) if kind == "ctb" else write_cor(table, units_per_mm=1.0)
    with pytest.raises(TableFileError):
        (read_ctb if kind == "ctb" else read_cor)(data[:cut])


@pytest.mark.parametrize("document, message", [
    ({"format": "other"}, "not a galvoscan correction table"),
    ({"format": "galvoscan-correction-table", "version": 2}, "version 2"),
    ({"format": "galvoscan-correction-table", "version": 1, "nodes": 4}, "nodes must be"),
    ({"format": "galvoscan-correction-table", "version": 1, "nodes": 5, "dx": [[0] * 5] * 4,
      "dy": [[0] * 5] * 5}, "dx must be 5 rows of 5 integers"),
    ({"format": "galvoscan-correction-table", "version": 1, "nodes": 5, "dx": [[0] * 5] * 5,
      "dy": [[40000] * 5] * 5}, "beyond ±32767"),
])
def test_json_errors(document, message):
    with pytest.raises(TableFileError, match=message):
        read_json(json.dumps(document))


# --- the photo pipeline -------------------------------------------------------------------------

def test_homography_recovers_a_known_one():
    truth = np.array([[1.2, 0.1, 30.0], [-0.05, 0.9, -12.0], [1e-4, -2e-4, 1.0]])
    source = np.random.default_rng(1).uniform(-500, 500, (9, 2))
    found = homography(source, apply_homography(truth, source))
    assert np.allclose(found, truth, rtol=1e-6, atol=1e-9)
    with pytest.raises(PhotoError, match="at least four"):
        homography(source[:3], source[:3])


def test_calibration_job_is_a_valid_vector_job():
    segments = calibration_job(5)
    text = "\n".join(f"{op} {x} {y}" for op, x, y in segments)
    assert parse_job(text) == segments
    assert sum(op == "jump" for op, _, _ in segments) == 25
    # Each circle is filled: the spiral's turns are one line width apart out to the rim.
    first = [(x, y) for op, x, y in segments[1:] if op == "mark"][:2000]
    radii = np.hypot(*(np.array(first[:400]) - np.array(segments[0][1:])).T)
    assert radii.max() <= 1500 + 1 and np.all(np.diff(radii[:200]) > -1)


@pytest.fixture(scope="module")
def photo_9():
    head = synthetic_head()
    image, camera = render_photo(calibration_job(9), head.land, grid=9, seed=3)
    return head, image, camera


def test_photo_centres_and_table(photo_9):
    """Circle centres from a blurred, noisy, tilted synthetic photo are within 25 galvo units
    (mean under 12: a third of a pixel at 36 units per pixel) of where the head really put them,
    and the table built from them removes at least 93 % of the mean error (Zhu & Zhang's
    figure is 86 %). The blob centroids measure 13 / 7 here; the minimum enclosing circle the
    paper uses measured 45 / 17 on the same photo."""
    head, image, _ = photo_9
    cx, cy, mx, my = measure_photo(image, 9)
    lx, ly = head.land(cx, cy)
    error = np.hypot(mx - lx, my - ly)
    assert error.max() < 25 and error.mean() < 12
    table = table_from_photo(image, 9)
    result = residuals(head.land, table)
    assert result["removed"] >= 0.93, result


def test_photo_turned_and_mirrored_still_pairs(photo_9):
    head, image, _ = photo_9
    reference = measure_photo(image, 9)
    for variant in (np.rot90(image), np.fliplr(image), np.rot90(np.flipud(image), 3)):
        again = measure_photo(variant, 9)
        assert np.allclose(again[2], reference[2], atol=25)
        assert np.allclose(again[3], reference[3], atol=25)


def test_photo_errors_are_clear(photo_9):
    _, image, _ = photo_9
    with pytest.raises(PhotoError, match="found 85 marks; a 7 × 7 calibration plate"):
        measure_photo(image, 7)
    with pytest.raises(PhotoError, match="found 0 marks|reference marks"):
        measure_photo(np.full((300, 300), 0.8), 9)
    with pytest.raises(PhotoError, match="grey-scale or colour image"):
        find_marks(np.zeros(10))


# --- galvoscan correct ----------------------------------------------------------------------------

def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_cli_model_convert_show(tmp_path, capsys):
    table = tmp_path / "lens.json"
    code, out, _ = run(capsys, "correct", "model", "--field", "302", "-o", str(table))
    assert code == 0 and "17 × 17 nodes" in out
    assert load_table(table) == ftheta_table(17, field_mm=302.0)
    code, out, err = run(capsys, "correct", "convert", str(table), "-o",
                         str(tmp_path / "lens.ctb"))
    assert "65 × 65 nodes (resampled from 17)" in out and "clipped" in err
    code, out, _ = run(capsys, "correct", "convert", str(tmp_path / "lens.ctb"), "-o",
                       str(tmp_path / "lens.cor"), "--units-per-mm", "217")
    assert code == 0
    code, out, _ = run(capsys, "correct", "show", str(tmp_path / "lens.cor"), "--png",
                       str(tmp_path / "lens.png"))
    assert "65 × 65 nodes, 1024 units apart" in out and (tmp_path / "lens.png").stat().st_size
    code, out, _ = run(capsys, "correct", "table1")
    assert "-0.000404 [-0.000404]" in out


def test_cli_measure_from_csv(tmp_path, capsys):
    head = synthetic_head()
    cx, cy = calibration_grid(5)
    lx, ly = head.land(cx, cy)
    path = tmp_path / "pairs.csv"
    with open(path, "w", newline="") as file:
        writer = csv.writer(file)
        writer.writerow(["cmd_x", "cmd_y", "meas_x", "meas_y"])
        for row in np.c_[cx.ravel(), cy.ravel(), lx.ravel(), ly.ravel()][::-1]:
            writer.writerow([f"{v:.1f}" for v in row])
    code, out, _ = run(capsys, "correct", "measure", str(path), "-o", str(tmp_path / "m.json"))
    assert code == 0 and "5 × 5 points" in out
    assert residuals(head.land, load_table(tmp_path / "m.json"))["removed"] > 0.85


def test_cli_job_and_photo(tmp_path, capsys):
    code, out, _ = run(capsys, "correct", "job", "--grid", "3", "-o", str(tmp_path / "c.job"))
    assert code == 0 and "9 circles" in out
    assert parse_job((tmp_path / "c.job").read_text())[0][0] == "jump"
    png = tmp_path / "plate.png"
    run(capsys, "correct", "synth-photo", "--grid", "5", "-o", str(png))
    code, out, _ = run(capsys, "correct", "photo", str(png), "--grid", "5", "-o",
                       str(tmp_path / "p.json"))
    assert code == 0 and load_table(tmp_path / "p.json").n == 17


@pytest.mark.parametrize("argv, message", [
    (["correct", "model", "--field", "0", "-o", "x.json"], "field must be from"),
    (["correct", "model", "--field", "100", "--nodes", "16", "-o", "x.json"],
     "nodes must be one of"),
    (["correct", "job", "--grid", "2", "-o", "x.job"], "grid must be an integer from 3"),
    (["correct", "convert", "nothere.ctb", "-o", "x.json"], "No such file"),
    (["correct", "photo", "nothere.png", "--grid", "5", "-o", "x.json"], "cannot read"),
    (["correct", "measure", "nothere.csv", "-o", "x.json"], "No such file"),
])
def test_cli_errors(argv, message, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    text = str(exit_info.value) + capsys.readouterr().err
    assert message in text


def test_cli_measure_rejects_a_broken_csv(tmp_path, capsys):
    path = tmp_path / "bad.csv"
    path.write_text("1,2,3,4\n5,6,7\n")
    with pytest.raises(SystemExit, match="3 values; a row is cmd_x"):
        main(["correct", "measure", str(path), "-o", str(tmp_path / "x.json")])
    path.write_text("1,2,3,4\n5,6,7,8\n9,9,9,9\n")
    with pytest.raises(SystemExit, match="do not make a square grid"):
        main(["correct", "measure", str(path), "-o", str(tmp_path / "x.json")])


def test_head_model_rejects_bad_parameters():
    with pytest.raises(ValueError, match="field_mm must be a positive"):
        ScanHeadModel(field_mm=float("nan"))


def test_cli_sim_carries_the_corrected_spiral(tmp_path, capsys):
    """`galvoscan sim --correction`: the frames decoded from the wires are the spiral model's
    points through the table's reference arithmetic."""
    from galvoscan.gateware.sources.spiral_table import SpiralTable
    from spiral_model import spiral_points
    table = ftheta_table(17, field_mm=302.0)
    (tmp_path / "t.json").write_text(write_json(table))
    # (Amaranth's simulator: 32 frames, shorter than a compile of this table's build.)
    code, _, _ = run(capsys, "sim", "--points", "30", "--dwell", "1", "--csv",
                     str(tmp_path / "s.csv"), "--correction", str(tmp_path / "t.json"),
                     "--backend", "python")
    assert code == 0
    with open(tmp_path / "s.csv") as file:
        rows = [tuple(int(v) for v in row[1:]) for row in list(csv.reader(file))[1:]]
    spiral = SpiralTable()
    points = spiral_points(spiral.x, spiral.y, 30, x_range=(0, 127), y_range=(1, 126))
    x, y, _ = table.apply([p[0] for p in points], [p[1] for p in points])
    assert rows[2:] == list(zip(x.tolist(), y.tolist()))
    assert rows[:2] == [(32768, 32768)] * 2          # the park position is corrected too: 0 there
