"""The compiled loop's post-step projection: the law ``study.laws.projection.project`` on y = [q, qd, ...] with the
numbers the run's options hold (tolerance, metric and iteration bound in the header, ``rcond`` at the stabilization's
parameters: ``study.solver.stabilization.Projection.compiled_parameters``)."""

from __future__ import annotations

from study.fast.dynamics import CF_PROJ_TOL, CI_BIAS, CI_PROJ_MASS, CI_PROJ_MAXITER
from study.kernels.cache import internal
from study.laws.projection import OK, project as projection


@internal()
def project(kinematics, y, ws, m, r):
    """Project y = [q, qd, ...] in place with the parameters and options in the workspace ``ws``
    (study.fast.dynamics.workspace); returns (changed, status), status 0 (OK) or the law's failure code.
    ``kinematics`` None: the loop compiled for runs without projection (study.fast.loop.segment_signature)."""
    if kinematics is None:
        return False, OK
    ci, cf = ws.ci, ws.cf
    q, qd = y[:m].copy(), y[m:2 * m].copy()
    changed, status = projection(kinematics, q, qd, ws.p, r, cf[CF_PROJ_TOL], ci[CI_PROJ_MASS] == 1,
                                 ci[CI_PROJ_MAXITER], cf[ci[CI_BIAS]])
    if changed:
        for i in range(m):
            y[i] = q[i]
            y[m + i] = qd[i]
    return changed, status
