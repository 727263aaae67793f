"""The paper's two paths for any generated differential-drive robot, scaled to its size.

Same construction as :mod:`runtime.paper.references` (smooth driven-wheel rate profiles η_d(t),
the configuration integrated through the generated kinematics q̇ = S(q) η with DOP853,
q̈_d by the chain rule through the generated linearisation), but nothing here knows the
robot: coordinates, actuated indices and kinematics come from its generated code, and the
sizes from :class:`RobotScale`.

Scaling (``s`` = track / Drishti's 0.414 m): the circle's radius is R1 · s at the paper's
angular rate (so a robot half Drishti's width drives a circle half the size), and the
lawn mower's wheel-rate levels are chosen so that its straight-leg speed and U-turn
diameter are Drishti's times ``s``. For a robot whose root body tows others (a trailer)
every other body follows from the same kinematics: the reference is a motion the whole
robot can make.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import solve_ivp

from runtime.closed_loop import Reference, velocities
from runtime.generated_modules import RobotCode
from runtime.paper import paths as paper_paths
from runtime.paper.paths import DRISHTI_RADIUS
from runtime.robot_scale import RobotScale

Array = NDArray[np.float64]

@dataclass(frozen=True)
class Path:
    """A reference and the length its RMS error is quoted against."""

    name: str
    ref: Reference
    scale: float  # m: the circle's radius, or the lawn mower's leg spacing


def _check_two_wheels(code: RobotCode) -> None:
    if code.nu != 2:
        raise ValueError(
            f"robot '{code.name}': the scaled circle and lawn mower are defined for a "
            f"differential drive (two driven wheels); it has {code.nu}"
        )


def integrate(
    code: RobotCode,
    profile: paper_paths.WheelProfile,
    start: Array,
    params: dict[str, float],
    h: float,
    duration: float,
) -> Reference:
    """Integrate q̇ = S(q) η_d(t) (DOP853, rtol 1e-11) and sample every h."""
    n = round(duration / h) + 1
    ts: Array = np.arange(n, dtype=np.float64) * h

    def rhs(tt: float, qq: Array) -> Array:
        return velocities(code, qq, profile.rates(tt), params)

    sol = solve_ivp(rhs, (0.0, ts[-1]), start, method="DOP853", t_eval=ts, rtol=1e-11,
                    atol=1e-12, max_step=paper_paths.RAMP / 2)
    if not sol.success:
        raise RuntimeError(f"robot '{code.name}': reference integration failed: {sol.message}")
    qs: Array = np.asarray(sol.y.T, dtype=np.float64)
    qds, qdds = [], []
    zero_tau = np.zeros(code.nu)
    for tk, q in zip(ts, qs, strict=True):
        eta, eta_dot = profile.rates(tk), profile.accels(tk)
        qdot = velocities(code, q, eta, params)
        # d/dt (S(q) η) = ∂(S η)/∂q q̇ + S(q) η̇; the second term is q̇ at η̇.
        jac, _ = code.model.linearization(q, eta, zero_tau, params)
        qds.append(qdot)
        qdds.append(jac[: code.nq, : code.nq] @ qdot + velocities(code, q, eta_dot, params))
    return Reference(ts, qs, np.array(qds), np.array(qdds))


def circle(code: RobotCode, scale: RobotScale, params: dict[str, float], h: float,
           duration: float) -> Path:
    """The root body's axle midpoint on a circle of radius R1 · size at θ̇ = 0.25 rad/s,
    counter-clockwise from rest (the first driven wheel is taken as the right one)."""
    _check_two_wheels(code)
    radius = paper_paths.R1 * scale.size
    w, r, b = paper_paths.THETA_DOT, scale.wheel_radius, scale.track
    v = w * radius
    profile = paper_paths.WheelProfile((paper_paths.START_AT,), (((v + w * b / 2) / r,
                                                                 (v - w * b / 2) / r),))
    start = np.zeros(code.nq)
    start[:2] = radius, 0.0
    start[2] = math.pi / 2  # heading tangent to the circle
    # Every other body's yaw starts aligned with the root's (a straight hitch).
    for i in body_yaws(code):
        start[i] = start[2]
    return Path("circle", integrate(code, profile, start, params, h, duration), radius)


def body_yaws(code: RobotCode) -> tuple[int, ...]:
    """Indices of the yaws of the bodies after the root (a trailer's): on a straight line
    every wheel angle turns, a body's yaw does not."""
    rate = velocities(code, np.zeros(code.nq), np.ones(code.nu), code.params)
    return tuple(i for i in code.dependent if i > 2 and abs(rate[i]) < 1e-9)


def lawnmower(code: RobotCode, scale: RobotScale, params: dict[str, float], h: float,
              duration: float) -> Path:
    """Straight legs and alternating U-turns (the paper's square-wave wheel rates made
    consistent, :func:`runtime.paper.paper_paths.lawnmower_profile`), with Drishti's leg speed and
    U-turn diameter times ``size``."""
    _check_two_wheels(code)
    speed = scale.size * DRISHTI_RADIUS / scale.wheel_radius
    a, b = paper_paths.LAWN_A * speed, paper_paths.LAWN_B * speed
    r, track = scale.wheel_radius, scale.track
    profile = paper_paths.lawnmower_profile({"r": r, "b": track}, duration, (a, b))
    spacing = 2 * (r * (a + b) / 2) / (r * (a - b) / track)
    ref = integrate(code, profile, np.zeros(code.nq), params, h, duration)
    return Path("lawnmower", ref, spacing)
