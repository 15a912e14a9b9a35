"""The package's floors: no import from a lower layer to a higher one (issue 28).

Every import of ``pipeline/**/*.py`` and ``analysis/**/*.py`` (at module level and inside
functions alike) is read from the source (no module is imported) and judged by the floor of the
package it lands in (:data:`FLOORS`): a package may import its own floor or lower, never a higher
one, and no two packages may import each other, directly or round about. Nothing outside
``pipeline/cli`` imports the CLI, the top level of ``pipeline/`` stays small, and a new package (or
top-level module) must be given its floor here before it can be imported at all.
"""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: Packages (and top-level modules) and their floors, bottom (0) to top: a unit may import only
#: units of its own floor or lower. ``pipeline`` is the facade, ``pipeline/__init__.py``.
FLOORS = {
    # 0: leaves (configuration, errors, progress lines, where dask work runs; the bundled TOML scenarios)
    "pipeline.config": 0, "pipeline.errors": 0, "pipeline.progress": 0, "pipeline.compute": 0,
    "pipeline.scenarios": 0,
    # 1: pure numpy/scipy
    "pipeline.physics": 1, "pipeline.fitting": 1,
    # 2: a scenario's solve, scene, measured height maps, stage files and reductions
    "pipeline.scene": 2, "pipeline.contact_solution": 2, "pipeline.heightmap": 2, "pipeline.store": 2,
    "pipeline.reductions": 2,
    # 3..7: before work, the stages, the full-field reference, the atlas, the predictor
    "pipeline.before_work": 3,
    "pipeline.stages": 4,
    "pipeline.reference": 5,
    "pipeline.atlas": 6,
    "pipeline.predict": 7,
    # 8: benchmarks, figures and report
    "pipeline.bench": 8, "analysis": 8,
    # 9: the command line and the facade
    "pipeline.cli": 9, "pipeline": 9,
}
#: Names any module may take from the facade: they need nothing above the leaves.
EXEMPT_FROM_FACADE = {"__version__"}
#: The most .py modules the top level of ``pipeline/`` may hold (``__init__.py`` included).
TOP_LEVEL_MODULES = 10


def module_name(path: Path) -> str:
    """The dotted name of a source file under :data:`ROOT` (a package's ``__init__.py``: the package)."""
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def sources() -> list[Path]:
    """Every ``.py`` file of ``pipeline/`` and ``analysis/``, sorted."""
    return sorted(p for top in ("pipeline", "analysis") for p in (ROOT / top).rglob("*.py"))


def is_module(name: str) -> bool:
    """Whether a dotted name is a module or package of this source tree."""
    path = ROOT.joinpath(*name.split("."))
    return path.with_suffix(".py").is_file() or (path / "__init__.py").is_file()


def unit(name: str) -> str:
    """The :data:`FLOORS` unit a dotted module name belongs to: the longest key it lies in."""
    keys = [k for k in FLOORS if name == k or name.startswith(k + ".")]
    return max(keys, key=len) if keys else name


def imports_of(path: Path) -> list[tuple[str, int]]:
    """The internal modules a file imports, anywhere in it, with their line: ``from P import m`` of a
    submodule ``m`` counts as ``P.m``; a facade name of :data:`EXEMPT_FROM_FACADE` is left out."""
    name = module_name(path)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found += [(alias.name, node.lineno) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(anchor + ([node.module] if node.module else []))
            for alias in node.names:
                if base == "pipeline" and alias.name in EXEMPT_FROM_FACADE:
                    continue
                target = f"{base}.{alias.name}"
                found.append((target if is_module(target) else base, node.lineno))
    return [(t, line) for t, line in dict.fromkeys(found) if t.split(".")[0] in ("pipeline", "analysis")]


def unit_edges() -> dict[tuple[str, str], list[str]]:
    """(importing unit, imported unit) -> the imports making it (``file:line -> module``), own unit left out."""
    edges: dict[tuple[str, str], list[str]] = defaultdict(list)
    for path in sources():
        here = unit(module_name(path))
        for target, line in imports_of(path):
            there = unit(target)
            if there != here:
                edges[here, there].append(f"{path.relative_to(ROOT)}:{line} -> {target}")
    return edges


def cycles(edges: dict[tuple[str, str], list[str]]) -> list[list[str]]:
    """The strongly connected components of more than one unit (Tarjan), each sorted."""
    graph: dict[str, list[str]] = defaultdict(list)
    for a, b in edges:
        graph[a].append(b)
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                out.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_the_scan_reads_function_level_imports_and_submodules() -> None:
    found = dict(imports_of(ROOT / "pipeline" / "__init__.py"))
    assert "pipeline.before_work.scenario_checks" in found  # at module level
    assert "pipeline.predict" in found  # inside __getattr__
    stages = {t for t, _ in imports_of(ROOT / "pipeline" / "stages" / "oxide.py")}
    assert "pipeline.store" in stages and "pipeline" not in stages  # `from pipeline import store`


def test_every_package_has_a_floor() -> None:
    modules = {module_name(p) for p in (ROOT / "pipeline").rglob("*.py")}
    unplaced = sorted(m for m in modules if unit(m) == "pipeline" and m != "pipeline")
    assert not unplaced, f"place these in FLOORS (tests/test_layers.py): {unplaced}"
    assert all(unit(module_name(p)) == "analysis" for p in (ROOT / "analysis").rglob("*.py"))
    stale = sorted(k for k in FLOORS if not is_module(k))
    assert not stale, f"FLOORS names units that are gone: {stale}"


def test_no_import_goes_up() -> None:
    upward = [f"{a} (floor {FLOORS[a]}) -> {b} (floor {FLOORS.get(b, 'none')}): {where}"
              for (a, b), lines in sorted(unit_edges().items()) if FLOORS.get(b, 99) > FLOORS[a] for where in lines]
    assert not upward, "imports from a lower floor to a higher one:\n" + "\n".join(upward)


def test_no_cycle_between_packages() -> None:
    edges = unit_edges()
    found = cycles(edges)
    detail = [f"{a} -> {b}: {edges[a, b][0]}" for c in found for a in c for b in c if (a, b) in edges]
    assert not found, f"packages importing each other: {found}\n" + "\n".join(detail)


def test_cycles_are_found() -> None:
    assert cycles({("a", "b"): [], ("b", "c"): [], ("c", "a"): [], ("c", "d"): []}) == [["a", "b", "c"]]
    assert cycles({("a", "b"): [], ("b", "c"): []}) == []


def test_only_the_cli_imports_the_cli() -> None:
    outside = [f"{path.relative_to(ROOT)}:{line}" for path in sources() if unit(module_name(path)) != "pipeline.cli"
               for target, line in imports_of(path) if unit(target) == "pipeline.cli"]
    assert not outside, f"library modules importing pipeline.cli: {outside}"


def test_the_top_level_stays_small() -> None:
    top = sorted(p.name for p in (ROOT / "pipeline").glob("*.py"))
    assert len(top) <= TOP_LEVEL_MODULES, f"pipeline/ holds {len(top)} modules (at most {TOP_LEVEL_MODULES}): {top}"
