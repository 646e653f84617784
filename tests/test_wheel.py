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


def _closure(requirements):
    """The distributions of this environment that ``requirements`` (Requires-Dist lines) need,
    with everything they need in turn: ``{name: distribution}``. Each must be installed at a
    version the requirement allows."""
    from importlib.metadata import PackageNotFoundError, distribution
    from packaging.requirements import Requirement
    from packaging.utils import canonicalize_name
    found = {}
    todo = [(Requirement(text), "") for text in requirements]
    while todo:
        requirement, extra = todo.pop()
        if requirement.marker and not requirement.marker.evaluate({"extra": extra}):
            continue
        name = canonicalize_name(requirement.name)
        try:
            dist = distribution(name)
        except PackageNotFoundError:
            pytest.fail(f"{requirement} is required but not installed here")
        assert requirement.specifier.contains(dist.version, prereleases=True), \
            (str(requirement), dist.version)
        for wanted in requirement.extras | {""}:
            if (name, wanted) not in found:
                found[(name, wanted)] = dist
                todo += [(Requirement(text), wanted) for text in dist.requires or ()]
    return {name: dist for (name, _), dist in found.items()}


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """The ``galvoscan`` script of a fresh venv holding the wheel built from this tree, and
    nothing else but the wheel's dependencies.

    The wheel is installed as a user installs it (not editable, ``--no-deps``); its declared
    dependencies, and theirs, are linked in from this environment (where they are installed
    already) rather than downloaded and installed again: the venv holds exactly what pip
    would put there, nothing of the tests' own packages, so a module the wheel leaves out or a
    dependency it does not declare still fails here."""
    import shutil
    import zipfile
    where = tmp_path_factory.mktemp("wheel")
    # Built from a copy of the tree: setuptools works in the source's build/, where other
    # tests write at the same time (the proofs' and the analyses' files), and a wheel built
    # there once failed on a dist-info folder that already existed.
    source = where / "source"
    shutil.copytree(ROOT, source, ignore=shutil.ignore_patterns(
        ".git", ".venv", "build", ".hypothesis", "*.egg-info", "__pycache__"))
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps",
                    "--wheel-dir", str(where / "dist"), str(source)], check=True)
    wheel, = (where / "dist").glob("galvoscan-*.whl")
    venv.create(where / "venv", with_pip=False, symlinks=sys.platform != "win32")
    bin_dir = where / "venv" / ("Scripts" if sys.platform == "win32" else "bin")
    python = bin_dir / "python"
    subprocess.run([sys.executable, "-m", "pip", "--python", str(python), "install", "--quiet",
                    "--no-deps", "--no-index", str(wheel)], check=True)
    with zipfile.ZipFile(wheel) as archive:
        metadata, = (n for n in archive.namelist() if n.endswith(".dist-info/METADATA"))
        requires = [line.split(":", 1)[1].strip() for line in
                    archive.read(metadata).decode().splitlines()
                    if line.startswith("Requires-Dist:")]
    site = Path(subprocess.run([str(python), "-c", "import sysconfig; "
                                "print(sysconfig.get_paths()['purelib'])"],
                               capture_output=True, text=True, check=True).stdout.strip())
    for dist in _closure(requires).values():
        for top in {Path(str(f)).parts[0] for f in dist.files}:
            if top in ("..", "__pycache__") or (site / top).exists():
                continue
            (site / top).symlink_to(dist.locate_file(top))
        # Their commands (the YoWASP tools are found beside the interpreter), as pip writes
        # them: run by this venv's Python.
        for entry in dist.entry_points.select(group="console_scripts"):
            script = bin_dir / entry.name
            script.write_text(f"#!{python}\nimport sys\nfrom {entry.module} import "
                              f"{entry.attr.split('.')[0]}\n"
                              f"sys.exit({entry.attr}())\n")
            script.chmod(0o755)
    return bin_dir / "galvoscan", where, requires


def test_wheel_declares_the_projects_dependencies(installed):
    """The wheel's Requires-Dist is pyproject.toml's dependencies and extras, no more, no less
    (the venv above holds what it declares, so what it declares is what a user gets)."""
    try:
        import tomllib  # novermin: tomli below where it is missing
    except ImportError:                          # Python < 3.11
        import tomli as tomllib
    from packaging.markers import Marker
    from packaging.requirements import Requirement
    from packaging.utils import canonicalize_name
    _, _, requires = installed
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]

    def key(requirement, extra=None):
        r = Requirement(requirement)
        marker = r.marker
        if extra is not None:
            marker = Marker(f'({marker}) and extra == "{extra}"' if marker
                            else f'extra == "{extra}"')
        return canonicalize_name(r.name), str(r.specifier), frozenset(r.extras), str(marker)
    wanted = {key(r) for r in project["dependencies"]}
    wanted |= {key(r, extra) for extra, rs in project["optional-dependencies"].items()
               for r in rs}
    assert {key(r) for r in requires} == wanted


def _run(script, *argv, cwd):
    # Run from an empty folder, so nothing of the source tree can be imported by accident.
    return subprocess.run([str(script), *argv], capture_output=True, text=True, cwd=cwd)


def test_wheel_runs_every_command_help(installed):
    script, where, _ = installed
    result = _run(script, "--help", cwd=where)
    assert result.returncode == 0, result.stderr
    assert _run(script, "--version", cwd=where).stdout.startswith("galvoscan ")
    commands = _commands(parser())
    assert ["correct", "upload"] in commands and ["sim"] in commands
    # Every command's help from the wheel's own code, in one interpreter of the venv (one
    # start-up, not one a command: the script itself ran above).
    helps = _run(script.parent / "python", "-c", HELPS, json.dumps(commands), cwd=where)
    assert helps.returncode == 0, helps.stderr
    for command, (code, out, err) in zip(commands, json.loads(helps.stdout)):
        assert code == 0, (command, err)
        assert f"usage: galvoscan {' '.join(command)}" in out


# Runs `galvoscan COMMAND --help` for each command of argv[1] (JSON), from whichever galvoscan
# this interpreter imports: [exit code, stdout, stderr] for each, as JSON. The imports are
# checked to come from the venv, not the source tree.
HELPS = """
import contextlib, io, json, sys
import galvoscan
assert "site-packages" in galvoscan.__file__, galvoscan.__file__
from galvoscan.cli import main
results = []
for command in json.loads(sys.argv[1]):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main([*command, "--help"])
        except SystemExit as stop:
            code = stop.code
    results.append([code or 0, out.getvalue(), err.getvalue()])
print(json.dumps(results))
"""


def test_wheel_regs_export_and_sim(installed):
    script, where, _ = installed
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
    """The job path's libraries (svgelements, ezdxf, shapely, the TOML reader, usvg for SVG
    text and wasmtime to run it) come with it."""
    script, where, _ = installed
    result = _run(script, "machine", "init", "wheel.toml", cwd=where)
    assert result.returncode == 0, result.stderr
    (where / "box.svg").write_text(
        '<svg xmlns="http://www.w3.org/2000/svg" width="4mm" height="4mm" viewBox="0 0 4 4">'
        '<rect x="1" y="1" width="2" height="2"/>'
        '<text x="1" y="3.9" font-size="0.8" font-family="sans-serif">A</text></svg>')
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
