"""The modules under ``study/`` import each other without a cycle, imports inside functions included.

Every ``.py`` file under ``study/`` is parsed with :mod:`ast`; every ``import study...`` and
``from ... import ...`` anywhere in it (top level, inside functions, under ``if TYPE_CHECKING``) that
names a ``study`` module is an edge. Relative imports are resolved against the importing module's
package. ``from study.x import y`` is an edge to ``study.x.y`` when that is a module, else to
``study.x``.

One kind of edge is left out: a package's ``__init__`` importing from its own submodules (re-exporting
them). Importing ``study.p.sub`` runs ``study/p/__init__.py`` first, so every submodule "imports" its
package; with the re-export edge that would make every re-exporting package a cycle, although Python
resolves it (the package finishes importing its submodules before anything uses it). An ``__init__``
importing anything else (another package, a sibling's submodule) is an edge like any other.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "study"


def module_names() -> dict[str, Path]:
    """Dotted module name -> file, for every .py file under study/ (a package is its __init__)."""
    names = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        names[".".join(parts)] = path
    return names


def imported_modules(name: str, path: Path, modules: set[str]) -> set[str]:
    """The study modules that module ``name`` (file ``path``) imports anywhere in its body."""
    is_package = path.name == "__init__.py"
    package = name if is_package else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                if node.level - 1 > len(package.split(".")) - 1:
                    raise ValueError(f"{path}: relative import beyond the top package (level {node.level})")
                stem = ".".join(base + ([node.module] if node.module else []))
            else:
                stem = node.module
            targets = [f"{stem}.{alias.name}" if f"{stem}.{alias.name}" in modules else stem
                       for alias in node.names]
        else:
            continue
        for target in targets:
            # "import study.a.b" binds study.a.b; the nearest module that exists is the edge's end
            while target and target not in modules:
                target = target.rpartition(".")[0]
            if not target or not target.startswith("study"):
                continue
            if is_package and target.startswith(name + "."):
                continue  # a package re-exporting its own submodule (see the module docstring)
            if target != name:
                found.add(target)
    return found


def import_graph() -> dict[str, set[str]]:
    files = module_names()
    return {name: imported_modules(name, path, set(files)) for name, path in files.items()}


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One cycle as a list of modules (first == last), or None; depth-first search with colours."""
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == 1:
                return stack[stack.index(nxt):] + [nxt]
            if nxt not in state:
                cycle = visit(nxt)
                if cycle:
                    return cycle
        stack.pop()
        state[node] = 2
        return None

    for start in sorted(graph):
        if start not in state:
            cycle = visit(start)
            if cycle:
                return cycle
    return None


def test_cycle_finder_finds_a_planted_cycle():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert find_cycle(graph) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set(), "c": {"a", "b"}}) is None


def test_relative_and_function_level_imports_are_edges(tmp_path):
    pkg = tmp_path / "study" / "p"
    pkg.mkdir(parents=True)
    (pkg / "__init__.py").write_text("from study.p.a import f\n")
    (pkg / "a.py").write_text("def f():\n    from . import b\n    from ..q import g\n")
    modules = {"study", "study.p", "study.p.a", "study.p.b", "study.q"}
    assert imported_modules("study.p.a", pkg / "a.py", modules) == {"study.p.b", "study.q"}
    assert imported_modules("study.p", pkg / "__init__.py", modules) == set()  # own submodule: left out


def test_study_has_no_import_cycle():
    graph = import_graph()
    assert len(graph) > 50, f"only {len(graph)} modules found under {PACKAGE}"
    cycle = find_cycle(graph)
    if cycle:
        pytest.fail("import cycle: " + " -> ".join(cycle))
