"""Layers (galvoscan/plan/layers.py, plan/layer_keys.py, cli/layers.py, `mark --layer`): paths
picked by SVG colour, Inkscape layer and DXF layer; the key table, read alike by `--layer`, a
job file's `[[layer]]` and `mark`'s own fill options; the layer options' one-line refusals;
and, on the simulated board, each layer's speed and pulses per point measured on the XY2-100
and DB25 wires."""

import argparse
import json
import re
from pathlib import Path

from hypothesis import given, strategies as st
import numpy as np
import pytest

from galvoscan.cli import main, parser
from galvoscan.cli.jobfile import _entry
from galvoscan.cli.job_options import SECTIONS
from galvoscan.cli.layers import layer_from_words
from galvoscan.inputs.drawings import load_drawing
from galvoscan.plan.layer_keys import (CONTOUR, HATCH, HATCH_LINES, LAYER_KEYS, OUTLINE,
                                       LayerKey, layer_from_table)
from galvoscan.plan.layers import Layer, split_by_layer
from galvoscan.geometry.drawing import PathStyle
from galvoscan.settings.schema import Setting, SettingError

from sim_board import VECTOR_BOARD, quick_sim_board


INKSCAPE = 'xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape"'

LAYERED_SVG = f"""<svg xmlns="http://www.w3.org/2000/svg" {INKSCAPE} width="30mm" height="30mm"
  viewBox="0 0 30 30">
 <g inkscape:groupmode="layer" inkscape:label="Engrave">
  <rect id="a" x="1" y="1" width="5" height="5" fill="none" stroke="#FF0000"/>
  <g inkscape:label="a plain group"><circle id="b" cx="12" cy="4" r="2" fill="#00f"/></g>
  <g inkscape:groupmode="layer" inkscape:label="Inner">
   <rect id="c" x="20" y="1" width="4" height="4" fill="none" stroke="green"/></g>
 </g>
 <rect id="d" x="1" y="20" width="5" height="5" style="fill:none;stroke:#ff0000"/>
 <path id="e" d="M 10 20 L 15 25" stroke="black" fill="none"/>
</svg>"""


def test_svg_paths_know_their_colour_and_layer(tmp_path):
    """A stroke's colour, else the fill's, as #rrggbb; the innermost Inkscape layer's label
    (a group that is not a layer does not count); none outside every layer."""
    svg = tmp_path / "layers.svg"
    svg.write_text(LAYERED_SVG)
    drawing = load_drawing(svg)
    # Paths come in document order, one per shape here.
    assert drawing.styles == (PathStyle("#ff0000", "Engrave"), PathStyle("#0000ff", "Engrave"),
                              PathStyle("#008000", "Inner"), PathStyle("#ff0000", None),
                              PathStyle("#000000", None))


def test_first_matching_layer_takes_a_path(tmp_path):
    svg = tmp_path / "layers.svg"
    svg.write_text(LAYERED_SVG)
    drawing = load_drawing(svg)
    parts, rest = split_by_layer(drawing, [Layer("#F00"), Layer("engrave")])
    red, engrave = parts
    assert [s.colour for s in red.styles] == ["#ff0000", "#ff0000"]         # a and d
    assert engrave.styles == (PathStyle("#0000ff", "Engrave"),)              # b: a isn't here
    assert rest.styles == (PathStyle("#008000", "Inner"), PathStyle("#000000", None))
    assert sum(len(p.paths) for p in (red, engrave, rest)) == len(drawing.paths)
    parts, rest = split_by_layer(drawing, [Layer("Inner")])
    assert len(parts[0].paths) == 1 and len(rest.paths) == 4


def test_dxf_layers_by_name(tmp_path):
    """Each entity on its own layer; a block's entities on the reference's."""
    import ezdxf
    document = ezdxf.new(units=4)                    # mm
    document.layers.add("CUT")
    document.layers.add("MARK")
    space = document.modelspace()
    space.add_line((0, 0), (10, 0), dxfattribs={"layer": "CUT"})
    space.add_circle((5, 5), 2, dxfattribs={"layer": "MARK"})
    block = document.blocks.new("TAG")
    block.add_line((0, 0), (1, 1))
    space.add_blockref("TAG", (20, 0), dxfattribs={"layer": "MARK"})
    document.saveas(tmp_path / "layers.dxf")
    drawing = load_drawing(tmp_path / "layers.dxf")
    assert [s.layer for s in drawing.styles] == ["CUT", "MARK", "MARK"]
    parts, rest = split_by_layer(drawing, [Layer("mark")])
    assert len(parts[0].paths) == 2 and len(rest.paths) == 1


