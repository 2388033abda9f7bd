"""A case's key: the code version of an engine (its source files and numeric packages) and the parameter hash.

A case's key (:meth:`study.pipeline.cases.Case.key`) hashes its specification, the SHA-256 of its
parameter set (:func:`parameter_hash`) and :func:`code_version`: the source of the code that computes
it (model, solver, mechanisms, and the Exudyn models or the in-house front end for that engine,
``CODE_PATHS``) and the versions of the numerical packages. The report, the studies' summaries and
the command line do not change a result and are left out.
"""

from __future__ import annotations

import json
from functools import lru_cache

from study.params import load_parameters
from study.results import package_versions
from study.sources import source_files, source_hash

# Source that determines a case's result, per engine (folders or files under study/). The report,
# the studies' summaries and the command line do not change a result and are left out.
_COMMON_CODE = ("model", "solver", "mechanisms", "params.py", "results.py", "reference_data.py",
                "fast/signatures.py", "fast/signs.py")   # the stabilization methods' compiled forms (solver/) use these
CODE_PATHS = {
    "inhouse": _COMMON_CODE + ("simulate.py", "fast"),
    "exudyn": _COMMON_CODE + ("exudyn_models",),
}
NUMERIC_PACKAGES = {"inhouse": ("numpy", "scipy", "sympy", "numba"), "exudyn": ("numpy", "scipy", "sympy", "exudyn")}


@lru_cache(maxsize=None)
def parameter_hash(mechanism: str, variant: str) -> str:
    """SHA-256 of a mechanism's parameter set ``variant``."""
    return load_parameters(mechanism, variant).sha256


@lru_cache(maxsize=None)
def code_version(engine: str) -> str:
    """SHA-256 (16 hex) of the source files that compute a result of ``engine`` + numeric package versions."""
    versions = package_versions()
    numeric = json.dumps({p: versions.get(p) for p in NUMERIC_PACKAGES[engine]}, sort_keys=True)
    return source_hash(source_files(*CODE_PATHS[engine]), extra=numeric)[:16]
