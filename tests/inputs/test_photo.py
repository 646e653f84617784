"""Photos (galvoscan/inputs/photo.py, `mark --image`): the dithered grid against Pillow's own
dithering and against the grey it stands for, and the marks off the simulated board's XY2-100
wires against the grid: each lit cell is a dark one, each dark cell is lit."""

import json

import numpy as np
import pytest
from PIL import Image, ImageDraw

from galvoscan.cli import main
from galvoscan.geometry.drawing import DrawingError
from galvoscan.inputs.photo import Dither, PhotoSpec, photo_bitmap, photo_drawing
from galvoscan.geometry.field import PlanError

from sim_board import VECTOR_BOARD, quick_sim_board


def picture(path, size=(30, 20)):
    """A grey ramp left to right (white to black) with a black disc and a white bar: grey
    levels, edges and runs of every length."""
    ramp = np.tile(np.linspace(255, 0, size[0]), (size[1], 1)).astype(np.uint8)
    image = Image.fromarray(ramp, "L")
    draw = ImageDraw.Draw(image)
    draw.ellipse((3, 3, 13, 13), fill=0)
    draw.rectangle((18, 2, 26, 5), fill=255)
    image.save(path)
    return np.asarray(image)


def test_threshold_and_floyd_are_pillows(tmp_path):
    """At one cell a pixel the grid is the picture itself: threshold is grey < 128, Floyd–
    Steinberg is Pillow's own convert("1") of it."""
    grey = picture(tmp_path / "p.png")
    spec = PhotoSpec(str(tmp_path / "p.png"), 3.0, 0.1, dither=Dither.THRESHOLD)
    assert np.array_equal(photo_bitmap(spec), grey < 128)
    floyd = np.asarray(Image.fromarray(grey).convert("1")) == 0
    assert np.array_equal(photo_bitmap(PhotoSpec(str(tmp_path / "p.png"), 3.0, 0.1)), floyd)


@pytest.mark.parametrize("dither", [Dither.FLOYD, Dither.ORDERED])
@pytest.mark.parametrize("level", [32, 96, 160, 224])
def test_dithered_grey_keeps_its_darkness(tmp_path, dither, level):
    """A flat grey comes out with the share of dark cells its darkness is (1 - level / 255),
    within a cell in 64 (ordered: every 8 × 8 tile the same)."""
    Image.new("L", (64, 64), level).save(tmp_path / "g.png")
    dark = photo_bitmap(PhotoSpec(str(tmp_path / "g.png"), 6.4, 0.1, dither=dither))
    assert dark.shape == (64, 64)
    assert dark.mean() == pytest.approx(1 - level / 255, abs=1 / 64)
    if dither is Dither.ORDERED:
        tiles = dark.reshape(8, 8, 8, 8).swapaxes(1, 2).reshape(64, 64)
        assert (tiles == tiles[0]).all()


def test_scaled_to_width_by_aspect(tmp_path):
    Image.new("L", (300, 100), 0).save(tmp_path / "b.png")
    drawing, dark = photo_drawing(PhotoSpec(str(tmp_path / "b.png"), 6.0, 0.05))
    assert dark.shape == (40, 120) and dark.all()
    # One mark a line, from the first cell's centre to the last's, the lines alternating.
    assert len(drawing.paths) == 40
    assert drawing.bounds() == pytest.approx((0.025, 0.025, 5.975, 1.975))
    assert drawing.paths[0][0][0] < drawing.paths[0][1][0]
    assert drawing.paths[1][0][0] > drawing.paths[1][1][0]


@pytest.mark.parametrize("make, words", [
    (lambda p: p.write_bytes(b"\x89PNG\r\n\x1a\n" + b"\0" * 40), "damaged|not an image"),
    (lambda p: p.write_text("hello"), "not an image Pillow reads"),
    (lambda p: p.mkdir(), "a folder"),
    (lambda p: None, "no such file"),
    (lambda p: Image.new("RGBA", (9, 9), (0, 0, 0, 0)).save(p, "PNG"), "no dark pixels"),
])
def test_bad_images_are_one_line(tmp_path, make, words):
    path = tmp_path / "x.png"
    make(path)
    with pytest.raises(DrawingError, match=words):
        photo_drawing(PhotoSpec(str(path), 5, 0.05))


