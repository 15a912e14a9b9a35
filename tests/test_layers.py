"""The package's floors: no import from a lower layer to a higher one, and no circles.

Every import of ``pipeline/**/*.py`` (installed as :mod:`g2tom`) and ``analysis/**/*.py`` (installed
as :mod:`g2tom.analysis`), at module level and inside functions alike, is read from the source (no
module is imported) and judged by the floor of the package it lands in (:data:`FLOORS`): a package
may import its own floor or lower, never a higher one, and no two packages (nor two modules) may
import each other, directly or round about. Nothing outside ``g2tom.cli`` imports the CLI, the
facade (``g2tom/__init__.py``) imports nothing of the package at import time, the top level stays
small, and a new package (or top-level module) must be given its floor here before it can be
imported at all.
"""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: Packages (and top-level modules) and their floors, bottom (0) to top: a unit may import only
#: units of its own floor or lower. ``g2tom`` is the facade, ``pipeline/__init__.py``.
FLOORS = {
    # 0: leaves (configuration, errors, progress lines, where dask work runs; the bundled TOML scenarios;
    # the metadata registry of every written variable)
    "g2tom.config": 0, "g2tom.errors": 0, "g2tom.progress": 0, "g2tom.compute": 0,
    "g2tom.scenarios": 0, "g2tom.variables": 0,
    # 1: pure numpy/scipy
    "g2tom.physics": 1, "g2tom.fitting": 1,
    # 2: a scenario's solve, scene, measured height maps, stage files and reductions
    "g2tom.scene": 2, "g2tom.contact_solution": 2, "g2tom.heightmap": 2, "g2tom.store": 2,
    "g2tom.reductions": 2,
    # 3: the contact models (each its checks, contact pool, cube spots and chunks, costs and words)
    "g2tom.models": 3,
    # 4..8: before work, the stages, the full-field reference, the atlas, the predictor
    "g2tom.before_work": 4,
    "g2tom.stages": 5,
    "g2tom.reference": 6,
    "g2tom.atlas": 7,
    "g2tom.predict": 8,
    # 8: the full field on a measured surface (beside the predictor: it may ask it for the statistical answer)
    "g2tom.surface": 8,
    # 9: benchmarks, figures and report
    "g2tom.bench": 9, "g2tom.analysis": 9,
    # 10: the command line and the facade
    "g2tom.cli": 10, "g2tom": 10,
}
#: Names any module may take from the facade: they need nothing above the leaves.
EXEMPT_FROM_FACADE = {"__version__"}
#: The source folder of each installed package (``pyproject.toml``'s ``package-dir``).
SOURCE_DIRS = {"pipeline": "g2tom", "analysis": "g2tom.analysis"}
#: The most .py modules the top level of ``pipeline/`` may hold (``__init__.py`` included).
TOP_LEVEL_MODULES = 10


def module_name(path: Path) -> str:
    """The dotted name of a source file under :data:`ROOT` (a package's ``__init__.py``: the package)."""
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join([SOURCE_DIRS[parts[0]], *parts[1:]])


def sources() -> list[Path]:
    """Every ``.py`` file of ``pipeline/`` and ``analysis/``, sorted."""
    return sorted(p for top in ("pipeline", "analysis") for p in (ROOT / top).rglob("*.py"))


def is_module(name: str) -> bool:
    """Whether a dotted name is a module or package of this source tree."""
    parts = name.split(".")
    folder = "analysis" if parts[:2] == ["g2tom", "analysis"] else "pipeline"
    path = ROOT.joinpath(folder, *parts[1 + (folder == "analysis"):])
    return parts[0] == "g2tom" and (path.with_suffix(".py").is_file() or (path / "__init__.py").is_file())


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
                if base == "g2tom" and alias.name in EXEMPT_FROM_FACADE:
                    continue
                target = f"{base}.{alias.name}"
                found.append((target if is_module(target) else base, node.lineno))
    return [(t, line) for t, line in dict.fromkeys(found) if t.split(".")[0] == "g2tom"]


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
    assert "g2tom.predict" in found  # inside __getattr__
    stages = {t for t, _ in imports_of(ROOT / "pipeline" / "stages" / "oxide.py")}
    assert "g2tom.store" in stages and "g2tom" not in stages  # `from g2tom import store`
    figures = {t for t, _ in imports_of(ROOT / "analysis" / "figures_contact.py")}
    assert "g2tom.analysis.style" in figures


def test_every_package_has_a_floor() -> None:
    modules = {module_name(p) for p in (ROOT / "pipeline").rglob("*.py")}
    unplaced = sorted(m for m in modules if unit(m) == "g2tom" and m != "g2tom")
    assert not unplaced, f"place these in FLOORS (tests/test_layers.py): {unplaced}"
    assert all(unit(module_name(p)) == "g2tom.analysis" for p in (ROOT / "analysis").rglob("*.py"))
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


def test_no_cycle_between_modules() -> None:
    graph = defaultdict(list)
    for path in sources():
        for target, line in imports_of(path):
            graph[module_name(path)].append(f"{target}")
    edges = {(a, b): [] for a, targets in graph.items() for b in targets if b != a and not a.startswith(b + ".")}
    found = cycles(edges)
    assert not found, f"modules importing each other: {found}"


def test_the_facade_imports_nothing_of_the_package_at_import_time() -> None:
    tree = ast.parse((ROOT / "pipeline" / "__init__.py").read_text())
    top = [node for node in tree.body if isinstance(node, (ast.Import, ast.ImportFrom))]
    names = [node.module if isinstance(node, ast.ImportFrom) else node.names[0].name for node in top]
    assert not [n for n in names if n and n.split(".")[0] == "g2tom"], names


def test_no_module_imports_the_old_top_level_names() -> None:
    old = [f"{path.relative_to(ROOT)}:{node.lineno}" for path in sources() + sorted((ROOT / "tests").rglob("*.py"))
           for node in ast.walk(ast.parse(path.read_text()))
           if isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] in ("pipeline", "analysis")
           or isinstance(node, ast.Import) and any(a.name.split(".")[0] in ("pipeline", "analysis") for a in node.names)]
    assert not old, f"imports of `pipeline` or `analysis` (the package is `g2tom`): {old}"


def test_cycles_are_found() -> None:
    assert cycles({("a", "b"): [], ("b", "c"): [], ("c", "a"): [], ("c", "d"): []}) == [["a", "b", "c"]]
    assert cycles({("a", "b"): [], ("b", "c"): []}) == []


def test_only_the_cli_imports_the_cli() -> None:
    outside = [f"{path.relative_to(ROOT)}:{line}" for path in sources() if unit(module_name(path)) != "g2tom.cli"
               for target, line in imports_of(path) if unit(target) == "g2tom.cli"]
    assert not outside, f"library modules importing g2tom.cli: {outside}"


def test_the_top_level_stays_small() -> None:
    top = sorted(p.name for p in (ROOT / "pipeline").glob("*.py"))
    assert len(top) <= TOP_LEVEL_MODULES, f"pipeline/ holds {len(top)} modules (at most {TOP_LEVEL_MODULES}): {top}"
