"""The tractor-trailer of ``modeling/robots/trailer/trailer.toml``: the forms that
``ConstrainedSystem`` derives from the description, against the KKT system, and the
physics along integrated trajectories.

KKT: the saddle-point system of (9) with the differentiated constraints,
[[M, Aᵀ], [A, 0]] [q̈; λ] = [B τ − H; −Ȧ q̇], solved with np.linalg.solve, uses only M, H,
A and B. Compared with it at N_STATES random consistent states (q random, every angle
anywhere, η random, q̇ = S(q) η, τ random), norm-wise relative RTOL = 1e-12:

* the minimal form: Sᵀ M S η̇ = Sᵀ B τ − Sᵀ(M Ṡ η + H) solved numerically, its symbolic
  solution ``minimal_forward_dynamics`` and q̈ = S η̇ + Ṡ η;
* the paper's reduced form (14): M̃ q̈ = B τ − H̃ solved numerically, and
  ``reduced_forward_dynamics``;
* A S = 0 and A q̇ = 0 (the states are consistent).

Parameter sets: the file's numbers and PERTURBED descriptions (inertial fields and radii
scaled by U(0.7, 1.3), centres of mass moved sideways by up to 5 cm) through the one
symbolic derivation; and an ASYMMETRIC geometry (hitch off the axis, unequal tracks and
cart wheel radii) derived with exact numbers (``numeric=True``).

Physics (DOP853, rtol 1e-11, atol 1e-12, T_END s): with τ = 0 the kinetic energy is
conserved; with smooth torques T(t) − T(0) = ∫ τᵀ θ̇_driven dt (the work integrated as a
state); the full form (14) keeps A q̇ = 0 and follows the minimal form's trajectory.

And a limitation of (14) that the WMR hides: its dependent rows are M_dd (q̈_d − …) = 0,
so a passive wheel without spin inertia makes M̃ singular, while the minimal form and the
KKT system are fine.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np
import pytest
from description_numeric import (
    NumericDescribed,
    asymmetric,
    numeric_description,
    parameter_vector,
    perturbed,
    rel,
    trailer,
)
from scipy.integrate import solve_ivp

from modeling.description import RobotDescription

RTOL = 1e-12
N_STATES = 100
N_PERTURBED = 2
SEED = 1898


def cases() -> list[tuple[str, RobotDescription, bool]]:
    """(id, numeric description, derive with exact numbers?)"""
    rng = np.random.default_rng(SEED)
    out = [("file", trailer(), False)]
    out += [(f"perturbed{i}", perturbed(trailer(), rng), False) for i in range(N_PERTURBED)]
    out.append(("asymmetric", asymmetric(), True))
    return out


CASES = cases()


def model_and_params(desc: RobotDescription, numeric: bool) -> tuple[NumericDescribed,
                                                                     np.ndarray]:
    """The shared symbolic derivation (of the file's description) evaluated at ``desc``'s
    numbers, or ``desc``'s own exact-number derivation."""
    if numeric:
        return numeric_description(desc, True), np.zeros(0)
    model = numeric_description(trailer())
    return model, parameter_vector(model.system, desc)


# ---------------------------------------------------------------------------------------
# Against the KKT system
# ---------------------------------------------------------------------------------------
@pytest.mark.parametrize(("desc", "numeric"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_minimal_and_reduced_forms_match_kkt(desc: RobotDescription, numeric: bool) -> None:
    model, p = model_and_params(desc, numeric)
    ind = model.independent
    worst: dict[str, float] = dict.fromkeys(
        ("consistent", "AS", "min_solve", "min_symbolic", "min_qdd", "red_solve",
         "red_symbolic"), 0.0)
    for q, _, qd, tau in model.states(p, seed=SEED + len(worst), count=N_STATES):
        a = model.A(q, p=p)
        s = model.S(q, p=p)
        worst["consistent"] = max(worst["consistent"],
                                  float(np.linalg.norm(a @ qd) / np.linalg.norm(qd)))
        worst["AS"] = max(worst["AS"], float(np.linalg.norm(a @ s)
                                             / (np.linalg.norm(a) * np.linalg.norm(s))))
        qdd_kkt, _ = model.kkt_solve(q, qd, tau, p)
        eta_kkt = qdd_kkt[ind]

        # minimal form, solved numerically from Sᵀ M S, Sᵀ(M Ṡη + H), Sᵀ B
        rhs = (model.B_min(q, p=p) @ tau).ravel() - model.H_min(q, qd, p=p).ravel()
        eta_dot = np.linalg.solve(model.M_min(q, p=p), rhs)
        worst["min_solve"] = max(worst["min_solve"], rel(eta_dot, eta_kkt))
        eta_sym = model.eta_dot(q, qd, tau=tau, p=p).ravel()
        worst["min_symbolic"] = max(worst["min_symbolic"], rel(eta_sym, eta_kkt))
        qdd_min = s @ eta_sym + model.Sdot_eta(q, qd, p=p).ravel()
        worst["min_qdd"] = max(worst["min_qdd"], rel(qdd_min, qdd_kkt))

        # the paper's reduced form (14)
        bt = (model.B(q, p=p) @ tau).ravel()
        qdd_14 = np.linalg.solve(model.M_red(q, qd, p=p), bt - model.H_red(q, qd, p=p).ravel())
        worst["red_solve"] = max(worst["red_solve"], rel(qdd_14, qdd_kkt))
        worst["red_symbolic"] = max(worst["red_symbolic"],
                                    rel(model.qdd_red(q, qd, tau=tau, p=p), qdd_kkt))
    assert max(worst.values()) < RTOL, worst


def test_kkt_reference_is_not_degenerate() -> None:
    """The KKT matrix is well conditioned, the multipliers are not zero, τ and the trailer
    both matter (a heavier cart changes the tractor's wheel accelerations)."""
    model, p = model_and_params(trailer(), False)
    q, _, qd, tau = next(model.states(p, seed=1, count=1))
    assert np.linalg.cond(model.kkt_lhs(q, qd, p=p)) < 1e6
    qdd0, _ = model.kkt_solve(q, qd, np.zeros(2), p)
    qdd1, lam = model.kkt_solve(q, qd, tau, p)
    assert np.linalg.norm(lam) > 1e-3
    assert np.linalg.norm(qdd1 - qdd0) > 1e-3 * np.linalg.norm(tau)
    heavy = replace(trailer(), bodies=(trailer().bodies[0],
                                       replace(trailer().bodies[1], mass=30.0)))
    qdd_heavy, _ = model.kkt_solve(q, qd, tau, parameter_vector(model.system, heavy))
    assert rel(qdd_heavy[4:6], qdd1[4:6]) > 1e-3


# ---------------------------------------------------------------------------------------
# Physics along trajectories
# ---------------------------------------------------------------------------------------
T_END = 4.0
RTOL_ODE, ATOL_ODE = 1e-11, 1e-12
ENERGY_DRIFT = 1e-9
POWER_BALANCE = 1e-8
CONSTRAINT_DRIFT = 1e-8
TRAJECTORY_AGREEMENT = 1e-8
Q0 = np.array([0.5, -0.3, 0.8, 0.5, 0.0, 0.0, 0.0, 0.0])  # hitch angle −0.3 rad
ETA0 = np.array([8.0, -3.0])  # rad/s: turning while moving


def smooth_torque(seed: int) -> Callable[[float], np.ndarray]:
    """τ(t) = Σₖ aₖ sin(ωₖ t + φₖ), three harmonics per driven wheel, |aₖ| ≤ 2 N m."""
    rng = np.random.default_rng(seed)
    amp = rng.uniform(-2, 2, (3, 2))
    omega = rng.uniform(0.5, 6, (3, 2))
    phase = rng.uniform(0, 2 * np.pi, (3, 2))
    return lambda t: (amp * np.sin(omega * t + phase)).sum(axis=0)


def zero_torque(t: float) -> np.ndarray:
    return np.zeros(2)


def integrate_minimal(model: NumericDescribed, p: np.ndarray,
                      torque: Callable[[float], np.ndarray]) -> Any:
    """State (q, η, W) with W = ∫ τ·η dt."""
    n = model.n

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        q, eta = y[:n], y[n:n + 2]
        qd = model.qdot_on_manifold(q, eta, p)
        tau = torque(t)
        return np.r_[qd, model.eta_dot(q, qd, tau=tau, p=p).ravel(), tau @ eta]

    sol = solve_ivp(rhs, (0, T_END), np.r_[Q0, ETA0, 0.0], method="DOP853", rtol=RTOL_ODE,
                    atol=ATOL_ODE, dense_output=True)
    assert sol.success, sol.message
    return sol


def integrate_full(model: NumericDescribed, p: np.ndarray,
                   torque: Callable[[float], np.ndarray]) -> Any:
    """State (q, q̇) of (14), M̃ q̈ = B τ − H̃ solved at each step."""
    n = model.n

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        q, qd = y[:n], y[n:]
        u = (model.B(q, p=p) @ torque(t)).ravel()
        return np.r_[qd, np.linalg.solve(model.M_red(q, qd, p=p),
                                          u - model.H_red(q, qd, p=p).ravel())]

    y0 = np.r_[Q0, model.qdot_on_manifold(Q0, ETA0, p)]
    sol = solve_ivp(rhs, (0, T_END), y0, method="DOP853", rtol=RTOL_ODE, atol=ATOL_ODE,
                    dense_output=True)
    assert sol.success, sol.message
    return sol


def energies(model: NumericDescribed, p: np.ndarray, sol: Any) -> np.ndarray:
    n = model.n
    return np.array([float(model.T(y[:n], model.qdot_on_manifold(y[:n], y[n:n + 2], p), p=p))
                     for y in sol.y.T])


@pytest.fixture(scope="module")
def file_model() -> tuple[NumericDescribed, np.ndarray]:
    return model_and_params(trailer(), False)


def test_energy_conserved_without_torque(file_model: tuple[NumericDescribed, np.ndarray]) -> None:
    model, p = file_model
    sol = integrate_minimal(model, p, zero_torque)
    t = energies(model, p, sol)
    drift = float(np.max(np.abs(t - t[0])) / t[0])
    assert drift < ENERGY_DRIFT, f"relative kinetic-energy drift {drift:.2e}"
    # not vacuous: the train moves, the cart swings, the wheel rates change
    assert np.linalg.norm(sol.y[:2, -1] - Q0[:2]) > 0.1
    hitch = sol.y[3] - sol.y[2]
    assert np.ptp(hitch) > 0.05
    assert np.abs(sol.y[8:10] - ETA0[:, None]).max() > 1e-2


def test_power_balance_with_torques(file_model: tuple[NumericDescribed, np.ndarray]) -> None:
    model, p = file_model
    sol = integrate_minimal(model, p, smooth_torque(seed=11))
    t = energies(model, p, sol)
    scale = float(np.max(t))
    err = float(np.max(np.abs(t - t[0] - sol.y[10])) / scale)
    assert err < POWER_BALANCE, f"|T − T0 − W| / max T = {err:.2e}"
    assert np.max(np.abs(t - t[0])) > 1e-2 * scale  # the torques do work


def test_full_form_keeps_constraints_and_matches_minimal_form(
    file_model: tuple[NumericDescribed, np.ndarray],
) -> None:
    model, p = file_model
    n = model.n
    torque = smooth_torque(seed=21)
    full = integrate_full(model, p, torque)
    minimal = integrate_minimal(model, p, torque)
    drift = max(float(np.linalg.norm(model.A(y[:n], p=p) @ y[n:])) for y in full.y.T)
    assert drift < CONSTRAINT_DRIFT, f"max ‖A q̇‖ along (14): {drift:.2e}"
    times = np.linspace(0, T_END, 81)
    yf, ym = full.sol(times), minimal.sol(times)
    dq = float(np.max(np.abs(yf[:n] - ym[:n])))
    dqd = max(float(np.max(np.abs(yf[n:, i] - model.qdot_on_manifold(ym[:n, i],
                                                                      ym[n:n + 2, i], p))))
              for i in range(times.size))
    assert max(dq, dqd) < TRAJECTORY_AGREEMENT, f"|Δq| = {dq:.2e}, |Δq̇| = {dqd:.2e}"
    assert np.linalg.norm(ym[:4, -1] - ym[:4, 0]) > 0.1


# ---------------------------------------------------------------------------------------
# What (14) needs that the minimal form does not
# ---------------------------------------------------------------------------------------
def test_reduced_form_needs_spin_inertia_on_passive_wheels() -> None:
    """Passive wheels without spin inertia: M̃ of (14) has zero rows (its dependent rows are
    M_dd (q̈_d − S_d η̇ − (Ṡη)_d) and M_dd has a zero row), while the minimal form still
    agrees with the KKT system."""
    desc = replace(trailer(), name="light-cart", wheels=tuple(
        w if w.driven else replace(w, spin_inertia=0.0, diameter_inertia=0.0, mass=0.0)
        for w in trailer().wheels))
    model = numeric_description(desc, True)
    p = np.zeros(0)
    q, _, qd, tau = next(model.states(p, seed=5, count=1))
    m_red = model.M_red(q, qd, p=p)
    assert np.linalg.matrix_rank(m_red) < model.n
    assert not m_red[6:].any()
    qdd_kkt, _ = model.kkt_solve(q, qd, tau, p)
    assert rel(model.qdd_red(q, qd, tau=tau, p=p), qdd_kkt) < RTOL
