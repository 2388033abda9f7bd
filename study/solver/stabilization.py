"""Constraint stabilization methods, chosen by name (``STABILIZATIONS``).

The acceleration-level constraint is Phi_q qdd = gamma + b, with Phi_ddot = b the desired
constraint dynamics (Phi_ddot = Phi_q qdd - gamma):

- ``none``:         b = 0 (Phi_ddot = 0; Phi drifts).
- ``baumgarte``:    b = -2 d w Phidot - w^2 Phi          (001 eq. 11; alpha = d w, beta = w).
- ``sliding_mode``: s = Phidot + Lambda Phi,  b = -Lambda Phidot - K s - k sgn(s)   (001 eqs. 14-17).
- ``projection``:   b = 0, and after every accepted step q is projected onto Phi = 0 and qd onto
                    Phi_q qd = 0 (minimum-norm or mass-weighted Gauss-Newton).

The sgn function of the sliding mode is one of ``SIGN_FUNCTIONS`` (001 after eq. 17; ``study.kernels.signs``, one
numba function each for both backends).

Each method is one class for both backends around its law in ``study.laws``: ``compiled_bias`` is its bias law
(``study.laws.stabilization``, a numba function of signature ``study.kernels.signatures.BIAS``), which the compiled
loop calls with the parameters ``compiled_parameters(r)`` packed into its options
(``study.fast.frontend.pack_options``), and ``bias`` is the same law called from Python (the reference path). The
projection's correction is ``study.laws.projection``, run by :meth:`Projection.project` through its source. A new
method (or a subclass that changes ``bias``) runs compiled once its class defines both ``bias`` and
``compiled_bias``; a class that does not define its own ``compiled_bias`` is refused by name on the compiled path.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from study import arguments
from study.kernels.signs import SIGN_FUNCTIONS
from study.laws import projection
from study.laws.stabilization import (apply_bias, baumgarte_bias, baumgarte_parameters, sliding_mode_bias,
                                      sliding_mode_parameters, zero_bias)
from study.reference_data import tolerance

from study.model.eom import EquationsOfMotion

Array = np.ndarray


def _positive(owner: str, **values: float) -> None:
    """Each value a finite positive number (or array of them), else one ValueError naming it."""
    for key, value in values.items():
        try:
            arr = np.atleast_1d(np.asarray(value, dtype=float))
        except (TypeError, ValueError):
            raise ValueError(f"{owner}: {key} = {value!r} must be a number (finite and > 0)") from None
        if not np.all(np.isfinite(arr)) or np.any(arr <= 0):
            raise ValueError(f"{owner}: {key} = {value!r} must be finite and > 0")


class Stabilization:
    """Contract (each method is a small object):

    1. ``bias(phi, phidot) -> (r,)``: the desired Phi_ddot added to gamma.
    2. ``project(eom, q, qd) -> (q, qd, projected)``: post-step correction; the default does nothing.
    3. ``settings() -> dict``: the values that identify the method in results and tables.
    """

    name = ""
    projects = False
    compiled_bias = None   # the compiled form of bias (signature study.kernels.signatures.BIAS), per class

    def bias(self, phi: Array, phidot: Array) -> Array:
        return apply_bias(zero_bias, [], phi, phidot)

    def compiled_parameters(self, r: int) -> list[float]:
        """The numbers ``compiled_bias`` reads at cf[offset:], for r constraints."""
        return []

    def project(self, eom: EquationsOfMotion, q: Array, qd: Array) -> tuple[Array, Array, bool]:
        return q, qd, False

    def settings(self) -> dict:
        return {"stabilization": self.name}


@dataclass(frozen=True)
class NoStabilization(Stabilization):
    name: str = "none"
    compiled_bias = staticmethod(zero_bias)


@dataclass(frozen=True)
class Baumgarte(Stabilization):
    """Phi_ddot + 2 d w Phidot + w^2 Phi = 0 (001 eq. 11), 0 < d <= 1, w > 0.

    The classic form Phi_ddot + 2 alpha Phidot + beta^2 Phi = 0 is accepted as
    ``Baumgarte.from_alpha_beta(alpha, beta)`` (alpha = d w, beta = w).
    Defaults d = 1 (critical damping) and w = 10 rad/s are the study's own: a decay time of
    0.1 s, a tenth of the crank period, so the correction is fast but the ODE stays non-stiff.
    """

    d: float = 1.0
    omega: float = 10.0
    name: str = "baumgarte"

    def __post_init__(self) -> None:
        _positive("baumgarte", omega=self.omega, d=self.d)
        if self.d > 1:
            raise ValueError(f"baumgarte: d = {self.d!r} must satisfy 0 < d <= 1 (001 eq. 11)")

    @classmethod
    def from_alpha_beta(cls, alpha: float, beta: float) -> "Baumgarte":
        _positive("baumgarte", alpha=alpha, beta=beta)
        return cls(d=alpha / beta, omega=beta)

    def bias(self, phi, phidot):
        return apply_bias(baumgarte_bias, baumgarte_parameters(self.d, self.omega), phi, phidot)

    compiled_bias = staticmethod(baumgarte_bias)

    def compiled_parameters(self, r):
        return baumgarte_parameters(self.d, self.omega)

    def settings(self):
        return {"stabilization": self.name, "d": self.d, "omega": self.omega}


@dataclass(frozen=True)
class SlidingMode(Stabilization):
    """s = Phidot + Lambda Phi, s_dot = -K s - k sgn(s) (001 eqs. 14-16).

    Lambda, K, k are diagonal, given as scalars (same for every constraint) or one value per
    constraint. ``sgn`` names the approximation in ``SIGN_FUNCTIONS``; ``width`` is its eps (sat,
    sqrt) or 1/c (tanh, arctan). Defaults (study's own): Lambda = K = 10 1/s as Baumgarte's w,
    k = 1e-6 (a switching gain just above the drift rate seen without stabilization) and
    width = 1e-8 (the constraint level the paper reports).
    """

    Lambda: float | tuple = 10.0
    K: float | tuple = 10.0
    k: float | tuple = 1e-6
    sgn: str = "tanh"
    width: float = 1e-8
    name: str = "sliding_mode"

    def __post_init__(self) -> None:
        _positive("sliding_mode", Lambda=self.Lambda, K=self.K, k=self.k, width=self.width)
        if self.sgn not in SIGN_FUNCTIONS:
            raise ValueError(f"sliding_mode: unknown sgn approximation {self.sgn!r}; "
                             f"valid choices: {', '.join(SIGN_FUNCTIONS)}")

    def bias(self, phi, phidot):
        return apply_bias(sliding_mode_bias, self.compiled_parameters(np.size(phi)), phi, phidot)

    compiled_bias = staticmethod(sliding_mode_bias)

    def compiled_parameters(self, r):
        return sliding_mode_parameters(self.Lambda, self.K, self.k, self.sgn, self.width, r)

    def settings(self):
        return {"stabilization": self.name, "Lambda": self.Lambda, "K": self.K, "k": self.k,
                "sgn": self.sgn, "width": self.width}


@dataclass(frozen=True)
class Projection(Stabilization):
    """Post-step projection of q onto Phi = 0 and qd onto Phi_q qd = 0.

    ``weighting``: 'minimum_norm' (W = I) or 'mass' (W = M(q)), the metric of the correction
    dq = -W^-1 Phi_q^T (Phi_q W^-1 Phi_q^T)^-1 Phi, iterated (Gauss-Newton) until max|Phi| <= tol.
    ``tol`` = 1e-12 (study's own): below it a correction is round-off; ``max_iter`` = 10 Newton
    steps are far more than a post-step correction of O(atol) needs (quadratic convergence).
    """

    weighting: str = "minimum_norm"
    tol: float = 1e-12
    max_iter: int = 10
    name: str = "projection"
    projects: bool = True
    compiled_bias = staticmethod(zero_bias)   # b = 0; the projection after each step is study.laws.projection

    def __post_init__(self) -> None:
        if self.weighting not in ("minimum_norm", "mass"):
            raise ValueError(f"projection: weighting {self.weighting!r}; valid choices: minimum_norm, mass")
        _positive("projection", tol=self.tol, max_iter=self.max_iter)
        if isinstance(self.max_iter, bool) or int(self.max_iter) != self.max_iter:
            raise ValueError(f"projection: max_iter = {self.max_iter!r} must be a whole number of iterations")

    def compiled_parameters(self, r):
        """The number the projection reads at the bias parameters (``study.fast.project``): its ``rcond``."""
        return [tolerance("singular_ratio")]

    def project(self, eom, q, qd):
        """The law ``study.laws.projection.project`` (through its source) on copies of q and qd, with the equations'
        Phi, Phi_q and M; RuntimeError if max|Phi| stays above ``tol`` for ``max_iter`` corrections."""
        mass = self.weighting == "mass"

        def kinematics(q, p, phi, J, M):
            phi[:] = eom.phi(q)
            J[:] = eom.phi_q(q)
            if mass:
                M[:] = eom.mass(q)

        q, qd = np.array(q, dtype=float), np.array(qd, dtype=float)
        changed, status = projection.project.py_func(kinematics, q, qd, np.zeros(0), eom.n_constraints, self.tol,
                                                     mass, self.max_iter, tolerance("singular_ratio"))
        if status == projection.NOT_CONVERGED:
            raise RuntimeError(f"projection did not reach max|Phi| <= {self.tol:g} in {self.max_iter} iterations "
                               f"(max|Phi| = {np.max(np.abs(eom.phi(q))):.3g}); the step left the manifold too far")
        return q, qd, changed

    def settings(self):
        return {"stabilization": self.name, "weighting": self.weighting, "tol": self.tol}


STABILIZATIONS: dict[str, type[Stabilization]] = {
    "none": NoStabilization,
    "baumgarte": Baumgarte,
    "sliding_mode": SlidingMode,
    "projection": Projection,
}


def make_stabilization(name: str | Stabilization, **options) -> Stabilization:
    """Build a stabilization method by name (Baumgarte also accepts ``alpha``/``beta``), or take a
    :class:`Stabilization` object as it is, the way scipy's ``solve_ivp`` takes an ``OdeSolver`` class:
    its options are then its own fields, and further options are an error."""
    if isinstance(name, Stabilization):
        if options:
            raise ValueError(f"method is a {type(name).__name__} object: its options are its fields, so "
                             f"{sorted(options)} cannot be given as well")
        return name
    if not isinstance(name, str) or name not in STABILIZATIONS:
        raise ValueError(f"method = {name!r} is not known; valid choices: {', '.join(STABILIZATIONS)}")
    options = check_options(name, options)
    if name == "baumgarte" and ("alpha" in options or "beta" in options):
        if set(options) != {"alpha", "beta"}:
            raise ValueError(f"baumgarte: give either d and omega or alpha and beta, got {sorted(options)}")
        return Baumgarte.from_alpha_beta(options["alpha"], options["beta"])
    return STABILIZATIONS[name](**options)


def method_options(name: str) -> dict[str, str]:
    """The options of the method ``name`` and their declared types ('float', 'int', 'str', 'float | tuple')."""
    fields = {f.name: str(f.type) for f in dataclasses.fields(STABILIZATIONS[name]) if f.name not in ("name", "projects")}
    return {**fields, "alpha": "float", "beta": "float"} if name == "baumgarte" else fields


def check_options(name: str, options: dict, source: str = "") -> dict:
    """``options`` of the method ``name``, each of its declared type (an integer option takes no fraction, a
    number no text or boolean); a ValueError names an unknown option, or a value and its type. ``source``
    prefixes the names (e.g. '--option ')."""
    declared = method_options(name)
    unknown = sorted(set(options) - set(declared))
    if unknown:
        valid = ", ".join(declared) if declared else "none (it takes no options)"
        raise ValueError(f"{', '.join(source + k for k in unknown)}: not an option of method {name!r}; valid "
                         f"options: {valid}")
    checked = {}
    for key, value in options.items():
        kind, where = declared[key], f"{name}: {source}{key}"
        if kind == "int":
            checked[key] = arguments.number(where, value, positive=False, whole=True)
        elif kind == "float":
            checked[key] = arguments.number(where, value, positive=False)
        elif kind == "str":
            checked[key] = arguments.choice(where, value, SIGN_FUNCTIONS) if key == "sgn" else arguments.text(where, value)
        elif isinstance(value, (list, tuple, np.ndarray)):   # a value per constraint
            checked[key] = tuple(arguments.number(f"{where}[{i}]", v, positive=False) for i, v in enumerate(value))
        else:
            checked[key] = arguments.number(where, value, positive=False)
    return checked
