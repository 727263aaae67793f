"""References that satisfy the robot's constraints exactly, for any generated robot.

A reference is defined by smooth driven-wheel rate profiles η_d(t); the configuration
follows from integrating the generated kinematics q̇ = S(q) η of (31) (DOP853, rtol 1e-11),
and the accelerations from the chain rule q̈_d = ∂(S η)/∂(q, η) · (q̇_d, η̇_d) (the q rows of
the generated linearisation's A). So every reference fed to a controller is a motion the
robot can make (docs/PAPER.md item 12); :mod:`runtime.sim.paths` builds the paper's two.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import solve_ivp

from runtime.bindings.generated import RobotCode
from runtime.sim.memo import Memo, key_of

Array = NDArray[np.float64]
RAMP = 0.3  # s, tanh time constant of every wheel-rate switch
START_AT = 1.0  # s, centre of the start-up ramp (the wheel rates ramp up from rest)


@dataclass(frozen=True)
class Reference:
    """q_d, q̇_d, q̈_d at the sample instants t (N × n each); ``name`` of the path and
    ``scale``, the length its errors are quoted against (m: a circle's radius, the lawn
    mower's leg spacing)."""

    name: str
    t: Array
    q: Array
    qdot: Array
    qddot: Array
    scale: float = math.nan


@dataclass(frozen=True)
class WheelProfile:
    """η(t) = Σ_k Δη_k s(t − t_k), s a tanh step: switches at times t_k by Δη_k."""

    times: tuple[float, ...]
    jumps: tuple[tuple[float, ...], ...]

    def rates(self, t: float) -> Array:
        out = np.zeros(len(self.jumps[0]))
        for tk, jump in zip(self.times, self.jumps, strict=True):
            s = 0.5 * (1.0 + math.tanh((t - tk) / RAMP))
            out += s * np.array(jump)
        return out

    def accels(self, t: float) -> Array:
        out = np.zeros(len(self.jumps[0]))
        for tk, jump in zip(self.times, self.jumps, strict=True):
            # d/dt of the tanh step: sech² written with exp(−2|x|), which cannot overflow
            # (cosh does, 710 ramps from a switch: a path of a few minutes)
            e = math.exp(-2.0 * abs((t - tk) / RAMP))
            ds = 0.5 / RAMP * 4.0 * e / (1.0 + e) ** 2
            out += ds * np.array(jump)
        return out


# References already integrated in this process, by everything the integration reads (the
# robot's generated code by its folder and prefix): the stability analysis, the saturation
# verdict and the simulations ask for the same circle and lawn mower once per controller,
# formulation and delay, at seconds each. Each caller gets its own copy of the arrays.
_memo: Memo[Reference] = Memo(32)


def integrate(code: RobotCode, name: str, profile: WheelProfile, start: Array,
              params: dict[str, float], h: float, duration: float,
              scale: float = math.nan) -> Reference:
    """Integrate q̇ = S(q) η_d(t) from ``start`` (DOP853, rtol 1e-11) and sample every h
    (the same arguments in one process: the same reference, integrated once)."""
    key = key_of(code, params, name, profile, np.asarray(start, dtype=np.float64).tobytes(),
                 h, duration, scale)
    ref = _memo.get(key, lambda: _integrate(code, name, profile, start, params, h, duration,
                                            scale))
    return replace(ref, t=ref.t.copy(), q=ref.q.copy(), qdot=ref.qdot.copy(),
                   qddot=ref.qddot.copy())


def _integrate(code: RobotCode, name: str, profile: WheelProfile, start: Array,
               params: dict[str, float], h: float, duration: float, scale: float) -> Reference:
    n = round(duration / h) + 1
    ts: Array = np.arange(n, dtype=np.float64) * h

    def rhs(tt: float, qq: Array) -> Array:
        return code.velocities(qq, profile.rates(tt), params)

    sol = solve_ivp(rhs, (0.0, ts[-1]), np.asarray(start, dtype=np.float64), method="DOP853",
                    t_eval=ts, rtol=1e-11, atol=1e-12, max_step=RAMP / 2)
    if not sol.success:
        raise RuntimeError(f"robot '{code.name}': reference {name}: integration failed: "
                           f"{sol.message}")
    qs: Array = np.asarray(sol.y.T, dtype=np.float64)
    qds, qdds = [], []
    zero_tau = np.zeros(code.nu)
    for tk, q in zip(ts, qs, strict=True):
        eta, eta_dot = profile.rates(tk), profile.accels(tk)
        qdot = code.velocities(q, eta, params)
        a_mat, _ = code.model.linearization(q, eta, zero_tau, params)
        qds.append(qdot)
        qdds.append(a_mat[: code.nq, :] @ np.concatenate([qdot, eta_dot]))
    return Reference(name, ts, qs, np.array(qds), np.array(qdds), scale)


def wheel_rate_reference(code: RobotCode, q0: Array, eta: Array, h: float, duration: float,
                         params: dict[str, float], substeps: int = 10) -> Reference:
    """The motion under constant wheel rates ``eta`` from ``q0`` (RK4 of q̇ = S(q) η with
    ``substeps`` per sample); q̈ = (∂(S η)/∂q) q̇ from the generated linearisation."""
    n = round(duration / h) + 1
    eta = np.asarray(eta, dtype=float)
    zero_tau = np.zeros(code.nu)
    q = np.asarray(q0, dtype=float).copy()
    qs, qds, qdds = [], [], []
    dt = h / substeps
    for k in range(n):
        qdot = code.velocities(q, eta, params)
        jac, _ = code.model.linearization(q, eta, zero_tau, params)
        qs.append(q.copy())
        qds.append(qdot)
        qdds.append(jac[: code.nq, : code.nq] @ qdot)
        if k == n - 1:
            break
        for _ in range(substeps):
            k1 = code.velocities(q, eta, params)
            k2 = code.velocities(q + dt / 2 * k1, eta, params)
            k3 = code.velocities(q + dt / 2 * k2, eta, params)
            k4 = code.velocities(q + dt * k3, eta, params)
            q = q + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    times = np.arange(n, dtype=np.float64) * h
    return Reference("wheel rates", times, np.array(qs), np.array(qds), np.array(qdds))
