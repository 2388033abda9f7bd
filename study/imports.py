"""The package's import graph, read from its source: which ``study`` modules each module imports.

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

:func:`dependencies` is what a cache key covers: the modules reachable from some entry modules. A package
reached that way brings all its submodules with it (a package's code may reach its submodules in ways no
``import`` statement shows, e.g. by name with :mod:`importlib`). A module's enclosing packages add their
``__init__`` files, which run first, but not what those re-export; the top package's ``__init__`` (the public
re-exports) is left out: it computes nothing.
"""

from __future__ import annotations

import ast
from functools import lru_cache
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent


def module_names(package: Path | None = None) -> dict[str, Path]:
    """Dotted module name -> file, for every .py file under ``package`` (default: study/; a package is its __init__)."""
    package = PACKAGE if package is None else package
    names = {}
    for path in sorted(package.rglob("*.py")):
        parts = list(path.relative_to(package.parent).with_suffix("").parts)
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
                if node.level - 1 > len(base) - 1:
                    raise ValueError(f"{path}: relative import beyond the top package (level {node.level})")
                base = base[: len(base) - (node.level - 1)]
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
            if not target or not target.startswith(PACKAGE.name):
                continue
            if is_package and target.startswith(name + "."):
                continue  # a package re-exporting its own submodule (see the module docstring)
            if target != name:
                found.add(target)
    return found


def import_graph(package: Path | None = None) -> dict[str, set[str]]:
    """Module -> the study modules it imports."""
    files = module_names(package)
    return {name: imported_modules(name, path, set(files)) for name, path in files.items()}


@lru_cache(maxsize=None)
def _package_graph(package: Path) -> tuple[dict[str, Path], dict[str, set[str]]]:
    """The modules and the import graph of ``package``, parsed once per process."""
    return module_names(package), import_graph(package)


@lru_cache(maxsize=None)
def dependencies(*entries: str, exclude: str | None = None) -> tuple[Path, ...]:
    """The files of the modules reachable from ``entries`` (the entries included), sorted; modules whose names start
    with ``exclude`` are neither included nor followed.

    Raises
    ------
    KeyError
        An entry is not a module of the package (a stale name would silently drop code from a key).
    """
    files, graph = _package_graph(PACKAGE)
    unknown = [e for e in entries if e not in files]
    if unknown:
        raise KeyError(f"not modules of {PACKAGE.name}: {', '.join(unknown)}")
    seen: set[str] = set()
    todo = list(entries)
    while todo:
        name = todo.pop()
        if name in seen or (exclude and name.startswith(exclude)):
            continue
        seen.add(name)
        todo += graph[name]
        if files[name].name == "__init__.py" and name != PACKAGE.name:
            todo += [m for m in files if m.startswith(name + ".")]
    parents = {m.rsplit(".", i)[0] for m in seen for i in range(1, m.count("."))}
    return tuple(sorted(files[m] for m in seen | parents))


#: The layer drawing, bottom to top: a module may import modules of its own layer or of a layer below, never above.
#: A name is a top-level module or package of ``study`` (a package covers its submodules); ``study`` itself (the
#: public re-exports) is the top. The reference path (``solver``) and the compiled path (``fast``) share the laws
#: below them (``laws``), and the reference path never imports the compiled one.
LAYERS: tuple[tuple[str, ...], ...] = (
    ("errors", "locations", "sources", "cache_folder", "integrity", "arguments", "reference_data",
     "reference_solutions", "imports", "progress", "output_folder", "emulate", "results", "compare"),
    ("kernels",),
    ("model", "mechanisms", "params", "inline_parameters", "user_mechanism", "spatial"),
    ("laws",),
    ("solver",),
    ("fast",),
    ("friction_default", "run_arguments", "reactions"),
    ("exudyn_models", "engines", "simulate"),
    ("pipeline", "validation_plan"),
    ("studies", "errata", "initial_report", "verify", "report", "bench", "validation", "validation_report",
     "describe"),
    ("cli", "cli_pipeline", "__main__", ""),
)


def layer_of(module: str) -> int:
    """The layer index of a study module (by its top-level name under ``study``).

    Raises
    ------
    KeyError
        The module's top-level name is in no layer (a new module must be placed in the drawing).
    """
    top = module.split(".")[1] if "." in module else ""
    for index, names in enumerate(LAYERS):
        if top in names:
            return index
    raise KeyError(f"{module}: {top!r} is in no layer of study.imports.LAYERS")


def upward_imports(graph: dict[str, set[str]]) -> list[str]:
    """Every edge of ``graph`` that goes up the layer drawing, as 'a (layer) -> b (layer)'."""
    return [f"{a} ({layer_of(a)}) -> {b} ({layer_of(b)})"
            for a in sorted(graph) for b in sorted(graph[a]) if layer_of(b) > layer_of(a)]