def test_dxf_colours_and_colour_names(tmp_path):
    """A DXF entity's colour: its ACI number (1 red), BYLAYER its layer's (5 blue), or its
    true colour; a CSS colour name (red) matches paths of that colour, in SVG or DXF."""
    import ezdxf
    document = ezdxf.new(units=4)
    document.layers.add("CUT", color=5)
    space = document.modelspace()
    space.add_line((0, 0), (10, 0), dxfattribs={"color": 1})
    space.add_line((0, 5), (10, 5), dxfattribs={"layer": "CUT"})
    space.add_line((0, 8), (10, 8), dxfattribs={"true_color": 0x00FF00})
    document.saveas(tmp_path / "colours.dxf")
    drawing = load_drawing(tmp_path / "colours.dxf")
    assert [s.colour for s in drawing.styles] == ["#ff0000", "#0000ff", "#00ff00"]
    parts, rest = split_by_layer(drawing, [Layer("red"), Layer("#00f")])
    assert [len(p.paths) for p in parts] == [1, 1] and len(rest.paths) == 1
    svg = tmp_path / "layers.svg"
    svg.write_text(LAYERED_SVG)
    parts, _ = split_by_layer(load_drawing(svg), [Layer("red")])
    assert len(parts[0].paths) == 2                     # stroke="#FF0000" and "#ff0000"


def test_every_layer_key_is_a_declaration():
    """Each key a layer takes is a declared setting, and each setting a Layer holds has its
    key."""
    for key, one in LAYER_KEYS.items():
        assert isinstance(one, LayerKey) and isinstance(one.setting, Setting)
        assert one.setting.key == key and one.said
    assert {one.field for one in LAYER_KEYS.values()} == set(Layer.__dataclass_fields__) - \
        {"match"}


def _mark_option(flag):
    mark = next(a for a in parser()._actions if isinstance(a, argparse._SubParsersAction))
    return next(a for a in mark.choices["mark"]._actions if flag in a.option_strings)


def test_marks_fill_options_are_the_declarations():
    """``--hatch``, ``--hatch-lines``, ``--contour`` and ``--no-outline`` are the layer keys'
    settings: their placeholders, words and default, and the job file's keys for them."""
    hatch, lines, contour = (_mark_option(s.flag) for s in (HATCH, HATCH_LINES, CONTOUR))
    assert (hatch.metavar, hatch.help) == (HATCH.metavar, HATCH.help)
    assert (contour.metavar, contour.help) == (CONTOUR.metavar, CONTOUR.help)
    assert lines.choices == list(HATCH_LINES.choices) and lines.default == HATCH_LINES.default
    assert SECTIONS["job"][OUTLINE.key].flag == "--no-outline"
    assert SECTIONS["job"][OUTLINE.key].inverted
    for setting in (HATCH, HATCH_LINES, CONTOUR):
        assert SECTIONS["job"][setting.key].flag == setting.flag


def _read(read, text):
    """What ``read(text)`` gives, or its refusal's line."""
    try:
        return read(text)
    except (ValueError, argparse.ArgumentTypeError) as error:
        return str(error)


@pytest.mark.parametrize("setting", [HATCH, CONTOUR], ids=lambda s: s.key)
@given(text=st.text(alphabet="0123456789.,-e x", max_size=12))
def test_a_fill_is_read_alike_everywhere(setting, text):
    """``mark --hatch``, a job file's ``[job] hatch``, ``--layer … hatch=`` and a
    ``[[layer]]`` table's ``hatch`` read a text by the one declaration: the same value, or
    the same refusal (each reader naming where); and so for ``contour``."""
    try:
        value, refusal = setting.parse(text), None
    except SettingError as error:
        value, refusal = None, str(error)
    option = _read(_mark_option(setting.flag).type, text)
    job = _read(lambda t: _entry("job", {setting.key: t}, Path("."), "[job]")[setting.key],
                text)
    table = _read(lambda t: getattr(layer_from_table({"match": "red", setting.key: t},
                                                     "L"), setting.name), text)
    words = _read(lambda t: getattr(layer_from_words(["red", f"{setting.key}={t}"]),
                                    setting.name), text)
    if refusal is None:
        made = [value] if setting.repeated else value
        assert (option, job) == (value, made)
        assert table == ((value,) if setting.repeated else value)
        if text == text.strip():          # (--layer's words are stripped first)
            assert words == table
    else:
        assert option == refusal and job == f"[job].{setting.key}: {refusal}"
        assert table == f"L ('red'): {setting.key}: {refusal}"


