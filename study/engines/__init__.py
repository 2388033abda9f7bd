"""One engine interface: a run specification in, a :class:`study.results.SimulationResult` out.

``run(mechanism, spec, t_end, q0=None, qd0=None, progress=None)`` (:mod:`study.engines.runner`) runs any engine:

- :class:`InHouse` (:mod:`study.engines.inhouse`): ``method`` (a stabilization object of
  ``study.solver.stabilization``: ``NoStabilization()``, ``Baumgarte(d, omega)``, ``SlidingMode(...)``,
  ``Projection(...)``), ``integrator`` (:mod:`study.engines.integrators`: ``RK45``, ``RK23``, ``DOP853``, ``Radau``,
  ``LSODA`` with ``rtol``, ``atol``, ``min_step``; ``RK4``, ``ALI3P`` with ``h``), ``friction``
  (:mod:`study.engines.friction`: ``Default``, ``NoFriction``, ``Exact``, ``Regularized(eps, sgn)``, ``Sign(eps)``),
  ``backend`` ('reference' or 'compiled') and the run's bounds; run by :mod:`study.engines.inhouse_run`.
- :class:`Exudyn` (:mod:`study.engines.exudyn`): ``solver``, ``h`` and the options of ``study.exudyn_models.run``.

``study.simulate`` and ``study.exudyn_run`` (:func:`study.engines.runner.exudyn_run`) are the same runs by keywords:
each makes the specification of its arguments and calls ``run``.

Each specification checks itself when made and refuses, by name, an option it does not take or a combination it
cannot run. ``to_dict()`` writes it as a plain dict (the keyword arguments of ``study.simulate`` or of
``study.exudyn_models.run``, plus ``engine``: a case list's options), ``spec_from_dict`` reads it back.
"""

from study.engines.exudyn import Exudyn
from study.engines.friction import Default, Exact, Friction, NoFriction, Regularized, Sign
from study.engines.inhouse import InHouse
from study.engines.integrators import ALI3P, DOP853, LSODA, RK4, RK23, RK45, Integrator, Radau
from study.engines.runner import exudyn_run, run, spec_from_dict
from study.solver.stabilization import Baumgarte, NoStabilization, Projection, SlidingMode

__all__ = ["ALI3P", "DOP853", "LSODA", "RK4", "RK23", "RK45", "Baumgarte", "Default", "Exact", "Exudyn", "Friction",
           "InHouse", "Integrator", "NoFriction", "NoStabilization", "Projection", "Radau", "Regularized", "Sign",
           "SlidingMode", "exudyn_run", "run", "spec_from_dict"]
