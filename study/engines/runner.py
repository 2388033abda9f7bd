"""``run(mechanism, spec, t_end)``: one run of any engine, a :class:`study.results.SimulationResult` out; a
specification from its plain dict (:func:`spec_from_dict`); ``study.exudyn_run``, the Exudyn run by keywords."""

from __future__ import annotations

import functools
from typing import Any, Callable, Mapping

from threadpoolctl import threadpool_limits

from study.engines.exudyn import Exudyn
from study.engines.inhouse import InHouse
from study.model.eom import EquationsOfMotion
from study.results import SimulationResult
from study.solver.friction import DEFAULT_EPS


def _planar_model(mechanism, t_end: float, **options) -> SimulationResult:
    from study.exudyn_models import run as translate

    return translate(mechanism, t_end, **options)


def _spatial_model(mechanism, t_end: float, **options) -> SimulationResult:
    from study.exudyn_models.spatial import run as translate

    return translate(mechanism, t_end, **options)


#: a mechanism's kind (:attr:`study.Mechanism.kind`; a study mechanism's ParameterSet is planar) -> its Exudyn
#: translator's ``run(mechanism, t_end, **Exudyn.options())`` (Exudyn is imported when a run needs it)
EXUDYN_TRANSLATORS = {"planar": _planar_model, "spatial": _spatial_model}


def resolve(eom_or_mechanism, variant: str | None = None):
    """An EquationsOfMotion, a Mechanism (a description with its parameter set) or a built-in mechanism name (with
    its variant) -> (eom, mechanism or None)."""
    from study.mechanisms import named_mechanism
    from study.model import Mechanism

    if isinstance(eom_or_mechanism, (EquationsOfMotion, Mechanism)) and variant is not None:
        raise ValueError(f"variant= applies to built-in mechanism names, not to a {type(eom_or_mechanism).__name__} "
                         f"(its parameter set is its own)")
    if isinstance(eom_or_mechanism, EquationsOfMotion):
        return eom_or_mechanism, None
    if isinstance(eom_or_mechanism, Mechanism):
        return eom_or_mechanism.equations(), eom_or_mechanism
    if isinstance(eom_or_mechanism, str):
        # found as the pipeline finds it (planar, spatial, a file), but built afresh: a run reads the cache folder of
        # the moment (STUDY_CACHE_DIR) for its generated equations, never a mechanism memoized by an earlier call
        m = named_mechanism.__wrapped__(eom_or_mechanism, variant or "seed")
        return m.equations(), m
    raise ValueError(f"eom_or_mechanism = {eom_or_mechanism!r} must be an EquationsOfMotion, a Mechanism or a "
                     f"mechanism name")


def one_blas_thread(fn):
    """Run ``fn`` with one BLAS thread. The study's matrices are small (Phi_q of the 40-window four-bar is 80 x 81):
    from about that size on OpenBLAS splits a product over threads, which on a busy host wait for a core (and the
    waiting counts as process time), and whose order of summation depends on the thread count. The pipeline's
    workers run with one thread for the same reasons."""
    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        with threadpool_limits(limits=1, user_api="blas"):
            return fn(*args, **kwargs)
    return wrapper


@one_blas_thread
def run(mechanism, spec, t_end: float = 1.0, *, q0=None, qd0=None,
        progress: Callable[[float], None] | None = None) -> SimulationResult:
    """Run ``mechanism`` (a :class:`study.Mechanism` or a :class:`study.spatial.SpatialMechanism` (Exudyn's model of
    its kind, EXUDYN_TRANSLATORS), a study mechanism's name with its seed parameters, for Exudyn also
    a study mechanism's ParameterSet, for the in-house engine a user's EquationsOfMotion with ``q0`` and ``qd0``) over [0, ``t_end``] as ``spec`` says: an
    :class:`study.engines.InHouse` or an :class:`study.engines.Exudyn` run specification.

    ``q0``, ``qd0``: the initial state (in-house; default the mechanism's consistent state); ``progress``: called with
    the time reached (in-house, on scipy's loop). What an engine does not take is refused by name before any work."""
    if isinstance(spec, InHouse):
        from study.engines.inhouse_run import run_inhouse

        eom, mech = resolve(mechanism)
        return run_inhouse(eom, mech, spec, t_end, q0, qd0, progress)
    if not isinstance(spec, Exudyn):
        raise ValueError(f"spec = {spec!r} must be a run specification: study.engines.InHouse(...) or "
                         f"study.engines.Exudyn(...)")
    for key, value, why in (("q0", q0, "it starts from the mechanism's consistent initial state"),
                            ("qd0", qd0, "it starts from the mechanism's consistent initial state"),
                            ("progress", progress, "Exudyn's loop does not call back")):
        if value is not None:
            raise ValueError(f"{key} = {value!r} does not apply to an Exudyn run: {why}")
    if isinstance(mechanism, EquationsOfMotion):
        raise ValueError(f"mechanism = {mechanism.name!r} is an EquationsOfMotion: Exudyn builds its model from a "
                         f"description; give a Mechanism")
    spec.checked(t_end)
    target = resolve(mechanism)[1] if isinstance(mechanism, str) else mechanism   # a Mechanism or a ParameterSet
    return EXUDYN_TRANSLATORS[getattr(target, "kind", "planar")](target, t_end, **spec.options())


def spec_from_dict(d: Mapping[str, Any]):
    """The run specification of a plain dict (``to_dict``'s form): ``engine`` 'inhouse' (the default) or 'exudyn'."""
    engines = {InHouse.engine: InHouse, Exudyn.engine: Exudyn}
    engine = d.get("engine", InHouse.engine)
    if engine not in engines:
        raise ValueError(f"engine = {engine!r} is not known; valid choices: {', '.join(engines)}")
    return engines[engine].from_dict(dict(d))


def exudyn_run(mechanism, t_end: float, h: float, solver: str = "index3", output_step: float | None = None,
               friction: str = "regularized", eps: float = DEFAULT_EPS, configuration: str = "python",
               ignore_singular: bool = False, linear_solver: str = "dense", newton_tolerance: float | None = None):
    """``study.exudyn_run``: :func:`study.engines.run` of ``mechanism`` (a :class:`study.Mechanism` or a study
    mechanism's ParameterSet) with the :class:`Exudyn` specification of these arguments (see
    :func:`study.exudyn_models.run` for each; ``newton_tolerance`` None: Exudyn's settings' NEWTON_TOLERANCE)."""
    return run(mechanism, Exudyn(h=h, solver=solver, output_step=output_step, friction=friction, eps=eps,
                                 configuration=configuration, ignore_singular=ignore_singular,
                                 linear_solver=linear_solver, newton_tolerance=newton_tolerance), t_end)
