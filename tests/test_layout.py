"""The package's import graph follows the data (``../shared/ARCHITECTURE.md``, README
"Development"): no import circle, and no arrow from a lower floor up to a higher one.

Every ``import`` in every module counts, the lazy ones inside functions included (a lazy
import is still a dependency; it only hides a circle from the interpreter).
"""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = "ftlbo_mav"
ROOT = Path(__file__).resolve().parents[1] / PACKAGE


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in sorted(ROOT.rglob("*.py"))}


MODULES = _modules()


def _resolve(name: str) -> str | None:
    """The package module that ``import name`` loads, or None when outside the package."""
    if name != PACKAGE and not name.startswith(PACKAGE + "."):
        return None
    while name not in MODULES:  # ``from .x import function``: x is the module
        name = name.rpartition(".")[0]
    return name


def _imports(module: str) -> set[str]:
    path = MODULES[module]
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    is_package = path.name == "__init__.py"
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = module.split(".")
                base = base[: len(base) - node.level + (1 if is_package else 0)]
                origin = ".".join(base + ([node.module] if node.module else []))
            else:
                origin = node.module or ""
            # ``from pkg import name`` loads pkg.name when that is a module
            targets = [origin] + [f"{origin}.{alias.name}" for alias in node.names]
        else:
            continue
        for target in targets:
            resolved = _resolve(target)
            if resolved is not None and resolved != module:
                found.add(resolved)
    return found


GRAPH = {module: _imports(module) for module in MODULES}


def _part(module: str) -> str:
    """The floor a module lives on: ``ftlbo_mav.mission.gis`` -> ``mission``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def _cycles() -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    components: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(GRAPH[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                components.append(sorted(component))

    for v in sorted(GRAPH):
        if v not in index:
            visit(v)
    return components


def _arrows(from_parts: set[str], to_parts: set[str]) -> list[str]:
    return sorted(
        f"{m} -> {t}"
        for m, targets in GRAPH.items()
        if _part(m) in from_parts
        for t in targets
        if _part(t) in to_parts
    )


def test_the_graph_sees_the_package():
    assert "ftlbo_mav.scenario" in MODULES or "ftlbo_mav.scenario" in {
        _resolve(m) for m in MODULES
    }
    assert "ftlbo_mav.planning.planner" in GRAPH["ftlbo_mav.mission.export"]
    assert "ftlbo_mav.ardupilot.storage" in GRAPH["ftlbo_mav.link.codec"]


def test_no_import_cycle():
    assert _cycles() == []


INPUT_AND_PLANNING = {"scenario", "obstacles", "geo", "formation", "planning"}


def test_input_and_planning_import_nothing_downstream():
    assert _arrows(INPUT_AND_PLANNING, {"mission", "link", "flight", "sim"}) == []


def test_link_imports_nothing_from_the_emulator():
    assert _arrows({"link"}, {"sim"}) == []


def test_ardupilot_model_imports_only_errors_and_compiling():
    outside = sorted(
        f"{m} -> {t}"
        for m, targets in GRAPH.items()
        if _part(m) == "ardupilot"
        for t in targets
        if _part(t) not in {"ardupilot", "errors", "compiling"}
    )
    assert outside == []


def test_compiling_is_a_leaf():
    """numba's machinery (when a loop is cached, the word before a compile) imports
    nothing of the package: every floor may use it."""
    assert GRAPH["ftlbo_mav.compiling"] == set()
