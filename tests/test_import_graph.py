"""The modules under ``study/`` import each other without a cycle, imports inside functions included.

The graph is :func:`study.imports.import_graph` (every ``import`` of a ``study`` module anywhere in a file, read
with :mod:`ast`; a package re-exporting its own submodules is not an edge, see that module).
"""

from __future__ import annotations

import pytest

from study.imports import PACKAGE, import_graph, imported_modules, layer_of, upward_imports


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


def test_upward_import_is_found():
    graph = {"study.solver.integrate": {"study.fast.loop"}, "study.fast.loop": {"study.solver.integrate"}}
    assert upward_imports(graph) == ["study.solver.integrate (4) -> study.fast.loop (5)"]
    with pytest.raises(KeyError, match="no layer"):
        layer_of("study.nowhere")


def test_no_import_goes_up_the_layer_drawing():
    """The layer drawing (study.imports.LAYERS): the reference path never imports the compiled one, the laws import
    neither, and no module imports one above its layer."""
    graph = import_graph()
    unplaced = sorted({m for m in graph if _unplaced(m)})
    assert not unplaced, f"modules in no layer of study.imports.LAYERS: {unplaced}"
    up = upward_imports(graph)
    assert not up, "upward imports:\n" + "\n".join(up)


def _unplaced(module: str) -> bool:
    try:
        layer_of(module)
    except KeyError:
        return True
    return False