def test_huge_images_are_refused_before_decoding(tmp_path, monkeypatch):
    import galvoscan.inputs.photo as photo
    Image.new("L", (400, 300), 0).save(tmp_path / "big.png")
    monkeypatch.setattr(photo, "MAX_PIXELS", 100_000)
    with pytest.raises(DrawingError, match="400 × 300 pixels, more than"):
        photo_bitmap(PhotoSpec(str(tmp_path / "big.png"), 5, 0.05))
    monkeypatch.setattr(photo, "MAX_PIXELS", 10 ** 9)
    with pytest.raises(DrawingError, match="cells at 0.001 mm, more than 4,000,000"):
        photo_bitmap(PhotoSpec(str(tmp_path / "big.png"), 500, 0.001))
    with pytest.raises(PlanError, match="wider than the image"):
        PhotoSpec("x.png", 1, 2)


def test_a_picture_enlarged_is_said(tmp_path):
    Image.new("L", (3, 3), 0).save(tmp_path / "tiny.gif")
    drawing, dark = photo_drawing(PhotoSpec(str(tmp_path / "tiny.gif"), 10, 0.05))
    assert dark.shape == (200, 200)
    assert any("3 pixels across made 200 cells (66.7 × enlarged)" in n for n in drawing.notes)
    Image.new("L", (200, 200), 0).save(tmp_path / "fine.png")
    drawing, _ = photo_drawing(PhotoSpec(str(tmp_path / "fine.png"), 10, 0.05))
    assert not any("enlarged" in n for n in drawing.notes)


def test_image_options_need_image(tmp_path):
    with pytest.raises(SystemExit, match="--dither is for --image"):
        main(["mark", "--text", "A", "--dither", "ordered", "--estimate"])
    with pytest.raises(SystemExit, match="--image needs --width"):
        main(["mark", "--image", "x.png", "--estimate"])
    with pytest.raises(SystemExit, match="--one-way is for --image"):
        main(["mark", "--text", "A", "--one-way", "--estimate"])


PROFILE = "[laser]\nspot_mm = 0.1\n[galvo]\njump_delay_us = 50\n"


@pytest.mark.slow
@pytest.mark.parametrize("extra, dither", [([], "floyd"), (["--one-way"], "threshold")])
def test_marked_cells_are_the_dark_cells_off_the_wires(tmp_path, capsys, extra, dither):
    """Every point the board marked, off the XY2-100 wires, falls in a dark cell of the
    grid, and every dark cell holds one; the lines run from the top, alternating (or, one
    way, all left to right)."""
    grey = picture(tmp_path / "p.png")
    dark = grey < 128 if dither == "threshold" else \
        np.asarray(Image.fromarray(grey).convert("1")) == 0
    machine = tmp_path / "machine.toml"
    machine.write_text(PROFILE)
    with quick_sim_board(**VECTOR_BOARD):
        assert main(["mark", "--image", str(tmp_path / "p.png"), "--width", "3",
                     "--line-spacing", "0.1", "--dither", dither, "--image-at=4,-2", *extra,
                     "--image-lines", "runs",
                     "--speed", "500", "--prr", "50", "--machine", str(machine), "--sim",
                     "--timeout", "600", "--json"]) == 0
    result = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert result["errors"] == result["underruns"] == result["rejected"] == 0
    marks = np.array(result["drawing_marks"])
    # In field mm the grid's corner is at --image-at less half its 3 × 2 mm.
    field = np.array(result["marks"])
    assert field - marks == pytest.approx(np.tile([4 - 1.5, -2 - 1.0], (len(marks), 1)),
                                          abs=0.005)
    rows = dark.shape[0]
    column = np.floor(marks[:, 0] / 0.1).astype(int)
    row = rows - 1 - np.floor(marks[:, 1] / 0.1).astype(int)
    lit = np.zeros_like(dark)
    lit[row, column] = True
    assert np.array_equal(lit, dark)
    # In marking order: rows from the top; within a row, x one way or alternating.
    assert (np.diff(row) >= 0).all()
    for r in np.unique(row):
        xs = marks[row == r, 0]
        steps = np.diff(xs)
        backward = not extra and r % 2 == 1
        assert (steps <= 1e-3).all() if backward else (steps >= -1e-3).all()
