"""The spatial study's cases by name (``reference/cases/spatial.toml``): a case's role in its mechanism's groups and a
readable run setting, for the tables of :mod:`study.studies.spatial` and :mod:`study.studies.spatial_friction`."""

from __future__ import annotations

from study.pipeline import Case


def role(case: Case) -> str:
    """The group's role, the part after ':' (reference, inhouse, methods, benchmark, exudyn, friction_exact, ...)."""
    return case.group.partition(":")[2]


def setting(case: Case) -> str:
    """A readable run setting: 'DOP853 rtol=1e-08 projection' or 'index3 h=0.0001'."""
    o = case.kwargs
    if case.engine == "exudyn":
        return f"{o.get('solver', 'index3')} h={o['h']:g}"
    return f"{o['integrator']} rtol={o['rtol']:g} {o.get('method', 'none')}"
