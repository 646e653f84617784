"""The gateware's packages import in one direction: no cycle between its subpackages, and
nothing below the top-level wiring imports :mod:`galvoscan.gateware.top` (read from the
sources' import statements, not from what happens to be loaded)."""

import ast
from pathlib import Path

import galvoscan.gateware


GATEWARE = Path(galvoscan.gateware.__file__).parent


def _unit(path):
    """The unit a module belongs to: its subpackage (``"host"``), or its own name for a
    top-level module (``"limits"``)."""
    parts = path.relative_to(GATEWARE).with_suffix("").parts
    return parts[0]


def _imports(path):
    """The gateware units that module ``path`` imports (relative imports only: the gateware
    imports itself so)."""
    here = path.relative_to(GATEWARE).parent.parts
    units = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.level:
            base = here[:len(here) - (node.level - 1)] if node.level > 1 else here
            if node.level - 1 > len(here):
                continue            # above the gateware package
            target = base + tuple(node.module.split(".")) if node.module else base
            if target:
                units.add(target[0])
            else:                   # `from .. import limits`
                units.update(alias.name for alias in node.names)
    return units


def _graph():
    graph = {}
    for path in GATEWARE.rglob("*.py"):
        if path.name == "__init__.py" and path.parent == GATEWARE:
            continue
        unit = _unit(path)
        graph.setdefault(unit, set()).update(_imports(path) - {unit})
    return graph


def test_the_graph_sees_the_known_imports():
    # (So that the checks below cannot pass on a graph that reads no import at all.)
    graph = _graph()
    assert "fields" in graph["sources"]
    assert "host" in graph["top"]
    assert "limits" in graph["host"]


def test_nothing_below_imports_the_top():
    graph = _graph()
    assert [unit for unit, imported in graph.items() if "top" in imported] == []


def test_no_import_cycle_between_gateware_units():
    graph = _graph()
    done, path = set(), []

    def visit(unit):
        if unit in path:
            raise AssertionError(f"import cycle: {' -> '.join(path[path.index(unit):] + [unit])}")
        if unit in done:
            return
        path.append(unit)
        for imported in sorted(graph.get(unit, ())):
            visit(imported)
        path.pop()
        done.add(unit)

    for unit in sorted(graph):
        visit(unit)