@pytest.mark.parametrize("words, said", [
    (["hatch_lines=joined", "outline=off"], dict(hatch_lines=HATCH_LINES.make("joined"),
                                                   outline=False)),
    (["hatch=none", "contour=0.1,3"], dict(hatch=(), contour=CONTOUR.parse("0.1,3"))),
    (["pulses=0x10", "jump_delay=2000", "laser_on_delay=-19"],
     dict(pulses_per_point=16, delays_us=(("jump_delay", 2000), ("laser_on_delay", -19)))),
])
def test_layer_words_and_tables_alike(words, said):
    """The same keys as ``--layer`` words and as a ``[[layer]]`` table: the same layer."""
    from_words = layer_from_words(["Engrave", *words])
    table = {"match": "Engrave"}
    for word in words:
        key, _, value = word.partition("=")
        table[key] = {"off": False}.get(value, value)
    assert from_words == layer_from_table(table) == Layer("Engrave", **said)


@pytest.mark.parametrize("layer, words", [
    (["#ff0000", "sped=300"], "'sped' is not a layer setting \\(did you mean 'speed'\\?\\)"),
    (["#ff0000", "speed=0"], "--layer #ff0000: speed: speed must be from 0.1"),
    (["#ff0000", "pulses=300"], "pulses per point must be from 1 to 255"),
    (["#ff0000", "hatch=x"], "--hatch must be SPACING"),
    (["#ff0000", "outline=maybe"], "must be yes or no"),
    (["#ff0000", "speed"], "'speed' is not KEY=VALUE"),
    (["#ff0000", "speed=500", "speed=600"], "speed is given twice"),
    (["Inner", "--layer", "inner", "power=50"], "layer 'inner' is given twice"),
    (["#123456", "speed=1007.1"], "layer '#123456' matches nothing in the job \\(its colours: "
                                  "#000000, #0000ff, #008000, #ff0000; its layers: 'Engrave', "
                                  "'Inner'\\)"),
])
def test_bad_layers_are_one_line(tmp_path, capsys, layer, words):
    svg = tmp_path / "layers.svg"
    svg.write_text(LAYERED_SVG)
    with pytest.raises(SystemExit):
        main(["mark", str(svg), "--layer", *layer, "--estimate"])
    said = capsys.readouterr().err          # (argparse's refusals and the command's alike)
    assert len([line for line in said.splitlines() if "error" in line]) == 1
    assert re.search(words, said), said


