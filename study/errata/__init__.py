"""Errata: the papers' printed formulas checked against the equations derived from the mechanisms.

``reference/printed_formulas.toml`` holds every checked formula of papers 000 (slider-crank) and
001 (quick-return) as printed, in sympy syntax. Each one names the derived quantity it claims to be
(its ``target``), which is built from the mechanism's joint-level description through
:func:`study.model.derive.derive`, i.e.

    M qdd + C qd + dV/dq + Phi_q^T lambda = Q_applied.

One module per step:

* :mod:`.printed`: the printed formulas and how each paper's symbols map onto a mechanism;
* :mod:`.derived`: the derived side (each target a small function of the derived equations);
* :mod:`.samples`: random states on the constraint manifold, for the numeric checks;
* :mod:`.algebra`: exact zero tests and display simplification;
* :mod:`.latex`: the typeset forms, with the derived terms the printed form lacks marked;
* :mod:`.judge`: the verdict of one formula;
* :mod:`.table`: the table of every formula, written as ``errata.csv`` and ``errata.md``.

Verdicts
--------
``exact``
    symbolically identical after simplification (an equation may differ by a constant factor).
``equivalent on the constraint manifold``
    not identical, but the same wherever it matters: equal at random points with Phi = 0,
    Phi_q qd = 0 (and Phi_q qdd = gamma); for generalized forces it is enough that the difference
    lies in the range of Phi_q^T (it moves load into the constraint reactions: the motion is
    unchanged, only the multipliers change; the note gives the shift mu).
``wrong``
    differs on the manifold; ``derived`` holds the corrected form.

Printed numbers (initial conditions) are ``exact`` when Newton-Raphson from the printed independent
values reproduces every printed number to its printed digits, else ``wrong``.

The numeric checks use parameter values spread randomly around the seed set (so that coincidences
of the seed such as a1 = 0 or c2 = l2/2 cannot hide a misprint) and configurations along a whole
turn of the crank, reached by continuation with :func:`study.model.initial_state.consistent_initial_conditions`.
"""

from study.errata.judge import EQUIVALENT, EXACT, VERDICTS, WRONG, check_formula
from study.errata.latex import DIFFERENCE_COLOR
from study.errata.printed import FORMULAS_PATH, load_printed
from study.errata.table import COLUMNS, errata_table, main, write_errata

__all__ = ["COLUMNS", "DIFFERENCE_COLOR", "EQUIVALENT", "EXACT", "FORMULAS_PATH", "VERDICTS", "WRONG",
           "check_formula", "errata_table", "load_printed", "main", "write_errata"]
