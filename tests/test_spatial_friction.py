"""Coulomb friction in spatial joints (study.spatial.friction) against closed-form physics.

1. A block on a prismatic guide along the unit axis U through ground, gravity G with components across the guide in
   both of its transverse directions, so the normal force is the 2-vector N = m (G - (G.U) U) and the law's
   |N|_delta = sqrt(m^2 |g_perp|^2 + delta^2) (delta = pin_friction_norm_width). While it slides with velocity v,
   x(t) = x0 + v0 t + a t^2 / 2 along U with a = G.U - sgn(v) mu_k |N|_delta / m; the friction's work is
   -mu_k |N|_delta |x - x0|. Here |G.U| < mu_s |g_perp|: at rest it stays stuck; launched up the guide it stops at
   t* = v0 / |a| and sticks (|G.U| < mu_k |g_perp| too, so the regularized law creeps rather than slides back).
2. A wheel (a disc on its axle, centre on the axle) on a revolute joint with ground, the axle horizontal, gravity
   across it: the centre never moves, so the transverse reaction is R_t = m g and the friction torque mu_k r |R_t|_delta
   brakes the spin at alpha = mu_k r |R_t|_delta / I_axle until it stops at omega0 / alpha, then it sticks. An axial
   force on the wheel is carried by the axial reaction alone: R_t and omega(t) do not change.
3. Every treatment runs (exact, regularized, sign), and the regularized one converges to the exact one as eps
   shrinks, at the creep rate the law predicts.
4. The catalogue's ``friction_carriage`` (both kinds at once) on both backends: the same transitions, the energy
   balance with the friction's work.

The angular velocity is computed here from the Euler parameters by the quaternion product (omega = 2 Im(p_dot p*)),
not by the equations' rate Jacobians.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from study.model.compile import GeneratedEquations
from study.reference_data import tolerance
from study.simulate import simulate
from study.spatial import GROUND, SpatialDescription, initial_state, spatial_equations

RTOL = 1e-10
EXACT = dict(integrator="DOP853", rtol=RTOL, atol=RTOL * 1e-2, friction="exact")
DELTA = tolerance("pin_friction_norm_width")

U = np.array([1.0, 2.0, 2.0]) / 3.0          # the guide
G = np.array([3.0, 1.0, -9.81])              # gravity: G.U = -4.87, |g_perp| = 9.08 (ratio 0.54)
M_BLOCK, MU_S, MU_K = 2.0, 0.7, 0.6   # |G.U| / |g_perp| = 0.54 < mu_k < mu_s
G_PERP = G - (G @ U) * U
N_DELTA = math.sqrt((M_BLOCK * np.linalg.norm(G_PERP)) ** 2 + DELTA ** 2)

H = np.array([0.6, 0.8, 0.0])                # the wheel's axle (horizontal)
M_WHEEL, RADIUS_WHEEL, PIN, MU_PIN = 3.0, 0.2, 0.02, 0.25
I_AXLE, I_CROSS = M_WHEEL * RADIUS_WHEEL ** 2 / 2, M_WHEEL * RADIUS_WHEEL ** 2 / 4
HUB = (0.1, 0.2, 1.0)
OMEGA0 = 3.0
ALPHA = MU_PIN * PIN * math.sqrt((M_WHEEL * 9.81) ** 2 + DELTA ** 2) / I_AXLE


def bound(scale: float, rtol: float = RTOL) -> float:
    return tolerance("adaptive_global_error_factor") * rtol * scale


def friction_tol(key: str) -> float:
    return tolerance(key, "friction")


def omega_about(res, axis: np.ndarray, k: int = 0) -> np.ndarray:
    """omega . axis of body k: omega = 2 (e0 e_dot - e0_dot e + e x e_dot), the quaternion product."""
    p, pd = res.q[:, 7 * k + 3:7 * k + 7], res.qd[:, 7 * k + 3:7 * k + 7]
    omega = 2 * (p[:, :1] * pd[:, 1:] - pd[:, :1] * p[:, 1:] + np.cross(p[:, 1:], pd[:, 1:]))
    return omega @ axis


def transitions(res) -> list[tuple]:
    return [(x["contact"], x["from"], x["to"], x["t"]) for x in res.stats["friction_transitions"] if x["contact"]]


# --- 1. the block on its guide -----------------------------------------------------------------------------------
def block():
    d = SpatialDescription("friction_block")
    d.body("block", M_BLOCK, (0.1, 0.2, 0.25), points={"c": (0, 0, 0)})
    d.prismatic("guide", ("block", "c"), (GROUND, (0.0, 0.0, 0.0), tuple(U)))
    d.friction("guide", MU_S, MU_K)
    d.gravity(G)
    return d


@pytest.fixture(scope="module")
def block_eom():
    d = block()
    return d, spatial_equations(d)


def block_start(block_eom, x0: float, v0: float):
    d, eom = block_eom
    return initial_state(d, eom, {"block": tuple(x0 * U)}, velocities={"block": tuple(v0 * U)})


def slide(t, x0, v0):
    """x(t), v(t) and the friction's work of the sliding block (v keeps its sign)."""
    a = G @ U - np.sign(v0) * MU_K * N_DELTA / M_BLOCK
    x = x0 + v0 * t + a * t ** 2 / 2
    return x, v0 + a * t, -MU_K * N_DELTA * np.abs(x - x0)


