"""Codes (galvoscan/inputs/codes.py, `mark --code`): the modules zxing-cpp makes, as shapes;
and the marks the simulated board puts on the XY2-100 wires, drawn at the spot's size and
read back by zxing-cpp's decoder (a reader written apart from the encoder's use here)."""

import json

from hypothesis import given, strategies as st
import numpy as np
import pytest

from galvoscan.cli import main
from galvoscan.inputs.codes import DATA_SHOWN, CodeSpec, code_drawing, code_modules, data_said
from galvoscan.geometry.field import PlanError

from sim_board import VECTOR_BOARD, quick_sim_board


def test_modules_and_shapes():
    """A QR of "SN 0042" is 21 × 21 modules (version 1); its three finder patterns are 7 × 7
    dark rings with a 3 × 3 centre; as a drawing 8 mm wide its modules are 8/21 mm, and its
    shapes' area is the dark modules' (the light ones inside are holes)."""
    import shapely
    from shapely.geometry import Polygon
    spec = CodeSpec("qr", "SN 0042", 8)
    dark = code_modules(spec)
    assert dark.shape == (21, 21)
    finder = np.ones((7, 7), bool)
    finder[1:6, 1:6] = False
    finder[2:5, 2:5] = True
    for rows, cols in [(slice(0, 7), slice(0, 7)), (slice(0, 7), slice(14, 21)),
                       (slice(14, 21), slice(0, 7))]:
        assert np.array_equal(dark[rows, cols], finder)
    drawing, module = code_drawing(spec)
    assert module == pytest.approx(8 / 21)
    assert drawing.bounds() == pytest.approx((0, 0, 8, 8))
    area = 0.0
    for path in drawing.paths:
        area = shapely.symmetric_difference(area and area or Polygon(), Polygon(path)) \
            if not isinstance(area, float) else Polygon(path)
    assert area.area == pytest.approx(dark.sum() * module ** 2, rel=1e-9)


