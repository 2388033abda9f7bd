"""The spatial study's cases by name (``reference/cases/spatial.toml``): a case's role in its mechanism's groups and a
readable run setting, for the tables of :mod:`study.studies.spatial` and :mod:`study.studies.spatial_friction`."""

from __future__ import annotations

from study.pipeline import Case

#: the roles of a mechanism's runs over its benchmark's horizon, judged by the energy rule of the in-house one
#: ('benchmark'): 'exudyn_benchmark' is Exudyn's run, held to the same bound (the in-house run's rtol)
BENCHMARK_ROLES = ("benchmark", "exudyn_benchmark")


def role(case: Case) -> str:
    """The group's role, the part after ':' (reference, inhouse, methods, benchmark, exudyn, friction_exact, ...)."""
    return case.group.partition(":")[2]


def setting(case: Case) -> str:
    """A readable run setting: 'DOP853 rtol=1e-08 projection', 'index3 h=0.0001' or, where the case names Exudyn's
    configuration, 'index3 h=6.25e-05 tuned'."""
    o = case.kwargs
    if case.engine == "exudyn":
        return f"{o.get('solver', 'index3')} h={o['h']:g}" + (f" {o['configuration']}" if "configuration" in o else "")
    return f"{o['integrator']} rtol={o['rtol']:g} {o.get('method', 'none')}"