def test_the_normal_force_is_a_two_vector(block_eom):
    """The guide's rows _tx, _ty both carry a share of the weight across it: |N| is a true 2-vector norm."""
    _, eom = block_eom
    q0, qd0 = block_start(block_eom, 0.2, -1.0)
    res = simulate(eom, q0, qd0, t_end=0.1, output_step=0.05, **EXACT)
    rows = [eom.constraint_names.index(f"guide_{k}") for k in ("tx", "ty")]
    n = res.lam[:, rows]
    assert np.abs(n).min() > 0.1 * M_BLOCK * np.linalg.norm(G_PERP)
    scale = M_BLOCK * np.linalg.norm(G_PERP)
    assert np.abs(np.hypot(*n.T) - scale).max() <= bound(scale)
    assert np.abs(res.forces["normal_guide"] - scale).max() <= bound(scale)


def test_a_sliding_block_follows_the_closed_form(block_eom):
    """Down the guide from v0 = -1 m/s (it slows down: |G.U| < mu_k |g_perp|, and stops at 1.74 s): position,
    velocity, friction force and work of the closed form over 1 s, the orientation held."""
    _, eom = block_eom
    q0, qd0 = block_start(block_eom, 0.2, -1.0)
    res = simulate(eom, q0, qd0, t_end=1.0, output_step=0.05, **EXACT)
    x, v, work = slide(res.t, 0.2, -1.0)
    assert transitions(res) == []
    assert np.abs(res.q[:, :3] - x[:, None] * U).max() <= bound(np.abs(x).max())
    assert np.abs(res.qd[:, :3] - v[:, None] * U).max() <= bound(np.abs(v).max())
    assert np.abs(res.forces["friction_guide"] - MU_K * N_DELTA).max() <= bound(MU_K * N_DELTA)
    assert np.abs(res.energies["work_friction_guide"] - work).max() <= bound(np.abs(work).max())
    balance = res.energy_balance()
    assert np.abs(balance - balance[0]).max() <= bound(np.abs(work).max())


def test_a_block_at_rest_stays_stuck(block_eom):
    """|G.U| < mu_s |g_perp|: the exact treatment starts in stick and stays there, velocity 0."""
    _, eom = block_eom
    q0, qd0 = block_start(block_eom, 0.2, 0.0)
    res = simulate(eom, q0, qd0, t_end=1.0, output_step=0.05, **EXACT)
    assert res.stats["friction_transitions"][0]["initial"] == {"guide": "stick"}
    assert transitions(res) == [] and np.all(res.forces["stick_guide"] == 1.0)
    assert np.abs(res.qd).max() <= friction_tol("stick_drift")
    # the guide holds the weight's component along it: f = -m G.U
    assert np.abs(res.forces["friction_guide"] + M_BLOCK * (G @ U)).max() <= bound(M_BLOCK * 9.81)


@pytest.fixture(scope="module")
def launched(block_eom):
    _, eom = block_eom
    q0, qd0 = block_start(block_eom, 0.2, 1.5)
    return eom, q0, qd0, simulate(eom, q0, qd0, t_end=0.5, output_step=0.01, **EXACT)


def test_a_block_launched_up_the_guide_stops_at_t_star_and_sticks(launched):
    _, _, _, res = launched
    a = G @ U - MU_K * N_DELTA / M_BLOCK
    t_star = 1.5 / abs(a)
    assert [(c, f, to) for c, f, to, _ in transitions(res)] == [("guide", "slip+", "stick")]
    assert transitions(res)[0][3] == pytest.approx(t_star, abs=friction_tol("event_time"))
    x_stop = 0.2 + 1.5 * t_star / 2
    x = np.where(res.t < t_star, slide(res.t, 0.2, 1.5)[0], x_stop)
    assert np.abs(res.q[:, :3] @ U - x).max() <= friction_tol("block_position")
    after = res.t > t_star
    assert np.all(res.forces["stick_guide"][after] == 1.0) and np.all(res.forces["stick_guide"][~after] == 0.0)
    assert np.abs(res.qd[after]).max() <= friction_tol("stick_drift")
    # every joule of the kinetic energy and of the climb's potential went into the friction's work
    w = res.energies["work_friction_guide"][-1]
    assert w == pytest.approx(-MU_K * N_DELTA * (x_stop - 0.2), rel=friction_tol("block_position"))


