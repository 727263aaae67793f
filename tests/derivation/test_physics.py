"""Physics of the derived dynamics along integrated trajectories.

The minimal form (η̇ from ``minimal_forward_dynamics``, q̇ = S(q) η) and the full
5-coordinate reduced form (14) (q̈ = M̃⁻¹(B τ − H̃)) are integrated with scipy's DOP853
(rtol 1e-11, atol 1e-12) for T_END seconds, at Drishti's parameters and at a
strong-coupling parameter set with a lateral first moment (K, K_lat of the order of
√(m I)). Checked:

* τ = 0: the kinetic energy is conserved, |T(t) − T(0)| ≤ 1e-9 T(0);
* smooth random torques: the power balance dT/dt = τ_r θ̇_r + τ_l θ̇_l, integrated:
  |T(t) − T(0) − ∫₀ᵗ τ·η dt| ≤ 1e-8 max_t T (the work W is integrated as a state);
* the full form (14) keeps the constraints: ‖A(q) q̇‖ ≤ 1e-8 along it (nothing enforces
  this but the dependent rows of (14), i.e. the constraints' second derivative);
* the full and the minimal form give the same trajectory: ‖q_full − q_min‖ ≤ 1e-8 and
  ‖q̇_full − S η_min‖ ≤ 1e-8 at common times (dense output).

The measured values are reported in the assertion messages (and in the module's report).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from modeling.robot_file import load_robot

T_END = 4.0
RTOL, ATOL = 1e-11, 1e-12
ENERGY_DRIFT = 1e-9
POWER_BALANCE = 1e-8
CONSTRAINT_DRIFT = 1e-8
TRAJECTORY_AGREEMENT = 1e-8


def drishti_params() -> np.ndarray:
    p = load_robot().lumped
    return np.array([p["m"], p["I"], p["K"], 0.0, p["Iw"], p["r"], p["b"], p["d"]])


def strong_coupling_params() -> np.ndarray:
    """(K² + K_lat²)/m = I/2, split equally between K and −K_lat."""
    p = drishti_params()
    k = np.sqrt(0.25 * p[1] * p[0])
    p[2], p[3] = k, -k
    return p


CASES = [("drishti", False, drishti_params()), ("strong-lateral", True, strong_coupling_params())]


def smooth_torque(seed: int) -> Callable[[float], np.ndarray]:
    """τ(t) = Σₖ aₖ sin(ωₖ t + φₖ), three harmonics per wheel, |aₖ| ≤ 2 N m."""
    rng = np.random.default_rng(seed)
    amp = rng.uniform(-2, 2, (3, 2))
    omega = rng.uniform(0.5, 6, (3, 2))
    phase = rng.uniform(0, 2 * np.pi, (3, 2))
    return lambda t: (amp * np.sin(omega * t + phase)).sum(axis=0)


def zero_torque(t: float) -> np.ndarray:
    return np.zeros(2)


Q0 = np.array([0.5, -0.3, 0.8, 0.0, 0.0])
ETA0 = np.array([8.0, -3.0])  # rad/s: turning while moving


def integrate_minimal(model: Any, p: np.ndarray, torque: Callable[[float], np.ndarray]) -> Any:
    """State (q, η, W) with W = ∫ τ·η dt."""

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        q, eta = y[:5], y[5:7]
        qd = model.qdot_on_manifold(q, eta, p)
        tau = torque(t)
        eta_dot = model.eta_dot(q, qd, tau=tau, p=p).ravel()
        return np.r_[qd, eta_dot, tau @ eta]

    y0 = np.r_[Q0, ETA0, 0.0]
    sol = solve_ivp(rhs, (0, T_END), y0, method="DOP853", rtol=RTOL, atol=ATOL,
                    dense_output=True)
    assert sol.success, sol.message
    return sol


def integrate_full(model: Any, p: np.ndarray, torque: Callable[[float], np.ndarray]) -> Any:
    """State (q, q̇) of the reduced form (14), solved numerically at each step."""

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        q, qd = y[:5], y[5:]
        u = (model.B(q, p=p) @ torque(t)).ravel()
        qdd = np.linalg.solve(model.M_red(q, qd, p=p), u - model.H_red(q, qd, p=p).ravel())
        return np.r_[qd, qdd]

    y0 = np.r_[Q0, model.qdot_on_manifold(Q0, ETA0, p)]
    sol = solve_ivp(rhs, (0, T_END), y0, method="DOP853", rtol=RTOL, atol=ATOL,
                    dense_output=True)
    assert sol.success, sol.message
    return sol


def energies(model: Any, p: np.ndarray, sol: Any) -> np.ndarray:
    out = []
    for y in sol.y.T:
        q, eta = y[:5], y[5:7]
        out.append(float(model.T(q, model.qdot_on_manifold(q, eta, p), p=p)))
    return np.array(out)


def model_for(lateral: bool, paper_model: Any, lateral_model: Any) -> Any:
    return lateral_model if lateral else paper_model


@pytest.mark.parametrize(("lateral", "p"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_energy_conserved_without_torque(
    paper_model: Any, lateral_model: Any, lateral: bool, p: np.ndarray
) -> None:
    model = model_for(lateral, paper_model, lateral_model)
    sol = integrate_minimal(model, p, zero_torque)
    t = energies(model, p, sol)
    drift = float(np.max(np.abs(t - t[0])) / t[0])
    assert drift < ENERGY_DRIFT, f"relative kinetic-energy drift {drift:.2e}"
    # not vacuous: the robot moves and the wheel rates change (coupling through K)
    assert np.linalg.norm(sol.y[:2, -1] - Q0[:2]) > 0.1
    assert np.linalg.norm(sol.y[5:7] - ETA0[:, None], axis=0).max() > 1e-3


@pytest.mark.parametrize(("lateral", "p"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_power_balance_with_torques(
    paper_model: Any, lateral_model: Any, lateral: bool, p: np.ndarray
) -> None:
    model = model_for(lateral, paper_model, lateral_model)
    sol = integrate_minimal(model, p, smooth_torque(seed=11 + int(lateral)))
    t = energies(model, p, sol)
    work = sol.y[7]
    scale = float(np.max(t))
    err = float(np.max(np.abs(t - t[0] - work)) / scale)
    assert err < POWER_BALANCE, f"|T − T0 − W| / max T = {err:.2e}"
    # not vacuous: the torques change the energy substantially
    assert np.max(np.abs(t - t[0])) > 1e-2 * scale


@pytest.mark.parametrize(("lateral", "p"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_full_form_keeps_constraints_and_matches_minimal_form(
    paper_model: Any, lateral_model: Any, lateral: bool, p: np.ndarray
) -> None:
    model = model_for(lateral, paper_model, lateral_model)
    torque = smooth_torque(seed=21 + int(lateral))
    full = integrate_full(model, p, torque)
    minimal = integrate_minimal(model, p, torque)

    drift = max(
        float(np.linalg.norm(model.A(y[:5], p=p) @ y[5:])) for y in full.y.T
    )
    assert drift < CONSTRAINT_DRIFT, f"max ‖A q̇‖ along (14): {drift:.2e}"

    times = np.linspace(0, T_END, 81)
    yf = full.sol(times)
    ym = minimal.sol(times)
    dq = float(np.max(np.abs(yf[:5] - ym[:5])))
    dqd = max(
        float(np.max(np.abs(yf[5:, i] - model.qdot_on_manifold(ym[:5, i], ym[5:7, i], p))))
        for i in range(times.size)
    )
    assert max(dq, dqd) < TRAJECTORY_AGREEMENT, f"|Δq| = {dq:.2e}, |Δq̇| = {dqd:.2e}"
    # not vacuous: the trajectory goes somewhere
    assert np.linalg.norm(ym[:3, -1] - ym[:3, 0]) > 0.1
