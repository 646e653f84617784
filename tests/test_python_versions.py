"""The Python versions ``requires-python`` promises are the ones the code runs on.

Only Python 3.11 is on the machines that run this suite, so the older ones are checked
statically: vermin reads every module (the package, its gateware, platforms, proofs, these
tests and the docs' examples) and names each feature that needs a newer Python than the
oldest ``requires-python`` allows (``tomllib`` without its ``tomli`` fallback, which is what
broke job files on 3.9 and 3.10).
"""

import re
import subprocess
import sys
from pathlib import Path

import pytest

try:
    import tomllib  # novermin: tomli below where it is missing
except ModuleNotFoundError:                      # Python < 3.11
    import tomli as tomllib


ROOT = Path(__file__).resolve().parent.parent
FOLDERS = ["galvoscan", "gateware", "platforms", "formal", "tests", "docs"]


def oldest_python():
    """The oldest Python ``requires-python`` allows, as ``"3.9"``."""
    spec = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["requires-python"]
    found = re.fullmatch(r">=\s*(3\.\d+)", spec.strip())
    assert found, f"requires-python is {spec!r}: this check reads only '>=3.N'"
    return found.group(1)


def vermin(*paths):
    """vermin's verdict on ``paths`` for the oldest Python: (exit code, its report)."""
    done = subprocess.run(
        # vermin has no ``__main__``: its console script's entry point, beside this Python.
        [sys.executable, "-c", "import sys, vermin; sys.exit(vermin.main())", "--no-tips", "--violations", "--eval-annotations",
         f"-t={oldest_python()}-", *map(str, paths)],
        capture_output=True, text=True, cwd=ROOT)
    return done.returncode, done.stdout + done.stderr


def test_every_module_runs_on_the_oldest_python_requires_python_allows():
    code, report = vermin(*[ROOT / folder for folder in FOLDERS if (ROOT / folder).exists()])
    assert code == 0, report


@pytest.mark.parametrize("source, needs", [
    ("import tomllib\n", "tomllib"),
    ("def f(a, b):\n    return list(zip(a, b, strict=True))\n", "zip(strict)"),
    ("def f(x):\n    match x:\n        case 1:\n            return 2\n", "pattern matching"),
])
def test_a_newer_feature_is_named(tmp_path, source, needs):
    """The check can fail: each of these needs 3.10 or 3.11."""
    (tmp_path / "newer.py").write_text(source)
    code, report = vermin(tmp_path / "newer.py")
    assert code != 0 and needs in report, report
