"""The docs build: Sphinx with MyST, warnings as errors, nitpicky, so that every internal link
and heading anchor resolves (``myst_heading_anchors``). External links are checked for form
only (scheme and host), never fetched: the suite runs without a network, so Sphinx's
``linkcheck`` builder is not run here."""

from pathlib import Path
import re
import shutil
import subprocess
import sys
from urllib.parse import urlsplit


ROOT = Path(__file__).parent.parent
DOCS = ROOT / "docs"


def sphinx_build(source, out):
    """Build the docs at ``source`` into ``out`` as HTML, warnings as errors: (exit status,
    the warnings)."""
    proc = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-n", "-q", "-b", "html",
         "-d", str(out / "doctrees"), str(source), str(out / "html")],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=300)
    return proc.returncode, proc.stderr


def docs_copy(tmp_path):
    """The docs' pages and configuration (not their figures' data) in a folder of their own."""
    copy = tmp_path / "docs"
    shutil.copytree(DOCS, copy, ignore=shutil.ignore_patterns("_build"))
    return copy


def test_docs_build_with_no_warning(tmp_path):
    status, warnings = sphinx_build(DOCS, tmp_path)
    assert status == 0 and warnings == "", warnings
    for page in ("index", "user/marking", "reference/registers", "design/architecture"):
        assert (tmp_path / "html" / f"{page}.html").is_file(), page


def test_a_broken_internal_link_fails_the_build(tmp_path):
    """One copy of the docs with three broken links: each is reported, and the build fails."""
    copy = docs_copy(tmp_path)
    marking = copy / "user" / "marking.md"
    broken = {
        "no-such-heading": "[the laser](../hardware/laser.md#no-such-heading)",  # another page's
        "not-this-one": "[above](#not-this-one)",                                # this page's
        "no-such-page.md": "[a page](no-such-page.md)",                          # no page
    }
    marking.write_text(marking.read_text()
                       + "".join(f"\nSee {link}.\n" for link in broken.values()))
    status, warnings = sphinx_build(copy, tmp_path / "out")
    assert status != 0
    reported = [line for line in warnings.splitlines() if "marking.md" in line]
    for target in broken:
        assert any(target in line and "not found" in line for line in reported), warnings


def external_links():
    """Every http(s) link in the README and the docs: (file, url)."""
    files = [ROOT / "README.md", *sorted(DOCS.rglob("*.md"))]
    return [(path.relative_to(ROOT).as_posix(), url) for path in files
            if "_build" not in path.parts
            for url in re.findall(r"\]\((https?://[^)\s]+)\)|<(https?://[^>\s]+)>",
                                  path.read_text())
            for url in url if url]


def test_external_links_are_well_formed():
    links = external_links()
    assert links
    for where, url in links:
        parts = urlsplit(url)
        assert parts.scheme == "https", (where, url)
        assert re.fullmatch(r"[a-z0-9-]+(\.[a-z0-9-]+)+", parts.netloc), (where, url)