# --- 2. the wheel on its axle --------------------------------------------------------------------------------------
def wheel(axial: float = 0.0):
    d = SpatialDescription("friction_wheel")
    d.body("wheel", M_WHEEL, I_CROSS * np.eye(3) + (I_AXLE - I_CROSS) * np.outer(H, H), points={"c": (0, 0, 0)},
           axes={"axle": tuple(H)})
    d.revolute("axle", ("wheel", "c", "axle"), (GROUND, HUB, tuple(H)))
    d.friction("axle", MU_PIN, MU_PIN, radius=PIN)
    if axial:
        d.force("push", "wheel", "c", tuple(axial * H))
    d.gravity((0, 0, -9.81))
    eom = spatial_equations(d)
    return eom, *initial_state(d, eom, {"wheel": HUB}, angular_velocities={"wheel": tuple(OMEGA0 * H)})


@pytest.fixture(scope="module", params=[0.0, 5.0], ids=["free", "axial_force"])
def spun(request):
    eom, q0, qd0 = wheel(request.param)
    t_stop = OMEGA0 / ALPHA
    return request.param, eom, simulate(eom, q0, qd0, t_end=1.5 * t_stop, output_step=t_stop / 20, **EXACT)


def test_a_wheel_spins_down_at_mu_r_m_g_over_i_and_sticks(spun):
    axial, eom, res = spun
    t_stop = OMEGA0 / ALPHA
    assert [(c, f, to) for c, f, to, _ in transitions(res)] == [("axle", "slip+", "stick")]
    assert transitions(res)[0][3] == pytest.approx(t_stop, abs=bound(OMEGA0) / ALPHA)
    omega = np.maximum(OMEGA0 - ALPHA * res.t, 0.0)
    assert np.abs(omega_about(res, H) - omega).max() <= bound(OMEGA0)
    assert np.abs(res.q[:, :3] - np.array(HUB)).max() <= bound(1.0)
    # R_t = m g whatever the axial force; the axial row carries that force alone
    assert np.abs(res.forces["normal_axle"] - M_WHEEL * 9.81).max() <= bound(M_WHEEL * 9.81)
    axial_row = res.lam[:, eom.constraint_names.index("axle_tz")]
    assert np.abs(axial_row - axial).max() <= bound(M_WHEEL * 9.81)


# --- 3. every treatment ----------------------------------------------------------------------------------------------
def test_every_treatment_runs_the_sliding_block(block_eom):
    """While the block slides fast (|v| >> eps) the regularized law is the kinetic one; the plain sgn with RK4
    integrates the constant acceleration's quadratic exactly."""
    _, eom = block_eom
    q0, qd0 = block_start(block_eom, 0.2, -1.0)
    reg = simulate(eom, q0, qd0, t_end=1.0, output_step=0.05, integrator="DOP853", rtol=RTOL, atol=RTOL * 1e-2,
                   friction="regularized", friction_eps=1e-4)
    x = slide(reg.t, 0.2, -1.0)[0]
    assert np.abs(reg.q[:, :3] @ U - x).max() <= bound(np.abs(x).max())
    sign = simulate(eom, q0, qd0, t_end=1.0, output_step=0.05, integrator="RK4", step=1e-3, friction="sign",
                    friction_eps=1e-4)
    assert np.abs(sign.q[:, :3] @ U - x).max() <= tolerance("spatial_friction_rk4_quadratic") * np.abs(x).max()
    for res in (reg, sign):   # tanh(|v| / eps) = 1 in floating point at |v| >= 0.4 m/s, eps = 1e-4
        assert np.abs(res.forces["friction_guide"] - MU_K * N_DELTA).max() <= tolerance("round_off") * MU_K * N_DELTA


def test_the_compiled_path_slides_the_block_as_the_closed_form(block_eom):
    """The regularized law on the compiled path (kernels generated from the same spatial system): the sliding block
    follows the closed form within the bound the reference path's run is held to."""
    _, eom = block_eom
    q0, qd0 = block_start(block_eom, 0.2, -1.0)
    res = simulate(eom, q0, qd0, t_end=1.0, output_step=0.05, integrator="DOP853", rtol=RTOL, atol=RTOL * 1e-2,
                   friction="regularized", friction_eps=1e-4, backend="compiled")
    x = slide(res.t, 0.2, -1.0)[0]
    assert res.meta["backend"] == "compiled"
    assert np.abs(res.q[:, :3] @ U - x).max() <= bound(np.abs(x).max())