def test_layer_estimate_json(tmp_path, capsys):
    """--estimate --json: the totals, and each layer's own settings and time, in the order
    they run (the rest last)."""
    svg = tmp_path / "layers.svg"
    svg.write_text(LAYERED_SVG)
    assert main(["mark", str(svg), "--layer", "Inner", "speed=335.7", "power=40", "pulses=2",
                 "passes=3", "--layer", "#ff0000", "prr=100", "hatch=0.1,45", "hatch=0.1,135",
                 "--estimate", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    layers = record["layers"]
    assert [entry["match"] for entry in layers] == ["Inner", "#ff0000", "the rest"]
    inner, red, rest = layers
    assert inner["pulses_per_point"] == 2 and inner["passes"] == 3
    assert inner["speed_mm_s"] == pytest.approx(335.7, rel=0.02) and inner["power_percent"] == 40
    assert red["prr_khz"] == 100 and red["mark_mm"] > 2 * rest["mark_mm"]     # hatched
    assert record["estimate_s"] == pytest.approx(sum(e["estimate_s"] for e in layers))
    assert record["segments"] == sum(e["segments"] for e in layers)


PROFILE = "[laser]\nspot_mm = 0.1\n[galvo]\njump_delay_us = 50\n"


@pytest.mark.slow
def test_each_layer_runs_at_its_own_speed_on_the_wires(tmp_path, capsys):
    """Three layers, each at its own speed and pulses per point: on the wires, each layer's
    points step at its speed (within 2 %) and are held for its pulses, and the layers run in
    the order given."""
    svg = tmp_path / "layers.svg"
    svg.write_text(LAYERED_SVG)
    machine = tmp_path / "machine.toml"
    machine.write_text(PROFILE)
    with quick_sim_board(**VECTOR_BOARD):
        assert main(["mark", str(svg), "--layer", "Inner", "speed=391.6", "pulses=3",
                     "--layer", "#ff0000", "speed=1500", "pulses=1", "--speed", "800",
                     "--prr", "50", "--machine", str(machine), "--sim", "--timeout", "600",
                     "--json"]) == 0
    result = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert result["errors"] == result["underruns"] == result["rejected"] == 0
    inner, red, rest = result["layers"]
    assert [inner["match"], red["match"], rest["match"]] == ["Inner", "#ff0000", "the rest"]
    for entry, speed, pulses in [(inner, 391.6, 3), (red, 1500, 1), (rest, 800, None)]:
        assert entry["speed_mm_s"] == pytest.approx(speed, rel=0.02), entry
        if pulses is not None:
            assert entry["pulses_per_point"] == entry["planned_pulses_per_point"] == pulses
        assert entry["points"] > 10
    assert sum(e["points"] for e in result["layers"]) == len(result["marks"])
    # The Inner square's points (x 20…24 mm in the drawing) come first, then the red ones.
    marks = np.array(result["drawing_marks"])
    first = marks[:inner["points"]]
    assert (first[:, 0] > 19.9).all() and (first[:, 0] < 24.1).all()


def test_an_image_of_layers_is_refused(tmp_path):
    svg = tmp_path / "layers.svg"
    svg.write_text(LAYERED_SVG)
    with pytest.raises(SystemExit, match="the job has 2 layers, each at its own settings"):
        main(["store", str(svg), "--layer", "Inner", "power=40", "-o",
              str(tmp_path / "job.img")])
    assert not (tmp_path / "job.img").exists()


def test_a_layers_wobble_is_its_own(tmp_path, capsys):
    """A layer that wobbles has its figure; the others have the wobble turned off (the board
    keeps a register until it is written), and the plan says which."""
    svg = tmp_path / "layers.svg"
    svg.write_text(LAYERED_SVG)
    assert main(["mark", str(svg), "--layer", "Inner", "wobble=60", "wobble_hz=2000",
                 "--estimate", "--json"]) == 0
    inner, rest = json.loads(capsys.readouterr().out)["layers"]
    assert inner["wobble_um"]["across"] == pytest.approx(60, abs=1)
    assert inner["wobble_um"]["hz"] == 2000
    assert "wobble_um" not in rest


def test_a_layers_delays_are_its_own(tmp_path, capsys):
    """Delays given to a layer are its registers (the jump delay timing its estimate too);
    the other layers keep the profile's."""
    svg = tmp_path / "layers.svg"
    svg.write_text(LAYERED_SVG)
    assert main(["mark", str(svg), "--layer", "Inner", "jump_delay=2000", "laser_on_delay=-10",
                 "mark_delay=300", "--estimate", "--json"]) == 0
    inner, rest = json.loads(capsys.readouterr().out)["layers"]
    assert (inner["jump_delay_us"], inner["laser_on_delay_us"], inner["mark_delay_us"]) == \
        (2000, -10, 300)
    assert rest["laser_on_delay_us"] == 100 and rest["jump_delay_us"] == 500
    # One jump to the square, then marks: its 2 ms jump delay is in the time.
    assert inner["estimate_s"] > 0.002


def test_a_layered_plan_and_its_preview_give_the_same_jumps(tmp_path, capsys):
    """The plan's jumps of a job of layers are each layer's joined where the last ended, as
    the preview draws (and its legend sums) them."""
    import matplotlib
    svg = tmp_path / "layers.svg"
    svg.write_text(LAYERED_SVG)
    with matplotlib.rc_context({"svg.fonttype": "none"}):
        assert main(["mark", str(svg), "--layer", "Inner", "power=40", "--layer", "#ff0000",
                     "power=60", "--preview", str(tmp_path / "p.svg"), "--estimate",
                     "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert f"jumps {record['jump_mm']:.1f} mm" in (tmp_path / "p.svg").read_text()


def test_a_layer_keeps_a_codes_and_a_photos_own_fill(tmp_path, capsys):
    """A layer's hatch and outline apply to drawings and outline text; a code's module lines,
    a photo's scan lines and single-line strokes are their own (outline = false dropped the
    photo without a word): in the layer they take its speed and power only."""
    from PIL import Image
    Image.new("L", (20, 20), 0).save(tmp_path / "black.png")
    job = tmp_path / "job.toml"
    job.write_text('[[image]]\nfile = "black.png"\nwidth = 2\nat = [10, 0]\nlayer = "T"\n'
                   '[[code]]\nkind = "qr"\ndata = "7"\nsize = 4\nat = [-10, 0]\nlayer = "T"\n'
                   '[[text]]\ntext = "AB"\nfont = "hershey"\nheight = 2\nat = [0, 8]\n'
                   'layer = "T"\n'
                   '[[layer]]\nmatch = "T"\nspeed = 503.5\noutline = false\nhatch = "0.3,45"\n')
    assert main(["mark", str(job), "--estimate", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    (layer,) = record["layers"]
    xmin, ymin, xmax, ymax = layer["bounds_mm"]
    assert xmin < -11.5 and xmax > 10.9 and ymax > 9.5        # the code, the photo, the text
    assert layer["speed_mm_s"] == pytest.approx(503.5, rel=0.01)
    # A drawing that has nothing to mark at its layer's settings is refused, naming it.
    svg = tmp_path / "lines.svg"
    svg.write_text('<svg xmlns="http://www.w3.org/2000/svg" width="10mm" height="10mm" '
                   'viewBox="0 0 10 10"><path d="M1 1 L9 9" stroke="#ff0000"/></svg>')
    with pytest.raises(SystemExit, match=r"layer '#ff0000': lines.svg \[#ff0000\]: nothing "
                                         r"to mark"):
        main(["mark", str(svg), "--text", "A", "--font", "hershey", "--text-at=0,-20",
              "--layer", "#ff0000", "outline=no", "--estimate"])


def test_a_blocks_entities_take_their_own_colours(tmp_path):
    """Inside a block: an entity's own colour is its own; BYBLOCK, and BYLAYER on layer 0,
    the reference's (as CAD draws them)."""
    import ezdxf
    document = ezdxf.new(units=4)
    block = document.blocks.new("TAG")
    block.add_line((0, 0), (1, 0), dxfattribs={"color": 1})                  # red
    block.add_line((0, 1), (1, 1), dxfattribs={"color": 0})                  # BYBLOCK
    block.add_line((0, 2), (1, 2))                                           # BYLAYER, 0
    document.modelspace().add_blockref("TAG", (10, 10), dxfattribs={"color": 5})   # blue
    document.saveas(tmp_path / "block.dxf")
    drawing = load_drawing(tmp_path / "block.dxf")
    assert [s.colour for s in drawing.styles] == ["#ff0000", "#0000ff", "#0000ff"]


def test_the_stall_note_names_the_layer_that_stalls(tmp_path, capsys):
    """Two layers, one stepping a point faster than the board sets up a segment (100 kHz, a
    pulse a point: 100,000 points a second against 12 MHz / 140 set-up clocks), the other
    not (the profile's 50 kHz): one stall note, naming the layer as the plan's layer lines
    do, with that layer's joints between two marks counted off its own segments."""
    from galvoscan import api
    from galvoscan.gateware.host.regmap import DEFAULT_CLOCK_HZ
    from galvoscan.gateware.sources.dda import SETUP_CLOCKS

    svg = tmp_path / "layers.svg"
    svg.write_text(LAYERED_SVG)
    assert main(["mark", str(svg), "--layer", "Inner", "prr=100", "pulses=1", "speed=1007",
                 "--estimate"]) == 0
    lines = capsys.readouterr().out.splitlines()
    planned = api.plan(api.Job(drawings=(api.Drawing(str(svg)),),
                               layers=(Layer("Inner", prr_khz=100, pulses_per_point=1,
                                             speed_mm_s=1007),)))
    layer_jobs = planned.vector_job.layers
    assert len(layer_jobs) == 2
    stalling = [(number, lj) for number, lj in enumerate(layer_jobs, 1)
                if lj.job.registers["laser_prr"] * 100 / lj.job.registers["pulses_per_point"]
                > DEFAULT_CLOCK_HZ / SETUP_CLOCKS]
    assert [lj.label for _, lj in stalling] == ["Inner"]
    (number, inner), = stalling
    joints = sum(1 for a, b in zip(inner.job.segments, inner.job.segments[1:])
                 if a[0] == b[0] == "mark")
    assert joints > 0
    name = f"layer {number} 'Inner'"
    assert any(line.startswith(name + " (") for line in lines)      # the layer's own line
    stalls = [line for line in lines if "stalls" in line]
    assert stalls == [line for line in lines if line.startswith(f"note: {name}: ")
                      and f"expect about {joints} stalls" in line]
    assert len(stalls) == 1
