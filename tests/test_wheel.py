"""The package as a user gets it: a wheel, installed (not editable) into a fresh venv, runs every
command. An editable install hides a package missing from the wheel; this does not."""

import json
from pathlib import Path
import subprocess
import sys
import venv

import pytest

from galvoscan.cli import parser


pytestmark = [pytest.mark.slow, pytest.mark.toolchain]

ROOT = Path(__file__).resolve().parent.parent


def _commands(top):
    """Every command path: ``["sim"]``, ``["correct", "model"]``, …"""
    paths = []

    def walk(p, prefix):
        for action in p._actions:
            if action.__class__.__name__ == "_SubParsersAction":
                for name, sub in action.choices.items():
                    paths.append(prefix + [name])
                    walk(sub, prefix + [name])
    walk(top, [])
    return paths


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """The ``galvoscan`` script of a fresh venv holding the wheel built from this tree."""
    where = tmp_path_factory.mktemp("wheel")
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps",
                    "--wheel-dir", str(where / "dist"), str(ROOT)], check=True)
    wheel, = (where / "dist").glob("galvoscan-*.whl")
    venv.create(where / "venv", with_pip=True)
    bin_dir = where / "venv" / ("Scripts" if sys.platform == "win32" else "bin")
    subprocess.run([str(bin_dir / "python"), "-m", "pip", "install", "--quiet", str(wheel)],
                   check=True)
    return bin_dir / "galvoscan", where


def _run(script, *argv, cwd):
    # Run from an empty folder, so nothing of the source tree can be imported by accident.
    return subprocess.run([str(script), *argv], capture_output=True, text=True, cwd=cwd)


def test_wheel_runs_every_command_help(installed):
    script, where = installed
    result = _run(script, "--help", cwd=where)
    assert result.returncode == 0, result.stderr
    assert _run(script, "--version", cwd=where).stdout.startswith("galvoscan ")
    commands = _commands(parser())
    assert ["correct", "upload"] in commands and ["sim"] in commands
    for command in commands:
        result = _run(script, *command, "--help", cwd=where)
        assert result.returncode == 0, (command, result.stderr)
        assert f"usage: galvoscan {' '.join(command)}" in result.stdout


def test_wheel_regs_export_and_sim(installed):
    script, where = installed
    result = _run(script, "regs", "--json", cwd=where)
    assert result.returncode == 0, result.stderr
    assert {"status", "dwell", "cor_node"} <= {r["name"] for r in json.loads(result.stdout)}

    result = _run(script, "export", "verilog", "-o", "out/top.v", cwd=where)
    assert result.returncode == 0, result.stderr
    assert "module galvoscan_top" in (where / "out" / "top.v").read_text()

    result = _run(script, "sim", "--points", "12", "--json", "--csv", "sim/spiral.csv",
                  cwd=where)
    assert result.returncode == 0, result.stderr
    summary = json.loads(result.stdout)
    assert summary["points"] == 12
    rows = (where / "sim" / "spiral.csv").read_text().splitlines()
    assert len(rows) == summary["frames"] + 1


def test_wheel_plans_a_drawing(installed):
    """The job path's libraries (svgelements, ezdxf, shapely, the TOML reader) come with it."""
    script, where = installed
    result = _run(script, "machine", "init", "wheel.toml", cwd=where)
    assert result.returncode == 0, result.stderr
    (where / "box.svg").write_text(
        '<svg xmlns="http://www.w3.org/2000/svg" width="4mm" height="4mm" viewBox="0 0 4 4">'
        '<rect x="1" y="1" width="2" height="2"/></svg>')
    result = _run(script, "mark", "box.svg", "--machine", "wheel.toml", "--hatch", "0.5",
                  "--estimate", cwd=where)
    assert result.returncode == 0, result.stderr
    assert "mm marked" in result.stdout and "estimated time" in result.stdout
    import ezdxf
    doc = ezdxf.new(units=4)
    doc.modelspace().add_circle((0, 0), 2)
    doc.saveas(where / "ring.dxf")
    result = _run(script, "mark", "ring.dxf", "--machine", "wheel.toml", "--estimate",
                  "--preview", "ring.png", cwd=where)
    assert result.returncode == 0, result.stderr
    assert (where / "ring.png").stat().st_size > 0
