"""Closed loop for any generated robot, from its generated code only.

Plant: the generated ``<prefix>_plant.plant_state_derivative`` (the constrained dynamics in
the minimal form), fixed-step RK4 under zero-order hold, ``substeps`` per sample.
Controller: the generated controller classes (the NumPy mirror of the C API, checked
against the C by the cross-check tests), sampled every h, fed the true q and q̇ at the
sample instant (no sensor model: the paper's robot has its own, ``runtime.paper.simulate``).
Reference: constant driven-wheel rates η_d from a consistent initial pose, integrated
through the generated kinematics q̇ = S(q) η — for a differential drive, a circle; for a
tractor with a trailer, a circle with the trailer settling onto its own circle.

Nothing here knows the robot: sizes, actuated coordinates and parameter keys come from
the generated ``robot.py`` (``runtime.generated_modules.load_robot_code``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from runtime.generated_modules import RobotCode

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Reference:
    """q_d, q̇_d, q̈_d at the sample instants t (N × n each)."""

    t: Array
    q: Array
    qdot: Array
    qddot: Array


def velocities(code: RobotCode, q: Array, eta: Array, params: dict[str, float]) -> Array:
    """q̇ = S(q) η: the driven-wheel rates and the rates the constraints give the others."""
    qdot = np.empty(code.nq)
    qdot[list(code.actuated)] = eta
    qdot[list(code.dependent)] = code.model.kinematics(q, eta, params)
    return qdot


def wheel_rate_reference(
    code: RobotCode,
    q0: Array,
    eta: Array,
    h: float,
    duration: float,
    params: dict[str, float],
    substeps: int = 10,
) -> Reference:
    """The motion under constant wheel rates ``eta`` from ``q0`` (RK4 of q̇ = S(q) η with
    ``substeps`` per sample); q̈ = (∂(S η)/∂q) q̇ from the generated linearisation."""
    n = round(duration / h) + 1
    eta = np.asarray(eta, dtype=float)
    zero_tau = np.zeros(code.nu)
    q = np.asarray(q0, dtype=float).copy()
    qs, qds, qdds = [], [], []
    dt = h / substeps
    for k in range(n):
        qdot = velocities(code, q, eta, params)
        jac, _ = code.model.linearization(q, eta, zero_tau, params)
        qs.append(q.copy())
        qds.append(qdot)
        qdds.append(jac[: code.nq, : code.nq] @ qdot)
        if k == n - 1:
            break
        for _ in range(substeps):
            k1 = velocities(code, q, eta, params)
            k2 = velocities(code, q + dt / 2 * k1, eta, params)
            k3 = velocities(code, q + dt / 2 * k2, eta, params)
            k4 = velocities(code, q + dt * k3, eta, params)
            q = q + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    times = np.arange(n, dtype=np.float64) * h
    return Reference(times, np.array(qs), np.array(qds), np.array(qdds))


@dataclass(frozen=True)
class LoopRun:
    """One closed-loop run at the sample instants (``failed_at``: a status < 0 or a
    non-finite state stopped it)."""

    controller: str
    t: Array
    q: Array  # true q (N × n)
    q_des: Array
    tau: Array  # (N × m)
    gain: Array
    saturated: int
    failed_at: float | None

    def wheel_error(self, actuated: tuple[int, ...]) -> Array:
        """‖q_d − q‖ over the driven-wheel angles (what the minimal formulation tracks)."""
        idx = list(actuated)
        return np.linalg.norm(self.q_des[:, idx] - self.q[:, idx], axis=1)


def plant_step(
    code: RobotCode, x: Array, tau: Array, pp: dict[str, float], dt: float, nsub: int
) -> Array:
    """RK4 of the plant's ẋ = f(x, τ) over ``nsub`` steps of ``dt`` under ZOH."""
    f = code.plant.plant_state_derivative
    for _ in range(nsub):
        k1 = f(x, tau, pp)
        k2 = f(x + dt / 2 * k1, tau, pp)
        k3 = f(x + dt / 2 * k2, tau, pp)
        k4 = f(x + dt * k3, tau, pp)
        x = x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return x


def run(
    code: RobotCode,
    controller: str,
    ref: Reference,
    config: Any,
    plant_params: dict[str, float] | None = None,
    substeps: int = 10,
) -> LoopRun:
    """Simulate ``controller`` (``"tdc"``, ``"tdroc"``, ``"roc"``, ``"asmc"``) with the
    generated ``config`` (a ``controllers.Config``) on ``ref``; the plant starts on the
    reference at rest and has ``plant_params`` (default: the robot's defaults)."""
    ctl = code.controller_class(controller)(config)
    pp = dict(code.plant_defaults if plant_params is None else plant_params)
    h = float(config.h)
    x = np.concatenate([ref.q[0], np.zeros(code.nu)])
    rec_q, rec_tau, rec_gain = [], [], []
    saturated, failed_at = 0, None
    for k in range(len(ref.t)):
        q = x[: code.nq]
        qdot = velocities(code, q, x[code.nq :], pp)
        try:
            tau = ctl.step(q, qdot, ref.q[k], ref.qdot[k], ref.qddot[k])
        except ValueError:
            failed_at = float(ref.t[k])
            break
        saturated += ctl.last_status.endswith("_WARN_SATURATED")
        rec_q.append(q.copy())
        rec_tau.append(np.array(tau, dtype=float))
        rec_gain.append(float(ctl.gain))
        if k == len(ref.t) - 1:
            break
        x = plant_step(code, x, np.asarray(tau, dtype=float), pp, h / substeps, substeps)
        if not np.all(np.isfinite(x)):
            failed_at = float(ref.t[k])
            break
    m = len(rec_q)
    return LoopRun(controller, ref.t[:m], np.array(rec_q), ref.q[:m], np.array(rec_tau),
                   np.array(rec_gain), int(saturated), failed_at)
