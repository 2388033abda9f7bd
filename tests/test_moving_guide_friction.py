"""Coulomb friction on a moving guide: a slider on a turning arm.

The mechanism: an arm turns about a ground pivot O at its centre of mass (angle ph, centroidal inertia Ja, a
constant drive torque tau); its guide line runs parallel to the arm's axis at the offset e (the line through the arm
point (0, e) along the arm's x axis). A slider (mass ms, inertia Js, turning with the arm) rides on that line, its
centre of mass at the distance rho along it: r_S = rho e_r + e e_ph, e_r = (cos ph, sin ph), e_ph = (-sin ph, cos ph).
Vertical plane, gravity -y. In the study's description the slider is a free body (x, y, angle ph) held by a prismatic
cut joint with friction whose guide is the arm; q = (ph, x, y), one gap row.

Independent reference, derived by hand here in the minimal coordinates (ph, rho), not from the description:

    T = (Ja + Js) ph'^2 / 2 + ms ((rho' - e ph')^2 + rho^2 ph'^2) / 2,     V = ms g (rho sin ph + e cos ph)

    (Ja + Js + ms (e^2 + rho^2)) ph'' - ms e rho'' + 2 ms rho rho' ph' + ms g (rho cos ph - e sin ph) = tau
    ms (rho'' - e ph'') - ms rho ph'^2 + ms g sin ph = F

F is the friction force on the slider along e_r. The slider's velocity relative to the arm's point under it is rho' e_r
(v_S = (rho' - e ph') e_r + rho ph' e_ph, the arm's point moves with ph' k x r_S), so F's virtual work on the pair
(F e_r on the slider, -F e_r on the arm at the same point) is F d rho: F enters the rho equation only. Its size comes
from the normal force N of the arm on the slider along e_ph, from the slider's transverse equation of motion (the
e_ph component of ms a_S = N e_ph + F e_r - ms g e_y; the arm's holding couple turns the slider, it pushes nothing):

    N = ms (rho ph'' + 2 rho' ph' - e ph'^2 + g cos ph)

Regularized law F = -mu_k |N| tanh(rho' / eps); exact law: slipping, F = -mu_k |N| sgn(rho'); stuck (rho'' = 0) while
the needed force F_req = -ms e ph'' - ms rho ph'^2 + ms g sin ph stays within mu_s |N|. With e != 0 the friction
couples to ph'' through the mass matrix, so N and F are solved together (linear in F for a given sign of N).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import study
from study.compare import observed_orders
from study.model.coordinates import lower
from study.model.joints import DescriptionError
from study.reference_data import tolerance

NAMES = ("ma", "Ja", "ms", "Js", "e", "mus", "muk", "tau", "g")
RTOL = 1e-10
EPS = tolerance("friction_eps", table="cross_validation")
OUTPUT_STEP = 0.01

# sliding throughout (outward, pushed by the arm's spin): the regularized law at |rho'| >> eps, and Exudyn
SLIDING = dict(values=dict(ma=2.0, Ja=0.4, ms=1.0, Js=0.02, e=0.08, mus=0.3, muk=0.3, tau=6.0, g=9.81),
               start=(0.2, 0.4, 6.0, 0.5))          # ph, rho, ph', rho'
# slides, sticks, and breaks loose again as the arm spins up (exact law)
STICKING = dict(values=dict(ma=2.0, Ja=0.4, ms=1.0, Js=0.02, e=0.08, mus=0.5, muk=0.4, tau=8.0, g=9.81),
                start=(0.0, 0.5, 0.0, 0.3))


# --- the study's description ------------------------------------------------------------------
def describe(ps: study.ParameterSet, travel: bool = False, slider_ground: bool = False) -> study.Description:
    d = study.Description("arm_slider_friction", ["ph", "x", "y"], {k: getattr(ps.values, k) for k in NAMES})
    p = d.p
    ph, x, y = d.q
    d.ground("O", 0, 0)
    d.body("arm", p.ma, p.Ja, {"pin": (0, 0), "line": (0, p.e)}, angle=ph)
    d.body("slider", p.ms, p.Js, {"c": (0, 0)}, angle=ph, position=(x, y))
    d.revolute("pin", (study.GROUND, "O"), ("arm", "pin"))
    slider = (study.GROUND, "O") if slider_ground else ("slider", "c")
    d.prismatic("slide", slider=slider, guide=("arm", "line"), axis=(1, 0), normal=(0, 1),
                friction=study.Friction(p.mus, p.muk), travel=x if travel else None)
    d.torque("drive", "arm", p.tau)
    d.gravity(p.g)
    return d


def full_state(values, start):
    """q = (ph, x, y), qd from the minimal (ph, rho, ph', rho'): r_S = rho e_r + e e_ph."""
    ph, rho, w, v = start
    e = values["e"]
    er, eph = np.array([math.cos(ph), math.sin(ph)]), np.array([-math.sin(ph), math.cos(ph)])
    r = rho * er + e * eph
    vs = (v - e * w) * er + rho * w * eph
    return np.array([ph, *r]), np.array([w, *vs])


def parameters(tmp_path, case) -> study.ParameterSet:
    q, qd = full_state(case["values"], case["start"])
    lines = ['[meta]\nmechanism = "arm_slider_friction"\npaper = "none: a test mechanism"\ndescription = "test"\n']
    for k, v in case["values"].items():
        lines.append(f'[parameters.{k}]\nvalue = {v!r}\nunit = "-"\nsource = "test"\nrule = "positive"\ndoc = "{k}"\n')
    lines.append(f'[initial_conditions.printed]\nq = {q.tolist()}\nqd = {qd.tolist()}\nsource = "test"\n')
    lines.append(f"[initial_conditions.consistent]\nindependent = [0, 1]\nq_independent = {q[:2].tolist()}\n"
                 f'qd_independent = {qd[:2].tolist()}\nbranch = "none"\nsource = "test"\n')
    lines.append('[variants.seed]\nnote = "test"\n')
    (tmp_path / "arm_slider_friction.toml").write_text("\n".join(lines))
    return study.load_parameters("arm_slider_friction", reference_dir=tmp_path)


def mechanism(tmp_path, case) -> study.Mechanism:
    ps = parameters(tmp_path, case)
    return study.Mechanism(describe(ps), ps)


def minimal(r):
    """(ph, rho, ph', rho') of a study result (q = ph, x, y)."""
    ph, x, y = r.q.T
    w, vx, vy = r.qd.T
    c, s = np.cos(ph), np.sin(ph)
    return np.column_stack([ph, x * c + y * s, w, vx * c + vy * s + w * (y * c - x * s)])


def balance_residual(r):
    """E(t) - E(0) - (work of the drive) - (work of the friction pair, f v_t with v_t relative to the arm)."""
    e = r.energies
    change = e["kinetic"] + e["potential"] - e["kinetic"][0] - e["potential"][0]
    return change - (e["work_drive"] - e["work_drive"][0]) - (e["work_friction_slide"] - e["work_friction_slide"][0])


# --- the hand model -----------------------------------------------------------------------------
class Hand:
    """The minimal-coordinate equations of the module docstring; y = (ph, rho, ph', rho')."""

    def __init__(self, values):
        self.v = values

    def _parts(self, y):
        v = self.v
        ph, rho, w, rd = y
        ms, e, g = v["ms"], v["e"], v["g"]
        m00, m01, m11 = v["Ja"] + v["Js"] + ms * (e * e + rho * rho), -ms * e, ms
        b0 = v["tau"] - 2 * ms * rho * rd * w - ms * g * (rho * math.cos(ph) - e * math.sin(ph))
        b1 = ms * rho * w * w - ms * g * math.sin(ph)
        return (m00, m01, m11), (b0, b1)

    def sliding(self, y, s):
        """(ph'', rho'', N, F) with F = -mu_k |N| s: N = n0 + n1 F, solved per sign of N (the consistent one)."""
        (m00, m01, m11), (b0, b1) = self._parts(y)
        ph, rho, w, rd = y
        ms, e, g, mu = self.v["ms"], self.v["e"], self.v["g"], self.v["muk"]
        det = m00 * m11 - m01 * m01
        a0, a1 = (m11 * b0 - m01 * b1) / det, -m01 / det          # ph'' = a0 + a1 F
        n0, n1 = ms * (rho * a0 + 2 * rd * w - e * w * w + g * math.cos(ph)), ms * rho * a1
        found = [n for sigma in (1.0, -1.0) for n in [n0 / (1 + sigma * mu * s * n1)] if sigma * n >= 0]
        assert len(found) >= 1 and abs(found[0] - found[-1]) <= 1e-12 * abs(found[0])
        n = found[0]
        f = -mu * abs(n) * s
        return a0 + a1 * f, (-m01 * b0 + m00 * (b1 + f)) / det, n, f

    def stuck(self, y):
        """(ph'', N, F_req) with rho'' = 0."""
        (m00, m01, _), (b0, b1) = self._parts(y)
        ph, rho, w, _ = y
        ms, e, g = self.v["ms"], self.v["e"], self.v["g"]
        a = b0 / m00
        return a, ms * (rho * a - e * w * w + g * math.cos(ph)), m01 * a - b1

    def regularized(self, t_grid, y0, eps=EPS):
        def rhs(t, y):
            a, b, _, _ = self.sliding(y, math.tanh(y[3] / eps))
            return [y[2], y[3], a, b]
        sol = solve_ivp(rhs, (t_grid[0], t_grid[-1]), y0, method="DOP853", rtol=tolerance("reference_rtol"),
                        atol=tolerance("reference_atol"), t_eval=t_grid)
        assert sol.success
        forces = np.array([self.sliding(y, math.tanh(y[3] / eps))[2:] for y in sol.y.T])
        return sol.y.T, forces

    def exact(self, t_end, y0):
        """The exact law's motion: slip phases end where rho' = 0, stick phases where |F_req| = mu_s |N|.
        Returns the phase changes [(t, 'stick' | 'slip'), ...] and a function t -> state."""
        rtol, atol = tolerance("reference_rtol"), tolerance("reference_atol")
        t, y, s = 0.0, np.array(y0, float), math.copysign(1.0, y0[3])
        changes, pieces = [], []
        while t < t_end and len(changes) < 10:
            if s != 0:     # slipping in direction s
                def rhs(t, y, s=s):
                    a, b, _, _ = self.sliding(y, s)
                    return [y[2], y[3], a, b]
                stop = lambda t, y: y[3]   # noqa: E731
                stop.direction = -s        # the stop ahead, not a start from rest
            else:          # stuck: rho fixed
                def rhs(t, y):
                    return [y[2], 0.0, self.stuck(y)[0], 0.0]
                stop = lambda t, y: self.v["mus"] * abs(self.stuck(y)[1]) - abs(self.stuck(y)[2])   # noqa: E731
            stop.terminal = True
            sol = solve_ivp(rhs, (t, t_end), y, method="DOP853", rtol=rtol, atol=atol, events=stop, dense_output=True)
            pieces.append((t, sol.t[-1], sol.sol))
            if sol.status != 1:
                break
            t, y = sol.t_events[0][0], sol.y_events[0][0].copy()
            if s != 0:
                y[3] = 0.0
                _, n, f_req = self.stuck(y)
                if abs(f_req) <= self.v["mus"] * abs(n):
                    s = 0.0
                    changes.append((t, "stick"))
                else:
                    s = -math.copysign(1.0, f_req)
            else:
                s = -math.copysign(1.0, self.stuck(y)[2])
                changes.append((t, "slip"))

        def state(tq):
            for a, b, f in pieces:
                if a <= tq <= b:
                    return f(tq)
            raise ValueError(tq)
        return changes, state


# --- the description: what is allowed ---------------------------------------------------------------
def test_friction_on_a_moving_guide_is_a_cut_joint_and_a_travel_is_still_refused(tmp_path):
    ps = parameters(tmp_path, SLIDING)
    b = lower(describe(ps))
    (c,) = b.contacts
    assert c.guide is not None and c.guide.name == "arm" and [n for n, _ in b.constraints] == ["slide"]
    (c,) = lower(describe(ps), "absolute").contacts        # one gap row and its rotation lock in absolute coordinates
    assert c.guide.name == "arm"
    with pytest.raises(DescriptionError, match=r"joint 'slide': a joint with friction cannot have a travel"):
        describe(ps, travel=True).validate()
    with pytest.raises(DescriptionError, match=r"joint 'slide': friction needs a slider body"):
        describe(ps, slider_ground=True).validate()


def test_tangent_jacobian_is_the_velocity_relative_to_the_guide(tmp_path):
    """v_t = e_r . (v_S - ph' k x r_S) = (y cos ph - x sin ph) ph' + cos ph x' + sin ph y' (any q, on the
    constraint or not), and its rate's bias 2 ph' (y' cos ph - x' sin ph) - ph'^2 (x cos ph + y sin ph)."""
    eom = mechanism(tmp_path, SLIDING).equations()
    (c,) = eom.contacts
    rng = np.random.default_rng(26)
    for _ in range(5):
        q, qd = rng.normal(size=3), rng.normal(size=3)
        ph, x, y = q
        w, vx, vy = qd
        cs, sn = math.cos(ph), math.sin(ph)
        jt = np.array([y * cs - x * sn, cs, sn])
        bt = 2 * w * (vy * cs - vx * sn) - w * w * (x * cs + y * sn)
        bound = tolerance("round_off")
        assert np.abs(c.tangent_jacobian(q) - jt).max() <= bound * (1 + np.abs(q).max())
        assert abs(c.tangent_bias(q, qd) - bt) <= bound * (1 + np.abs(q).max()) * (1 + np.abs(qd).max()) ** 2


# --- the regularized law against the hand model ---------------------------------------------------------
@pytest.mark.parametrize("backend", ["reference", "compiled"])
def test_regularized_law_follows_the_hand_equations(tmp_path, backend):
    mech = mechanism(tmp_path, SLIDING)
    r = study.simulate(mech, t_end=1.0, integrator="DOP853", rtol=RTOL, atol=RTOL * 1e-2, output_step=OUTPUT_STEP,
                       friction="regularized", friction_eps=EPS, friction_sgn="tanh", backend=backend)
    hand, forces = Hand(SLIDING["values"]).regularized(r.t, SLIDING["start"])
    got = minimal(r)
    assert np.abs(got[:, 3]).min() > 100 * EPS          # slides throughout: the law is smooth along the motion
    factor = tolerance("adaptive_global_error_factor")
    for k in range(4):
        assert np.abs(got[:, k] - hand[:, k]).max() <= factor * RTOL * np.abs(hand[:, k]).max(), k
    for key, col in (("normal_slide", 0), ("friction_slide", 1)):
        assert np.abs(r.forces[key] - forces[:, col]).max() <= factor * RTOL * np.abs(forces[:, col]).max(), key
    assert np.abs(balance_residual(r)).max() <= tolerance("energy_drift_factor") * RTOL * r.energies["kinetic"].max()


# --- the exact law: slip, stick, release; energy ----------------------------------------------------------
T_EXACT = 1.0     # sticks at 0.068 s, breaks loose outward at 0.777 s as the arm spins up (the hand model's times)


@pytest.fixture(scope="module")
def exact_runs(tmp_path_factory):
    mech = mechanism(tmp_path_factory.mktemp("exact"), STICKING)
    return {b: study.simulate(mech, t_end=T_EXACT, integrator="DOP853", rtol=RTOL, atol=RTOL * 1e-2,
                              output_step=OUTPUT_STEP, friction="exact", backend=b) for b in ("reference", "compiled")}



@pytest.mark.parametrize("backend", ["reference", "compiled"])
def test_exact_law_sticks_and_breaks_loose_where_the_hand_model_does(exact_runs, backend):
    r = exact_runs[backend]
    hand = Hand(STICKING["values"])
    changes, state = hand.exact(T_EXACT, STICKING["start"])
    assert [k for _, k in changes] == ["stick", "slip"], changes
    found = [(x["t"], x["to"]) for x in r.stats["friction_transitions"] if x["contact"] == "slide"]
    assert [k if k == "stick" else k[:4] for _, k in found] == ["stick", "slip"], found
    for (t_hand, _), (t_got, _) in zip(changes, found):
        assert abs(t_got - t_hand) <= tolerance("event_time_agreement_adaptive"), (t_got, t_hand)
    got = minimal(r)
    expected = np.array([state(t) for t in r.t])
    for k in range(4):
        bound = tolerance("adaptive_global_error_factor") * RTOL * np.abs(expected[:, k]).max()
        assert np.abs(got[:, k] - expected[:, k]).max() <= bound, k
    stuck = r.forces["stick_slide"] == 1.0
    assert stuck.any() and (~stuck).any()
    assert np.abs(got[stuck, 3]).max() <= tolerance("stick_drift", table="friction")
    # held only while the needed force is within the static limit: the hand's F_req and N at the same states
    force_bound = tolerance("adaptive_global_error_factor") * RTOL * np.abs(r.forces["friction_slide"]).max()
    mu_s = STICKING["values"]["mus"]
    for k in np.flatnonzero(stuck):
        _, n, f_req = hand.stuck(expected[k])
        assert abs(f_req) <= mu_s * abs(n)
        assert abs(r.forces["friction_slide"][k] - f_req) <= force_bound
        assert abs(r.forces["normal_slide"][k] - n) <= force_bound
    # it breaks loose where the needed force reaches the limit mu_s |N| (the study's record at the located release)
    (release,) = [x for x in r.stats["friction_transitions"] if x["contact"] == "slide" and x["from"] == "stick"]
    assert abs(abs(release["f_required"]) - release["limit"]) <= force_bound
    assert release["limit"] == pytest.approx(mu_s * abs(release["normal"]), rel=tolerance("round_off"))


@pytest.mark.parametrize("backend", ["reference", "compiled"])
def test_energy_change_is_the_drive_work_minus_friction_dissipation(exact_runs, backend):
    r = exact_runs[backend]
    e = r.energies
    assert np.abs(balance_residual(r)).max() <= tolerance("energy_drift_factor") * RTOL * e["kinetic"].max()
    w = e["work_friction_slide"]     # dissipation only: never increases (while stuck, v_t is drift, ~1e-10 m/s)
    assert w[-1] < 0 and np.diff(w).max() <= tolerance("energy_drift_factor") * RTOL * e["kinetic"].max()


# --- Exudyn ------------------------------------------------------------------------------------------------
EXUDYN_HORIZON, EXUDYN_STEPS = 0.5, [2e-3, 1e-3, 5e-4]
#: Index 3's multipliers carry an O(h) start-up transient (generalized-alpha at position level, started at
#: phi' = 6 rad/s): it decays within ~0.1 s and shows without friction too (the frictionless normal force's orders
#: are 1.07, 1.00 over the whole horizon, > 5 after 0.1 s), so index 3 is held to order 2 in q and qd; index 2
#: (velocity-level constraints) in the forces as well.
EXUDYN_QUANTITIES = {"index2": ("q", "qd", "F", "N"), "index3": ("q", "qd")}


@pytest.fixture(scope="module")
def sliding(tmp_path_factory):
    mech = mechanism(tmp_path_factory.mktemp("sliding"), SLIDING)
    ref = study.simulate(mech, t_end=EXUDYN_HORIZON, method="projection", integrator="DOP853",
                         rtol=tolerance("reference_rtol"), atol=tolerance("reference_atol"), output_step=OUTPUT_STEP,
                         friction="regularized", friction_eps=EPS, friction_sgn="tanh")
    return mech, ref


@pytest.mark.parametrize("solver", ["index2", "index3"])
def test_exudyn_regularized_friction_on_the_moving_guide_converges_at_order_two(sliding, solver):
    """Exudyn's regularized friction on the turning guide (the force along the guide's current axis on the slider,
    the opposite one on the arm at the slider point; the sliding velocity relative to the arm) converges to the
    in-house reference (same law and eps) at h, h/2, h/4. Without the arm's share the arm would miss the moment
    e F of the friction pair (measured: max|dq| 3.8e-2 instead of 2.5e-6 at h = 1e-3)."""
    from study.exudyn_models import run as exudyn_run

    mech, ref = sliding
    rows = []
    for h in EXUDYN_STEPS:
        x = exudyn_run(mech, EXUDYN_HORIZON, h, solver=solver, output_step=OUTPUT_STEP, friction="regularized",
                       eps=EPS)
        assert np.abs(x.t - ref.t).max() <= 1e-12
        rows.append({"q": np.abs(x.q - ref.q).max(), "qd": np.abs(x.qd - ref.qd).max(),
                     "F": np.abs(x.forces["friction_slide"] - ref.forces["friction_slide"]).max(),
                     "N": np.abs(x.forces["normal_slide"] - ref.forces["normal_slide"]).max()})
    low = tolerance("min_order", table="cross_validation")
    floor = tolerance("order_error_floor", table="cross_validation")
    for key in EXUDYN_QUANTITIES[solver]:
        e = [row[key] for row in rows]
        assert min(e) > floor, (key, e)
        p = observed_orders(EXUDYN_STEPS, e)
        assert np.all(p >= low), (key, e, p)
