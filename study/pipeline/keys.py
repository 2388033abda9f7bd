"""A case's key: the code version of an engine (its source files and numeric packages) and the mechanism's content.

A case's key (:meth:`study.pipeline.cases.Case.key`) hashes its specification, the mechanism's fingerprint
(:func:`mechanism_hash`: the description's symbolic content, the parameter file, Newton's start) and
:func:`code_version`: the source of every module that computes it, found by following the import graph
(:func:`study.imports.dependencies`) from the engine's entry modules (``ENTRY_MODULES``), and the versions of the
numerical packages. What those modules do not import (the report, the studies' summaries, the command line)
does not change a result and is left out. So are the description modules (``study.mechanisms.<name>``): what
they produce is in the fingerprint, so an edit to one mechanism recomputes that mechanism's cases only, and a
user's mechanism file, or a Mechanism passed in from Python, is keyed the same way.
"""

from __future__ import annotations

import json
from functools import lru_cache

from study.mechanisms import named_mechanism
from study.model import Mechanism
from study.results import package_versions
from study.imports import dependencies
from study.sources import source_hash

# Where a case's result is computed (study.pipeline.execute.run_case), per engine; the key covers what they import.
ENTRY_MODULES = {   # study.spatial: a spatial mechanism's equations (the engines reach them through the Mechanism)
    "inhouse": ("study.pipeline.execute", "study.simulate", "study.mechanisms", "study.spatial"),
    "exudyn": ("study.pipeline.execute", "study.exudyn_models", "study.mechanisms", "study.spatial"),
}
NUMERIC_PACKAGES = {"inhouse": ("numpy", "scipy", "sympy", "numba"), "exudyn": ("numpy", "scipy", "sympy", "exudyn")}
DESCRIPTIONS = "study.mechanisms."   # the description modules: keyed by what they produce (mechanism_hash)


def mechanism_of(mechanism: str | Mechanism, variant: str) -> Mechanism:
    """A case's mechanism: a study mechanism by name or a user's mechanism file by path, in a variant
    (:func:`study.mechanisms.named_mechanism`), or a Mechanism passed in from Python (``study validate``), as it is."""
    return mechanism if isinstance(mechanism, Mechanism) else named_mechanism(mechanism, variant)


@lru_cache(maxsize=None)
def mechanism_hash(mechanism: str | Mechanism, variant: str) -> str:
    """Fingerprint of a case's mechanism (:func:`mechanism_of`): a Mechanism object is keyed by its content, as a
    user's file is."""
    return mechanism_of(mechanism, variant).fingerprint()


@lru_cache(maxsize=None)
def code_version(engine: str) -> str:
    """SHA-256 (16 hex) of the source files that compute a result of ``engine`` + numeric package versions."""
    versions = package_versions()
    numeric = json.dumps({p: versions.get(p) for p in NUMERIC_PACKAGES[engine]}, sort_keys=True)
    return source_hash(dependencies(*ENTRY_MODULES[engine], exclude=DESCRIPTIONS), extra=numeric)[:16]
