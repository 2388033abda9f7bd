"""The compiled module of a mechanism description: generated once, stored, imported so numba's cache finds it.

The source (``evaluate``, ``indicators``, ``kinematics`` kernels) is written by
:func:`study.model.codegen.compiled_source` from the same printer and common-subexpression elimination as the
reference module, from a planar description (:func:`generated_module`) or any symbolic system (:func:`system_module`,
a spatial one's). It is stored in ``generated_dir()`` under a key of the description (or system) and of the compiled
path's sources (numeric load values are an argument, ``lp``), written atomically, and imported by name so numba's cache
can find it again in the next process.
"""

from __future__ import annotations

import hashlib
import importlib.util
import sys
from types import ModuleType
from typing import Callable

from study.integrity import ensure_generated
from study.kernels.cache import SOURCE_HASH, generated_dir
from study.model.builder import MechanismBuilder
from study.model.codegen import SymbolicSystem, compiled_source, planar_system
from study.model.compile import description_key
from study.model.derive import derive


def module_key(b: MechanismBuilder) -> str:
    """Hash of the description (loads and switching functions included) and the fast path's sources."""
    text = "\n".join([SOURCE_HASH, description_key(b), repr([c.name for c in b.contacts])])
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def generated_module(b: MechanismBuilder) -> ModuleType:
    """The numba module of a description, generated on first use and imported from the cache folder."""
    return compiled_module(b.name, module_key(b), lambda: planar_system(b, derive(b)))


def system_module(s: SymbolicSystem, key: str) -> ModuleType:
    """The numba module of a symbolic system keyed ``key`` (``study.model.compile.system_key``), e.g. a spatial one."""
    return compiled_module(s.name, hashlib.sha256(f"{SOURCE_HASH}\n{key}".encode()).hexdigest()[:16], lambda: s)


def compiled_module(mechanism: str, key: str, system: Callable[[], SymbolicSystem]) -> ModuleType:
    """The numba module ``study_fast_<mechanism>_<key>``: imported if it is, else written from ``system()`` (only
    when not stored yet), stored and imported."""
    name = f"study_fast_{mechanism}_{key}"
    if name in sys.modules:
        return sys.modules[name]
    path = generated_dir() / f"{name}.py"
    ensure_generated(path, lambda: compiled_source(system()))  # checksum-verified; regenerated if it fails
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # numba's cache pickles the module name and imports it on reload
    spec.loader.exec_module(module)   # its kernels have declared signatures: each compiles (or loads) on first use
    return module
