"""A drawing's units (`mark --units`, a job file's `units`): the numbers taken in a unit the
user gives, in place of the units the file declares; `--scale` applied before the size
check; and a curve of too many chords refused naming its entity and its size. Through the
command line (`--estimate --json`: no board), with DXF files made by ezdxf as its example
files are (in metres, $INSUNITS 6, with numbers a millimetre drawing has)."""

import json

from hypothesis import given, settings, strategies as st
import pytest

from galvoscan.cli import main
from galvoscan.geometry.drawing import DrawingError
from galvoscan.inputs.drawings import UNITS, load_drawing

from drawings import new_dxf, svg


def estimate(capsys, *argv):
    """``mark … --estimate --json``'s record."""
    assert main(["mark", *map(str, argv), "--estimate", "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def size_of(record):
    xmin, ymin, xmax, ymax = record["bounds_mm"]
    return pytest.approx((xmax - xmin, ymax - ymin), abs=2e-3)     # (bounds to 3 decimals)


@pytest.fixture
def metres_of_mm(tmp_path):
    """A plate 40 × 20 with a hole of 5 across, in a file that says metres: as five of
    ezdxf's example files are."""
    doc, msp = new_dxf(units=6)
    msp.add_lwpolyline([(0, 0), (40, 0), (40, 20), (0, 20)], close=True)
    msp.add_circle((20, 10), 2.5)
    doc.saveas(tmp_path / "plate.dxf")
    return tmp_path / "plate.dxf"


def test_a_dxf_in_metres_of_mm_numbers_is_refused_saying_its_size_and_units(metres_of_mm):
    with pytest.raises(SystemExit) as refusal:
        main(["mark", str(metres_of_mm), "--estimate", "--json"])
    assert str(refusal.value).endswith(
        f"{metres_of_mm}: 40 × 20 m (its $INSUNITS 6, metres), more than 10 m: give --units "
        f"mm if its numbers are millimetres, or --scale 0.25 or less")


def test_units_mm_marks_it_at_its_numbers(metres_of_mm, capsys):
    record = estimate(capsys, metres_of_mm, "--units", "mm")
    assert size_of(record) == (40, 20)
    assert "DXF numbers taken as millimetres (--units mm; its $INSUNITS 6, metres)" in \
        record["notes"]
    # Each unit is its size: 40 × 20 cm would not fit the field, 40 × 20 pt does.
    assert size_of(estimate(capsys, metres_of_mm, "--units", "pt")) == \
        (40 * 25.4 / 72, 20 * 25.4 / 72)


def test_scale_is_applied_before_the_size_check(metres_of_mm, capsys):
    """40 m at 1/500 is 80 mm: marked, not refused as 40 m."""
    assert size_of(estimate(capsys, metres_of_mm, "--scale", "0.002")) == (80, 40)
    with pytest.raises(SystemExit, match=r": 20 × 10 m at --scale 0.5 \(its \$INSUNITS 6, "
                                         r"metres\), more than 10 m: give --units mm if its "
                                         r"numbers are millimetres, or --scale 0.25 or less$"):
        main(["mark", str(metres_of_mm), "--scale", "0.5", "--estimate"])


def test_a_job_file_keeps_the_units(metres_of_mm, tmp_path, capsys):
    """--units is the drawing's, as --scale is: saved in its [[drawing]], read back."""
    job = tmp_path / "job.toml"
    first = estimate(capsys, metres_of_mm, "--units", "mm", "--save", job)
    assert 'units = "mm"' in job.read_text()
    assert estimate(capsys, job)["bounds_mm"] == first["bounds_mm"]
    with pytest.raises(SystemExit, match="--units is the job file's"):
        main(["mark", str(job), "--units", "cm", "--estimate"])
    job.write_text(job.read_text().replace('units = "mm"', 'units = "furlong"'))
    with pytest.raises(SystemExit, match=r"job.toml: \[\[drawing\]\] 1\.units must be one of "
                                         r"mm, cm, m, in, pt, px, not 'furlong'$"):
        main(["mark", str(job), "--estimate"])


def test_svg_units_replace_its_width_height_and_viewbox(tmp_path, capsys):
    """An SVG 10 in wide over a viewBox 100 wide is 254 mm; its numbers taken as mm, 100 mm.
    One with no size is in px (96 per inch); taken as mm, its numbers are mm."""
    sized = tmp_path / "sized.svg"
    sized.write_text(svg('<rect x="0" y="0" width="100" height="50"/>',
                         size='width="10in" height="5in" viewBox="0 0 100 50"'))
    assert size_of(estimate(capsys, sized, "--units", "mm")) == (100, 50)
    assert size_of(estimate(capsys, sized, "--units", "mm", "--scale", "0.5")) == (50, 25)
    bare = tmp_path / "bare.svg"
    bare.write_text(svg('<rect x="0" y="0" width="60" height="30"/>', size=""))
    assert size_of(estimate(capsys, bare)) == (60 * 25.4 / 96, 30 * 25.4 / 96)
    assert size_of(estimate(capsys, bare, "--units", "mm")) == (60, 30)
    # (A size in a unit svgelements does not know is refused unless the units are given.)
    odd = tmp_path / "odd.svg"
    odd.write_text(svg('<rect x="0" y="0" width="60" height="30"/>',
                       size='width="60furlong" height="30furlong" viewBox="0 0 60 30"'))
    with pytest.raises(SystemExit, match="in a unit galvoscan does not know"):
        main(["mark", str(odd), "--estimate"])
    assert size_of(estimate(capsys, odd, "--units", "mm")) == (60, 30)


def test_too_many_chords_names_the_entity_and_its_size(tmp_path):
    """A circle two billion metres across, or a text a million high: refused before their
    chords are made, naming the entity by its type and handle, and its size."""
    doc, msp = new_dxf()
    msp.add_line((0, 0), (10, 0))
    circle = msp.add_circle((0, 0), 1e12)
    doc.saveas(tmp_path / "circle.dxf")
    with pytest.raises(SystemExit) as refusal:
        main(["mark", str(tmp_path / "circle.dxf"), "--estimate"])
    assert str(refusal.value).endswith(
        f"circle.dxf: CIRCLE entity #{circle.dxf.handle}, 2,000,000,000 × 2,000,000,000 m "
        f"(its $INSUNITS 4, millimetres): a curve in it would take more than 1,000,000 chords "
        f"within 0.01 mm: coordinates far beyond any field: give a smaller --scale")
    doc, msp = new_dxf()
    text = msp.add_text("HUGE", height=1e9)
    doc.saveas(tmp_path / "text.dxf")
    with pytest.raises(SystemExit, match=rf"text.dxf: TEXT entity #{text.dxf.handle}, [\d,]+ × "
                                         rf"[\d,]+ m at --scale 0.001 \(its \$INSUNITS 4, "
                                         rf"millimetres\): a curve in it would take more than "
                                         rf"1,000,000 chords"):
        main(["mark", str(tmp_path / "text.dxf"), "--scale", "0.001", "--estimate"])
    (tmp_path / "path.svg").write_text(svg('<path id="wild" d="M0 0 C 9e14 9e14 -9e14 9e14 1 '
                                           '0"/>'))
    with pytest.raises(SystemExit, match=r"path.svg: <path id='wild'> element, [\d,]+ × "
                                         r"[\d,]+ m \(its width 100mm and height 100mm: 1 mm "
                                         r"a unit\): a curve in it would take more than"):
        main(["mark", str(tmp_path / "path.svg"), "--estimate"])


def test_text_in_a_metres_file_of_mm_numbers(tmp_path, capsys):
    """As ezdxf's text_alignments.dxf: lines of text 2.5 high in a file that says metres.
    Its glyphs, 2.5 m high at 0.01 mm, are refused by their chords (naming the entity, its
    size and the file's units), not after gigabytes of points; with --units mm, marked."""
    doc, msp = new_dxf(units=6)
    for row in range(3):
        text = msp.add_text("The quick brown fox jumps over the lazy dog, twice or thrice",
                            height=2.5)
        text.set_placement((0, 8 * row))
    doc.saveas(tmp_path / "text.dxf")
    with pytest.raises(SystemExit, match=r"text.dxf: TEXT entity #[0-9A-F]+, [\d.]+ × [\d.]+ "
                                         r"m \(its \$INSUNITS 6, metres\): a curve in it would "
                                         r"take more than 1,000,000 chords within 0.01 mm: "
                                         r"coordinates far beyond any field: give --units mm if "
                                         r"its numbers are millimetres, or a smaller --scale$"):
        main(["mark", str(tmp_path / "text.dxf"), "--estimate"])
    capsys.readouterr()
    width, height = size_of(estimate(capsys, tmp_path / "text.dxf", "--units", "mm")).expected
    assert 80 < width < 100 and 18 < height < 22          # (three lines 8 apart)


def test_a_drawing_scaled_down_is_flattened_for_its_marked_size(tmp_path):
    """The tolerance is the marked drawing's: a circle 100 m across, marked at 1/1000, has the
    chords of a 100 mm circle, not a thousand times more (and not too many to make)."""
    doc, msp = new_dxf()
    msp.add_circle((0, 0), 50)
    small = len(load_drawing(_saved(doc, tmp_path / "small.dxf")).paths[0])
    doc, msp = new_dxf()
    msp.add_circle((0, 0), 50_000)
    big = len(load_drawing(_saved(doc, tmp_path / "big.dxf"), scale=1e-3).paths[0])
    assert big == small


def _saved(doc, path):
    doc.saveas(path)
    return path


@settings(max_examples=30, deadline=None)
@given(st.text(min_size=1, max_size=12).filter(lambda t: t not in UNITS))
def test_units_it_does_not_know_are_one_line(tmp_path_factory, word):
    """On the command line (argparse's choices), and through the API."""
    folder = tmp_path_factory.mktemp("units")
    path = folder / "t.svg"
    path.write_text(svg('<rect width="10" height="10"/>'))
    with pytest.raises(SystemExit) as refusal:
        main(["mark", str(path), f"--units={word}", "--estimate"])
    assert refusal.value.code == 2
    with pytest.raises(DrawingError) as error:
        load_drawing(path, units=word)
    assert "\n" not in str(error.value) and "one of mm, cm, m, in, pt, px" in str(error.value)
