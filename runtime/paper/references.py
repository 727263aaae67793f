"""Reference trajectories that satisfy the constraints (6)–(8) exactly (docs/PAPER.md item 12).

A reference is defined by smooth wheel-rate profiles η_d(t); the pose follows from
integrating the kinematics (31) (DOP853, rtol 1e-11), and the accelerations from the chain rule
q̈_d = ∂(S η)/∂(q, η) · (q̇_d, η̇_d) (rows 1–5 of the generated linearisation's A).
So every reference fed to a controller is a motion the robot can make.

The paper's printed definitions are kept beside ours (``printed_*``) for the plots:

* circle: printed x_d, y_d on R1 = 1.5 m with θ_d = θ0 + θ̇_d t, wheel rates assuming the
  axle centre is on R1. Ours: the same angular rate θ̇_d = 0.25 rad/s, C (not the axle
  centre) exactly on the circle of radius R1: axle radius √(R1² − d²), heading tangent
  to the axle's circle, wheel rates (v ± θ̇_d b/2)/r with v = θ̇_d √(R1² − d²).
* lawn mower: printed x_d = 0.1 t + 0.3 sin(0.4 t), y_d = 1.2 + 1.2 cos(0.2 t − T) with
  square-wave wheel rates (levels a = 3, b = 1.6 rad/s, T = 25 s) — two different motions.
  Ours: the square waves made consistent: straight legs with both wheels at a = 3 rad/s,
  U-turns with one wheel at b = 1.6 rad/s (alternating left and right), each turn lasting
  exactly π/ω so the legs are parallel; switching smoothed with tanh over 0.3 s.
Both start from rest (the wheel rates ramp up over the first ~2 s).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import solve_ivp

from runtime.generated_modules import wmr_model
from runtime.paper.paths import (
    LAWN_A,
    LAWN_B,
    LAWN_T,
    R1,
    RAMP,
    START_AT,
    THETA_DOT,
    WheelProfile,
    lawnmower_profile,
)

__all__ = ["LAWN_A", "LAWN_B", "LAWN_T", "R1", "RAMP", "START_AT", "THETA_DOT", "Reference",
           "WheelProfile", "circle", "circle_profile", "lawnmower", "lawnmower_leg_spacing",
           "lawnmower_profile", "printed_circle", "printed_lawnmower"]

CIRCLE_START = (1.5, 1.5, 0.0)


@dataclass(frozen=True)
class Reference:
    """Samples at t = k h: q_d, q̇_d, q̈_d (each (N, 5)); ``name`` of the path."""

    name: str
    t: NDArray[np.float64]
    q: NDArray[np.float64]
    qdot: NDArray[np.float64]
    qddot: NDArray[np.float64]


def circle_profile(params: dict[str, float]) -> WheelProfile:
    r, b, d = params["r"], params["b"], params["d"]
    v = THETA_DOT * math.sqrt(R1**2 - d**2)
    wr, wl = (v + THETA_DOT * b / 2) / r, (v - THETA_DOT * b / 2) / r
    return WheelProfile((START_AT,), ((wr, wl),))


def lawnmower_leg_spacing(params: dict[str, float]) -> float:
    """Distance between neighbouring legs: the U-turn's diameter 2 v/ω of the axle centre."""
    r, b = params["r"], params["b"]
    v, w = r * (LAWN_A + LAWN_B) / 2, r * (LAWN_A - LAWN_B) / b
    return 2 * v / w


def integrate(
    name: str,
    profile: WheelProfile,
    start: tuple[float, float, float],
    params: dict[str, float],
    h: float,
    duration: float,
) -> Reference:
    """Integrate (31) (DOP853, rtol 1e-11) and sample every h."""
    n = round(duration / h) + 1
    ts: NDArray[np.float64] = np.arange(n, dtype=np.float64) * h

    def rhs(tt: float, qq: NDArray[np.float64]) -> NDArray[np.float64]:
        eta = profile.rates(tt)
        return np.concatenate([wmr_model.kinematics(qq, eta, params), eta])

    sol = solve_ivp(
        rhs,
        (0.0, ts[-1]),
        [*start, 0.0, 0.0],
        method="DOP853",
        t_eval=ts,
        rtol=1e-11,
        atol=1e-12,
        max_step=RAMP / 2,
    )
    if not sol.success:
        raise RuntimeError(f"reference {name}: integration failed: {sol.message}")
    qs: NDArray[np.float64] = np.asarray(sol.y.T, dtype=np.float64)
    qds, qdds = [], []
    for tk, q in zip(ts, qs, strict=True):
        eta, eta_dot = profile.rates(tk), profile.accels(tk)
        qdot = np.concatenate([wmr_model.kinematics(q, eta, params), eta])
        a_mat, _ = wmr_model.linearization(q, eta, np.zeros(2), params)
        qds.append(qdot)
        qdds.append(a_mat[:5, :] @ np.concatenate([qdot, eta_dot]))
    return Reference(name, ts, qs, np.array(qds), np.array(qdds))


def circle(params: dict[str, float], h: float, duration: float) -> Reference:
    return integrate("circle", circle_profile(params), CIRCLE_START, params, h, duration)


def lawnmower(params: dict[str, float], h: float, duration: float) -> Reference:
    return integrate(
        "lawnmower", lawnmower_profile(params, duration), (0.0, 0.0, 0.0), params, h, duration
    )


def printed_circle(t: NDArray[np.float64]) -> NDArray[np.float64]:
    """The printed circle's (x_d, y_d): centre (0, 1.5)... as printed, radius R1 = 1.5 m,
    starting at (1.5, 1.5) — shown beside ours, not used for control."""
    return np.stack([R1 * np.cos(THETA_DOT * t), 1.5 + R1 * np.sin(THETA_DOT * t)], axis=1)


def printed_lawnmower(t: NDArray[np.float64]) -> NDArray[np.float64]:
    """The printed lawn-mower (x_d, y_d) with T = 25 s — shown beside ours, not used."""
    return np.stack([0.1 * t + 0.3 * np.sin(0.4 * t), 1.2 + 1.2 * np.cos(0.2 * t - LAWN_T)], axis=1)
