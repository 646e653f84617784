"""The host's package layout: no import cycle among galvoscan's modules, and no package importing
one above it in the data flow (settings → link, profile and flashing → geometry → inputs →
plan → outputs → sim → the API → the CLI → the meerk40t device).

The graph is grimp's, of every import in the source (those inside functions too), built from a
copy of the four source folders in their installed layout: the editable install maps
``galvoscan.gateware`` and the others onto folders beside ``galvoscan/``, where grimp, which
reads a package from one folder, would not find them.
"""

import copy
import shutil
import sys
from pathlib import Path

import grimp
import pytest


ROOT = Path(__file__).resolve().parents[1]
#: Source folder → where it is installed, under the copy's ``galvoscan/``.
FOLDERS = {"galvoscan": "", "gateware": "gateware", "platforms": "platforms", "formal": "formal"}

#: The host's layers, highest first: a package may import those below it, never one above.
#: Packages on one row are independent of each other (neither imports the other).
LAYERS = (
    # (meerk40t's device: galvoscan as a plugin of another program, on top of the API and the
    # CLI's reports.)
    "galvoscan.meerk40t",
    "galvoscan.cli",
    "galvoscan.api",
    "galvoscan.sim",
    "galvoscan.outputs",
    "galvoscan.plan",
    "galvoscan.inputs",
    "galvoscan.geometry",
    # (flashing: the board's flash written from bytes, the job image's layout its only
    # dependency, below the packages that make the image; the CLI calls it.)
    ("galvoscan.profile", "galvoscan.flashing"),
    # (The link below the profile: the profile's template says how long the line takes to
    # bring a frame.)
    "galvoscan.link",
    "galvoscan.settings",
)

@pytest.fixture(scope="module")
def graph(tmp_path_factory):
    copy = tmp_path_factory.mktemp("layout")
    for folder, installed in FOLDERS.items():
        shutil.copytree(ROOT / folder, copy / "galvoscan" / installed, dirs_exist_ok=True,
                        ignore=shutil.ignore_patterns("__pycache__"))
    sys.path.insert(0, str(copy))
    try:
        # (Read from the files, not imported: the copy's modules never reach sys.modules.)
        return grimp.build_graph("galvoscan", cache_dir=None)
    finally:
        sys.path.remove(str(copy))


def cycles(graph):
    """The graph's import cycles: each strongly connected set of two or more modules (Tarjan's
    algorithm, iterative: the graph is deeper than Python's recursion limit allows for)."""
    index, low, on_stack, stack, found = {}, {}, set(), [], []
    for start in sorted(graph.modules):
        if start in index:
            continue
        work = [(start, iter(sorted(graph.find_modules_directly_imported_by(start))))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            module, imported = work[-1]
            for other in imported:
                if other not in index:
                    index[other] = low[other] = len(index)
                    stack.append(other)
                    on_stack.add(other)
                    work.append((other, iter(sorted(graph.find_modules_directly_imported_by(
                        other)))))
                    break
                if other in on_stack:
                    low[module] = min(low[module], index[other])
            else:
                work.pop()
                if work:
                    parent = work[-1][0]
                    low[parent] = min(low[parent], low[module])
                if low[module] == index[module]:
                    component = set()
                    while True:
                        member = stack.pop()
                        on_stack.discard(member)
                        component.add(member)
                        if member == module:
                            break
                    if len(component) > 1:
                        found.append(component)
    return found


def sorted_cycles(graph):
    return [sorted(c) for c in cycles(graph)]


def upward_imports(graph):
    """``"importer -> imported"`` for each package of a lower layer that imports a higher one."""
    layers = [grimp.Layer(*row) if isinstance(row, tuple) else grimp.Layer(row)
              for row in LAYERS]
    return sorted(f"{dependency.importer} -> {dependency.imported}"
                  for dependency in graph.find_illegal_dependencies_for_layers(layers=layers))


def test_no_import_cycle(graph):
    assert sorted_cycles(graph) == []


def test_no_layer_imports_one_above_it(graph):
    assert upward_imports(graph) == []


def test_the_layers_are_the_host_packages(graph):
    """Every host package is in the layers (or above them all: the CLI, the bench, the
    analysis), so that a new one is placed on purpose."""
    named = {p for row in LAYERS for p in (row if isinstance(row, tuple) else (row,))}
    above = {"galvoscan.analysis", "galvoscan.correction", "galvoscan.gateware",
             "galvoscan.platforms", "galvoscan.formal"}
    packages = {m for m in graph.find_children("galvoscan")
                if graph.find_children(m)}
    assert packages - named - above == set()


def test_a_cycle_is_caught(graph):
    """The checks fail on a cycle: an import made from the lowest module back to one above."""
    graph = copy.deepcopy(graph)
    graph.add_import(importer="galvoscan.geometry.field", imported="galvoscan.plan.vector_job")
    assert any({"galvoscan.geometry.field", "galvoscan.plan.vector_job"} <= set(c)
               for c in sorted_cycles(graph))
    assert "galvoscan.geometry -> galvoscan.plan" in upward_imports(graph)


def test_a_cycle_inside_a_package_is_caught(graph):
    graph = copy.deepcopy(graph)
    graph.add_import(importer="galvoscan.geometry.field", imported="galvoscan.geometry.hatch")
    assert ["galvoscan.geometry.field", "galvoscan.geometry.hatch"] in sorted_cycles(graph)
    assert upward_imports(graph) == []          # (inside one layer: a cycle, not a layer's)