def test_regularized_converges_to_exact_at_the_creep_rate(launched):
    """After the exact block sticks at x*, tanh(v / eps) creeps down the guide at v_c = eps atanh(m G.U /
    (mu_k |N|_delta)): the distance to the exact run grows as |v_c| (T - t*), shrinking with eps."""
    eom, q0, qd0, exact = launched
    t_star = [t for *_, t in transitions(exact)][0]
    errors = []
    for eps in (1e-2, 1e-3, 1e-4):
        reg = simulate(eom, q0, qd0, t_end=0.5, output_step=0.01, friction="regularized", friction_eps=eps,
                       integrator="LSODA")
        err = float(np.abs((reg.q[:, :3] - exact.q[:, :3]) @ U).max())
        creep = eps * abs(math.atanh(M_BLOCK * (G @ U) / (MU_K * N_DELTA))) * (0.5 - t_star)
        print(f"eps {eps:g}: max |x_reg - x_exact| {err:.4g} m, creep estimate {creep:.4g} m")
        assert err == pytest.approx(creep, rel=friction_tol("regularized_creep_rate"))
        errors.append(err)
    assert errors[0] > errors[1] > errors[2]


def test_every_treatment_runs_the_wheel():
    eom, q0, qd0 = wheel()
    t_end = 0.5 * OMEGA0 / ALPHA   # still turning fast: every treatment applies the kinetic torque
    omega = OMEGA0 - ALPHA * np.linspace(0, t_end, 11)
    for friction, options in (("regularized", {"friction_eps": 1e-4}), ("sign", {"friction_eps": 1e-4})):
        res = simulate(eom, q0, qd0, t_end=t_end, output_step=t_end / 10, integrator="DOP853", rtol=RTOL,
                       atol=RTOL * 1e-2, friction=friction, **options)
        assert np.abs(omega_about(res, H) - omega).max() <= bound(OMEGA0), friction


# --- 4. the catalogue's carriage on both backends ------------------------------------------------------------------
@pytest.fixture(scope="module")
def carriage_runs():
    from study.mechanisms import named_mechanism

    mech = named_mechanism("friction_carriage")
    options = dict(t_end=2.0, integrator="DOP853", rtol=RTOL, atol=RTOL * 1e-2, output_step=0.05, friction="exact")
    return {backend: simulate(mech, backend=backend, **options) for backend in ("reference", "compiled")}


def test_the_carriage_slides_then_sticks_in_both_joints_on_both_backends(carriage_runs):
    ref, comp = carriage_runs["reference"], carriage_runs["compiled"]
    assert [c for c, *_ in transitions(ref)] == ["guide", "axle"]
    for a, b in zip(transitions(ref), transitions(comp)):
        assert a[:3] == b[:3] and abs(a[3] - b[3]) <= tolerance("fast_event_time_agreement")
    # the carriage stops at t* = v0 / |a|, the guide's normal force the weight across it (the wheel's included)
    g, u = np.array([0, 0, -9.81]), np.array([2.0, 1.0, 1.0]) / math.sqrt(6)
    n = math.sqrt((5.5 * np.linalg.norm(g - (g @ u) * u)) ** 2 + DELTA ** 2)
    assert transitions(ref)[0][3] == pytest.approx(2.0 / abs(g @ u - 0.3 * n / 5.5), abs=friction_tol("event_time"))
    assert np.abs(ref.forces["normal_guide"] - 5.5 * np.linalg.norm(g - (g @ u) * u)).max() <= bound(60.0)
    for res in (ref, comp):
        balance = res.energy_balance()
        scale = max(np.abs(v).max() for v in res.energies.values())
        assert np.abs(balance - balance[0]).max() <= friction_tol("energy_balance_adaptive") * scale
        assert res.energies["work_friction_axle"][-1] < 0 and res.energies["work_friction_guide"][-1] < 0
    assert np.abs(ref.q - comp.q).max() <= bound(1.0)


def test_the_compiled_path_refuses_pins_its_system_does_not_generate():
    from study.fast.user import user_kernels

    eom, _, _ = wheel()
    assert isinstance(eom, GeneratedEquations) and len(eom.system.rates) == 1
    stripped = dataclasses.replace(eom, system=dataclasses.replace(eom.system, rates=()))
    with pytest.raises(ValueError, match="1 friction entries.*0 rate rows.*backend='reference'"):
        user_kernels(stripped)


def test_only_a_revolute_with_friction_writes_its_rows_in_the_joint_frame():
    eom, _, _ = wheel()
    assert eom.constraint_names[:5] == ("axle_tx", "axle_ty", "axle_tz", "axle_f", "axle_g")
    d = SpatialDescription("frictionless_wheel")
    d.body("wheel", 1.0, (0.1, 0.1, 0.15), points={"c": (0, 0, 0)}, axes={"axle": (0, 0, 1)})
    d.revolute("axle", ("wheel", "c", "axle"), (GROUND, (0, 0, 0), (0, 0, 1)))
    assert spatial_equations(d).constraint_names[:5] == ("axle_x", "axle_y", "axle_z", "axle_f", "axle_g")