def test_code128_bars_are_filled_along_their_length(capsys):
    """A Code 128's bars are filled with lines along them: 20 mm of code, 4 mm high, at a 50 µm
    spot is some 1,200 segments (lines across them, one every 25 µm of the height: 11,315)."""
    assert main(["mark", "--code", "code128", "--data", "LOT 7731", "--size", "20",
                 "--code-height", "4", "--estimate", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["segments"] < 1500
    assert record["bounds_mm"][3] - record["bounds_mm"][1] == pytest.approx(4, abs=0.01)


def test_code128_is_bars():
    spec = CodeSpec("code128", "ABC-123", 30, height_mm=6)
    dark = code_modules(spec)
    assert dark.shape[0] == 1 and dark[0, 0] and dark[0, -1]     # starts and ends on a bar
    drawing, module = code_drawing(spec)
    assert drawing.bounds() == pytest.approx((0, 0, 30, 6))
    bars = [p for p in drawing.paths if np.ptp(p[:, 1]) == pytest.approx(6)]
    edges = np.flatnonzero(np.diff(np.concatenate([[0], dark[0].astype(int), [0]])))
    assert len(bars) == len(edges) // 2


@pytest.mark.parametrize("kwargs, words", [
    (dict(kind="qr", data="", size_mm=5), "needs data"),
    (dict(kind="qr", data="x", size_mm=0.1), "from 0.5 to 500"),
    (dict(kind="qr", data="x", size_mm=5, ec_level="Z"), "one of L, M, Q, H"),
    (dict(kind="datamatrix", data="x", size_mm=5, ec_level="H"), "QR's"),
    (dict(kind="qr", data="x" * 8000, size_mm=5), "cannot hold"),
])
def test_impossible_codes_are_one_line(kwargs, words):
    with pytest.raises(PlanError, match=words):
        code_drawing(CodeSpec(**kwargs))


def read_marks(marks, size_mm, *, spot_mm, module_mm, px_mm=0.02, margin_mm=2.0):
    """The marks as an image (each a disc of the spot, black on white), seen as a code
    reader's camera sees a part, some three or four pixels a module, and read by zxing-cpp."""
    import zxingcpp
    from PIL import Image
    n = int(round((size_mm + 2 * margin_mm) / px_mm))
    image = np.full((n, n), 255, np.uint8)
    yy, xx = np.mgrid[0:n, 0:n]
    r = spot_mm / 2 / px_mm
    for x, y in marks:
        cx, cy = (x + margin_mm) / px_mm, (size_mm + margin_mm - y) / px_mm     # Y down
        box = (slice(max(0, int(cy - r - 1)), int(cy + r + 2)),
               slice(max(0, int(cx - r - 1)), int(cx + r + 2)))
        disc = (xx[box] - cx) ** 2 + (yy[box] - cy) ** 2 <= r * r
        image[box][disc] = 0
    shrink = max(1, round(module_mm / px_mm / 3.5))
    seen = Image.fromarray(image).resize((n // shrink, n // shrink), Image.BOX)
    found = zxingcpp.read_barcode(seen)
    return None if found is None else (found.text, found.format.name)


PROFILE = "[laser]\nspot_mm = {spot}\n[galvo]\njump_delay_us = 100\n"


@pytest.mark.slow
@pytest.mark.parametrize("args, spot, size, kind", [
    (["--code", "qr", "--data", "SN 0042", "--size", "5"], 0.1, 5, "QRCode"),
    (["--code", "datamatrix", "--data", "GS-2026-12", "--size", "4"], 0.1, 4, "DataMatrix"),
    (["--code", "code128", "--data", "LOT 7731", "--size", "20", "--code-height", "4"], 0.1,
     20, "Code128"),
    (["--code", "qr", "--data", "DOTS", "--size", "6.3", "--code-fill", "dots"], 0.36, 6.3,
     "QRCode"),
])
def test_a_marked_code_reads_back_off_the_wires(args, spot, size, kind, tmp_path, capsys):
    machine = tmp_path / "machine.toml"
    machine.write_text(PROFILE.format(spot=spot))
    with quick_sim_board(**VECTOR_BOARD):
        assert main(["mark", *args, "--speed", "2000", "--prr", "50", "--machine",
                     str(machine), "--sim", "--timeout", "600", "--json"]) == 0
    result = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert result["errors"] == result["underruns"] == result["rejected"] == 0
    data = args[args.index("--data") + 1]
    module = size / code_modules(CodeSpec(args[1], data, size)).shape[1]
    assert read_marks(result["drawing_marks"], size, spot_mm=spot, module_mm=module) == \
        (data, kind)


@pytest.mark.parametrize("args, words", [
    (["--data", "A" * 3000, "--size", "5"], "modules of 30 µm, less than the 50 µm spot"),
    (["--data", "hello", "--size", "0.5"], "modules of 24 µm, less than the 50 µm spot"),
    (["--data", "x", "--size", "5", "--code-height", "5"], "--code-height is Code 128's"),
    (["--data", "hello", "--size", "0.7", "--code-fill", "dots"],
     "modules of 33 µm, less than the 50 µm spot \\(a dot may be 4/3 of its module\\)"),
])
def test_a_code_too_fine_for_the_spot_is_refused(args, words):
    """(And a bar height is Code 128's only.)"""
    """A module narrower than the spot (the default profile's 50 µm) cannot be marked apart
    from its neighbours: a code too long for its size is refused before anything is sent."""
    with pytest.raises(SystemExit, match=words):
        main(["mark", "--code", "qr", *args, "--estimate"])


def test_a_drawing_in_a_codes_quiet_zone_is_refused(tmp_path):
    svg = tmp_path / "logo.svg"
    svg.write_text('<svg xmlns="http://www.w3.org/2000/svg" width="10mm" height="10mm" '
                   'viewBox="0 0 10 10"><rect x="1" y="1" width="8" height="8" fill="none" '
                   'stroke="black"/></svg>')
    with pytest.raises(SystemExit, match="reaches into the quiet zone of the qr code"):
        main(["mark", str(svg), "--code", "qr", "--data", "x", "--size", "5",
              "--code-at=7,0", "--estimate"])
    assert main(["mark", str(svg), "--code", "qr", "--data", "x", "--size", "5",
                 "--code-at=15,0", "--estimate"]) == 0
    with pytest.raises(SystemExit, match="--data is for --code"):
        main(["mark", str(svg), "--data", "x", "--estimate"])
    with pytest.raises(SystemExit, match="give a drawing"):
        main(["mark", "--estimate"])


@given(st.text(min_size=1, max_size=3 * DATA_SHOWN))
def test_a_codes_data_is_said_whole_or_cut_with_an_ellipsis(data):
    """Never cut without a sign: a URL cut short reads as a whole, wrong one."""
    said = eval(data_said(data))                    # (a repr: its quotes and escapes undone)
    if len(data) <= DATA_SHOWN:
        assert said == data
    else:
        assert said.endswith("…") and data.startswith(said[:-1]) and len(said) == DATA_SHOWN


def test_a_codes_data_in_the_note_and_the_preview_title(tmp_path, capsys, monkeypatch):
    """The note and the preview's title show a URL whole (it was cut at 20 characters,
    'https://example.com/', with no sign of it) or, past 40 characters, with "…"."""
    import galvoscan.plan.preview
    titles = []
    monkeypatch.setattr(galvoscan.plan.preview, "preview",
                        lambda path, *a, title, **k: titles.append(title))
    short, long = "https://example.com/lot/7731", "https://example.com/products/2026/lot/7731"
    for data in (short, long):
        assert main(["mark", "--code", "qr", "--data", data, "--size", "20", "--estimate",
                     "--preview", str(tmp_path / "code.png")]) == 0
    out = capsys.readouterr().out
    cut = "'https://example.com/products/2026/lot/7…'"
    assert f"note: qr code {short!r}: " in out and f"note: qr code {cut}: " in out
    assert titles[0].startswith(f"qr code {short!r}: ")
    assert titles[1].startswith(f"qr code {cut}: ")
