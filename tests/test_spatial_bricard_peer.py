"""Exudyn's Bricard test model (TestModels/bricardMechanism.py) as a peer model (study.spatial.bricard_peer,
study.studies.peer_models): the description against the file's own numbers, transcribed below by hand with their
lines (jgerstmayr/EXUDYN commit e44aca1b4fe3e5f4d820ff407fb3fd30b6581c1c); the counts the published value adds; the
in-house run against the published value by the agreement rule; the summary's rows and its report subsection."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from exudyn.rigidBodyUtilities import InertiaCuboid

from study.mechanisms import named_mechanism
from study.pipeline import CASES_DIR, load_case_list, run_case
from study.pipeline.tables import record_written
from study.reference_data import tolerance, values
from study.reference_solutions import richardson_second_order
from study.spatial.elements import GROUND
from study.studies.peer_models import BRICARD, BRICARD_COLUMNS, BRICARD_PUBLISHED, bricard, counts

L, R = 1.0, 0.1                        # lines 39-40: L = 1, r = 0.1
DENSITY = 100.0                        # line 42: InertiaCuboid(density=100, sideLengths=[L, r, r])
COM = np.array([0.5 * L, 0.0, 0.0])    # line 43: inertia.Translated([L*0.5, 0, 0])
LIST_P = L * np.array([[0, 0, 0], [1, 0, 0], [1, -1, 0], [1, -1, 1], [0, -1, 1], [0, 0, 1]])   # lines 51-59
ROT_LIST = np.array([np.eye(3),                                 # lines 60-67: np.eye(3),
                     [[0, 1, 0], [-1, 0, 0], [0, 0, 1]],        # RotationMatrixZ(-0.5*pi),
                     [[0, 0, -1], [0, 1, 0], [1, 0, 0]],        # RotationMatrixY(-0.5*pi),
                     [[-1, 0, 0], [0, -1, 0], [0, 0, 1]],       # RotationMatrixZ(pi),
                     [[0, -1, 0], [1, 0, 0], [0, 0, 1]]])       # RotationMatrixZ(0.5*pi)
ROT_AXES = np.array([[0, 1, 0], [0, 0, 1], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 0]])   # line 69
GRAVITY = [0.0, -9.81, 0.0]            # line 85
T_END, STEPS = 1.0, 1000               # line 32 endTime = 1, line 122 numberOfSteps = 1000
EXACT = tolerance("round_off")         # the same numbers computed two ways


def rotation(p) -> np.ndarray:
    """A(p) of Euler parameters (e0, e), written here: (e0^2 - e.e) I + 2 e e^T + 2 e0 skew(e)."""
    e0, e = p[0], np.asarray(p[1:], dtype=float)
    skew = np.array([[0, -e[2], e[1]], [e[2], 0, -e[0]], [-e[1], e[0], 0]])
    return (e0 ** 2 - e @ e) * np.eye(3) + 2 * np.outer(e, e) + 2 * e0 * skew


def test_the_description_is_the_test_files_model():
    """Each rod k: the cuboid's mass and inertia (Exudyn's own InertiaCuboid of the file's arguments) in the body
    frame rotList[k]; its reference point (the node) at listP[k], its centre of mass at listP[k] + rotList[k] COM;
    joint k at listP[k] about listRotAxes[k] (global); gravity; the case list's horizon and the published step."""
    mech = named_mechanism(BRICARD)
    d, start = mech.description, mech.start
    cuboid = InertiaCuboid(density=DENSITY, sideLengths=[L, R, R])
    assert list(d.bodies) == [f"rod{k + 1}" for k in range(5)]
    place = {}
    for k, (name, body) in enumerate(d.bodies.items()):
        frame, centre = rotation(start["orientations"][name]), np.array(start["positions"][name])
        np.testing.assert_allclose(frame, ROT_LIST[k], rtol=0, atol=EXACT)
        np.testing.assert_allclose(centre, LIST_P[k] + ROT_LIST[k] @ COM, rtol=0, atol=EXACT)
        assert body.mass == pytest.approx(cuboid.Mass(), rel=EXACT)
        np.testing.assert_allclose(body.inertia, cuboid.InertiaCOM(), rtol=0, atol=EXACT * cuboid.InertiaCOM().max())
        np.testing.assert_allclose(centre + frame @ body.points["tail"], LIST_P[k], rtol=0, atol=EXACT)
        np.testing.assert_allclose(centre + frame @ body.points["head"], LIST_P[k + 1], rtol=0, atol=EXACT)
        place[name] = (centre, frame, body)
    assert len(d.joints) == 6
    for k, j in enumerate(d.joints):
        assert type(j).__name__ == "Revolute"
        for body, point, axis in ((j.body_a, j.a, j.axis_a), (j.body_b, j.b, j.axis_b)):
            if body == GROUND:
                position, direction = np.array(point), np.array(axis)
            else:
                centre, frame, b = place[body]
                position, direction = centre + frame @ b.points[point], frame @ b.axes[axis]
            np.testing.assert_allclose(position, LIST_P[k], rtol=0, atol=EXACT)
            np.testing.assert_allclose(direction, ROT_AXES[k], rtol=0, atol=EXACT)
    np.testing.assert_array_equal(d.gravity_vector, GRAVITY)
    assert d.redundant == 1
    assert {c.t_end for c in bricard_cases()} == {T_END}
    assert tolerance(f"{BRICARD_PUBLISHED}_step", table="benchmarks") == T_END / STEPS


