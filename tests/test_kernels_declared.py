"""Kernels with a declared signature (study.kernels.cache.kernel(SIGNATURE)): nothing compiles at import; on first
use, whichever use comes first, exactly the declared overload compiles, and every later use finds it, converts to it
or is refused, as after numba's own ``njit(SIGNATURE)``."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest
from numba import njit, types

from study.kernels.cache import kernel

SCALE = types.float64(types.float64, types.float64)


def _scaled(x, k):
    return x * k + 0.5


def _declared():
    """A fresh declared kernel of _scaled (each test its own dispatcher: the first use is the test's)."""
    return kernel(SCALE)(_scaled)


def test_import_study_compiles_no_kernel(tmp_path):
    script = ("import study, study.kernels.signs as s, study.laws.stabilization as b, study.laws.friction as f\n"
              "kernels = [*s.SIGN_FUNCTIONS.values(), b.zero_bias, b.baumgarte_bias, b.sliding_mode_bias,\n"
              "           f.mode_phases, f.slip_phases, f.switching_pair]\n"
              "print(sum(len(k.overloads) for k in kernels))\n")
    env = {**os.environ, "STUDY_CACHE_DIR": str(tmp_path)}
    out = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "0"


def test_a_call_from_python_compiles_the_declared_signature_only():
    f = _declared()
    assert len(f.overloads) == 0
    assert f(3, 2) == 6.5                     # int arguments: converted to the declared float64 ones
    assert f.signatures == [SCALE.args]
    with pytest.raises(TypeError):
        f(np.ones(2), 2.0)                     # no overload for an array, and none compiled for it
    assert f.signatures == [SCALE.args]


def test_a_call_from_compiled_code_compiles_the_declared_signature_only():
    f = _declared()

    @njit
    def caller(n):
        return f(n, 2) + f(1.5, n)            # int64 and literal arguments: the declared overload

    assert caller(3) == 6.5 + 5.0
    assert f.signatures == [SCALE.args]


def test_a_first_class_use_compiles_the_declared_signature_only():
    f = _declared()

    @njit(types.float64(types.FunctionType(SCALE), types.float64))
    def apply(g, x):
        return g(x, 4.0)

    assert apply(f, 0.25) == 1.5
    assert f.signatures == [SCALE.args]


def test_importing_study_sets_numbas_optimization_level_unless_the_user_did():
    """study sets NUMBA_OPT=1 before numba is imported (study/__init__.py gives the reason); the user's value wins."""
    import os
    import subprocess
    import sys

    code = "import study, numba; print(int(numba.config.OPT))"
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_OPT"}
    levels = [subprocess.run([sys.executable, "-c", code], env={**env, **extra}, capture_output=True, text=True,
                             check=True).stdout.split()[-1] for extra in ({}, {"NUMBA_OPT": "3"})]
    assert levels == ["1", "3"]