def bricard_cases():
    return [c for c in load_case_list(CASES_DIR / "peer_models.toml").cases if c.mechanism == BRICARD]


@pytest.fixture(scope="module")
def runs():
    """The case list's Bricard cases, run here: {case: result}."""
    return {case: run_case(case) for case in bricard_cases()}


def ode2_norm(result) -> tuple[np.ndarray, float]:
    """Exudyn's ODE2 coordinates at the end (each rod's node, at body point -COM from its centre, displaced from its
    start, and its Euler parameters' change), computed here from the result's r and p, and their norm."""
    q0, q = result.q[0], result.q[-1]
    parts = []
    for k in range(5):
        r0, p0, r, p = q0[7 * k:7 * k + 3], q0[7 * k + 3:7 * k + 7], q[7 * k:7 * k + 3], q[7 * k + 3:7 * k + 7]
        parts += [r - rotation(p) @ COM - (r0 - rotation(p0) @ COM), p - p0]
    coordinates = np.concatenate(parts)
    return coordinates, float(np.linalg.norm(coordinates))


def by_source(runs) -> dict:
    h = tolerance(f"{BRICARD_PUBLISHED}_step", table="benchmarks")
    pick = {"inhouse": lambda c: c.engine == "inhouse", "coarse": lambda c: c.kwargs.get("h") == h,
            "fine": lambda c: c.kwargs.get("h") == h / 2}
    return {key: next(r for c, r in runs.items() if test(c)) for key, test in pick.items()}


def test_the_counts_are_those_exudyn_logs():
    """One degree of freedom, one redundant row and a lowest eigenvalue of 0 at the start, as Exudyn's test-suite log
    prints them for the file's model."""
    assert counts(BRICARD) == tuple(values(f"{BRICARD_PUBLISHED}_counts", table="benchmarks"))


def test_the_in_house_run_reproduces_the_published_value(runs):
    """The in-house value lies within exudyn_bricard_agreement_factor times the published run's discretization error
    (Richardson's estimate from the Exudyn runs at the published h and h/2) of the published value, and so does the
    Exudyn run of the description at the published step."""
    published = tolerance(BRICARD_PUBLISHED, table="benchmarks")
    counted = sum(values(f"{BRICARD_PUBLISHED}_counts", table="benchmarks"))
    found = {key: ode2_norm(r) for key, r in by_source(runs).items()}
    extrapolated = float(np.linalg.norm(richardson_second_order(found["coarse"][0], found["fine"][0])[0]))
    bound = tolerance("exudyn_bricard_agreement_factor", table="benchmarks") * abs(extrapolated - found["coarse"][1])
    assert abs(found["inhouse"][1] + counted - published) <= bound
    assert abs(found["coarse"][1] + counted - published) <= bound


def test_the_summary_rows(runs, tmp_path):
    """Published, in-house, Exudyn at h and h/2, Richardson's extrapolation: each row's norm as computed here, its
    counts, its published quantity and difference; the verdict and the timing rows; the report's subsection."""
    published = tolerance(BRICARD_PUBLISHED, table="benchmarks")
    logged = list(values(f"{BRICARD_PUBLISHED}_counts", table="benchmarks"))
    tables = bricard(list(runs), runs.__getitem__)
    table = tables["exudyn_bricard_test_model"]
    assert list(table.columns) == BRICARD_COLUMNS
    assert [s.split(" (")[0].split(",")[0] for s in table["source"]] == [
        "published", "in-house reference", "Exudyn from the description", "Exudyn from the description",
        "Richardson extrapolation of the two Exudyn runs"]
    found = {key: ode2_norm(r) for key, r in by_source(runs).items()}
    extrapolated = richardson_second_order(found["coarse"][0], found["fine"][0])[0]
    norms = [published - sum(logged), *(found[k][1] for k in ("inhouse", "coarse", "fine")),
             float(np.linalg.norm(extrapolated))]
    np.testing.assert_allclose(table["ode2_norm"], norms, rtol=EXACT, atol=0)
    for column, value in zip(["dof", "redundant_constraints", "lowest_eigenvalue"], logged):
        assert list(table[column]) == [value] * 5
    np.testing.assert_allclose(table["test_value"], np.array(norms) + sum(logged), rtol=EXACT, atol=0)
    np.testing.assert_allclose(table["minus_published"], np.array(norms) + sum(logged) - published, rtol=0,
                               atol=EXACT * published)
    verdict = tables["exudyn_bricard_test_model_verdict"].iloc[0]
    error, factor = abs(norms[4] - norms[2]), tolerance("exudyn_bricard_agreement_factor", table="benchmarks")
    assert verdict["published_run_error_estimate"] == pytest.approx(error, rel=0, abs=EXACT * published)
    assert verdict["agrees"] and verdict["bound"] == pytest.approx(factor * error, rel=0, abs=EXACT * published)
    assert list(tables["exudyn_bricard_test_model_timing"]["source"]) == list(table["source"][1:4])
    text = "\n".join(report_subsection(tables, tmp_path))
    assert f"**within {factor:g} times that error**" in text and text.count("\n| ") == 6


def report_subsection(tables: dict[str, pd.DataFrame], folder) -> list[str]:
    """The report's Bricard subsection from the tables, saved as the one table writer records them."""
    from study.report.context import ReportContext
    from study.report.sections.beyond_papers import _bricard_peer

    (folder / "tables").mkdir()
    for name, frame in tables.items():
        frame.to_csv(folder / "tables" / f"{name}.csv", index=False)
        record_written(folder / "tables" / f"{name}.csv", "written by the test")
    return _bricard_peer(ReportContext(reports_dir=folder, store=None, case_lists={}))


@pytest.mark.slow
def test_the_same_motion_as_a04_in_other_body_frames(runs):
    """The file's body frames turn every rod, A04's (study.spatial.bricard) keep them parallel to the global frame:
    the same mechanism, so the four joints between rods move alike, both runs within the global-error rule."""
    from study.simulate import simulate
    from study.spatial.bricard import bricard_mechanism

    case, peer = next((c, r) for c, r in runs.items() if c.engine == "inhouse")
    a04 = bricard_mechanism()
    eom, state, o = a04.equations(), a04.initial_state(), case.kwargs
    ours = simulate(eom, state.q, state.qd, t_end=case.t_end, integrator=o["integrator"], rtol=o["rtol"],
                    atol=o["atol"], output_step=o["output_step"], acceleration_solver=o["acceleration_solver"])
    peer_eom = named_mechanism(BRICARD).equations()

    def heads(e, q):
        return np.array([[np.ravel(e.points[f"rod{k}.head"](x)) for k in range(1, 5)] for x in q])

    assert ours.t.shape == peer.t.shape
    bound = 2 * tolerance("adaptive_global_error_factor") * o["rtol"] * L
    assert np.abs(heads(peer_eom, peer.q) - heads(eom, ours.q)).max() <= bound
