"""The inputs of the hand-written comparison (the paper's robot, Drishti): random samples
for the model functions and measurement/reference sequences for the controllers — a closed
loop (the hand-written controller driving the generated forward dynamics with perturbed
true parameters, RK4) and random smooth motions near and far from the reference with random
configurations.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from runtime.tooling.crosscheck.deviation import Arr, Params
from runtime.tooling.crosscheck.targets import Target
from runtime.tooling.witness import controllers as hc
from runtime.tooling.witness import model as hw

ACCEL_NAMES: tuple[hc.Accel, ...] = ("backward", "central", "matched")


def accel_code(target: Target, accel: str) -> int:
    """The generated code's ``ACCEL_*`` constant of an estimator name."""
    return int(getattr(target.code.controllers, f"ACCEL_{accel.upper()}"))


def model_samples(rng: np.random.Generator, n: int) -> list[tuple[Params, Arr, Arr, Arr]]:
    """(params, q, wheel rates, tau) samples: parameters within ±30 % of Drishti's."""
    out = []
    for _ in range(n):
        p = {k: v * rng.uniform(0.7, 1.3) for k, v in hw.DRISHTI.items()}
        q = np.concatenate(
            [rng.uniform(-5, 5, 2), rng.uniform(-12, 12, 1), rng.uniform(-50, 50, 2)]
        )
        eta = rng.uniform(-10, 10, 2)
        tau = rng.uniform(-30, 30, 2)
        out.append((p, q, eta, tau))
    return out


def model_args(gen: str, q: Arr, eta: Arr, tau: Arr, p: Params) -> tuple[Arr, ...]:
    qdot = hw.qdot_on_manifold(q, eta, p)
    return {
        "mass_matrix": (q,),
        "bias_forces": (q, qdot),
        "forward_dynamics": (q, qdot, tau),
        "kinematics": (q, eta),
        "minimal_mass_matrix": (q,),
        "minimal_bias_forces": (q, eta),
        "minimal_forward_dynamics": (q, eta, tau),
    }[gen]


@dataclass
class Sequence_:
    """A measurement/reference sequence and the configuration to run it with."""

    name: str
    settings: hc.Settings
    q: Arr  # (N, 5)
    qdot: Arr
    q_des: Arr
    qdot_des: Arr
    qddot_des: Arr


def smooth(
    rng: np.random.Generator, amp: float, wmin: float, wmax: float, terms: int = 3
) -> Callable[[float], tuple[float, float]]:
    """A random smooth signal: (value, derivative) of a sum of sinusoids."""
    a = rng.uniform(0.2, 1.0, terms) * amp / terms
    w = rng.uniform(wmin, wmax, terms)
    ph = rng.uniform(0, 2 * math.pi, terms)

    def f(t: float) -> tuple[float, float]:
        return float(np.sum(a * np.sin(w * t + ph))), float(np.sum(a * w * np.cos(w * t + ph)))

    return f


def integrate_pose(
    p: Params,
    q0: Arr,
    rates: Callable[[float], tuple[Arr, Arr]],
    h: float,
    steps: int,
    sub: int = 10,
) -> tuple[Arr, Arr, Arr]:
    """Sampled (q, q̇, q̈) of the motion with wheel rates ``rates(t) = (η, η̇)``: the pose
    follows (31) (hand-written, RK4 with ``sub`` substeps per sample)."""
    qs, qds, qdds = [], [], []
    q = np.array(q0, dtype=np.float64)
    dt = h / sub

    def f(t: float, x: Arr) -> Arr:
        eta, _ = rates(t)
        return hw.qdot_on_manifold(x, eta, p)

    for k in range(steps):
        t = k * h
        eta, etad = rates(t)
        qs.append(q.copy())
        qds.append(hw.qdot_on_manifold(q, eta, p))
        qdds.append(hw.pose_acceleration(q, eta, etad, p))
        for j in range(sub):
            tj = t + j * dt
            k1 = f(tj, q)
            k2 = f(tj + dt / 2, q + dt / 2 * k1)
            k3 = f(tj + dt / 2, q + dt / 2 * k2)
            k4 = f(tj + dt, q + dt * k3)
            q = q + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return np.array(qs), np.array(qds), np.array(qdds)


def pair(x: Arr) -> tuple[float, float]:
    return float(x[0]), float(x[1])


def wheel_profile(
    base: tuple[float, float], mods: Sequence[Callable[[float], tuple[float, float]]]
) -> Callable[[float], tuple[Arr, Arr]]:
    def rates(t: float) -> tuple[Arr, Arr]:
        (ar, dr), (al, dl) = mods[0](t), mods[1](t)
        return np.array([base[0] + ar, base[1] + al]), np.array([dr, dl])

    return rates


def closed_loop(
    target: Target, kind: hc.Kind, formulation: hc.Formulation, seconds: float
) -> Sequence_:
    """The hand-written controller driving the generated forward dynamics + kinematics
    (true parameters ≠ nominal: +9 kg payload behind C), tracking a circle with modulated
    wheel rates (R1 = 1.5 m, θ̇d = 0.25 rad/s as in the paper), RK4 at h/10."""
    model = target.code.model
    p = dict(hw.DRISHTI)
    true = {**p, "m": 45.0, "I": 7.1, "K": 0.34 + 9.0 * 0.08, "Iw": 0.075}
    h, steps = 0.1, round(seconds / 0.1)
    wd, r1, b, r = 0.25, 1.5, p["b"], p["r"]
    base = (wd * (r1 + b / 2) / r, wd * (r1 - b / 2) / r)

    def mod(ph: float) -> Callable[[float], tuple[float, float]]:
        return lambda t: (0.6 * math.sin(0.7 * t + ph), 0.42 * math.cos(0.7 * t + ph))

    ref = integrate_pose(
        p, np.array([1.5, 1.5, 0.0, 0.0, 0.0]), wheel_profile(base, (mod(0.0), mod(1.0))), h, steps
    )
    settings = hc.Settings(nominal=p, formulation=formulation, h=h, alpha=0.35, phi=2.0, gamma=2.0)
    ctrl = hc.Controller(kind, settings)
    x = np.concatenate([[1.55, 1.45, 0.06, 0.0, 0.0], [0.0, 0.0]])  # (q, η)

    def deriv(x: Arr, tau: Arr) -> Arr:
        q, eta = x[:5], x[5:]
        qdot = np.concatenate([model.kinematics(q, eta, true), eta])
        return np.concatenate([qdot, model.forward_dynamics(q, qdot, tau, true)[3:5]])

    qs, qds = [], []
    sub = 10
    dt = h / sub
    for k in range(steps):
        q, eta = x[:5].copy(), x[5:].copy()
        qdot = np.concatenate([model.kinematics(q, eta, true), eta])
        qs.append(q)
        qds.append(qdot)
        tau = ctrl.step(q, qdot, ref[0][k], ref[1][k], ref[2][k])
        for _ in range(sub):
            k1 = deriv(x, tau)
            k2 = deriv(x + dt / 2 * k1, tau)
            k3 = deriv(x + dt / 2 * k2, tau)
            k4 = deriv(x + dt * k3, tau)
            x = x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        if not np.all(np.isfinite(x)):
            raise FloatingPointError("closed-loop simulation diverged")
    return Sequence_(f"loop {kind}/{formulation}", settings, np.array(qs), np.array(qds), *ref)


def random_sequence(
    rng: np.random.Generator, kind: hc.Kind, formulation: hc.Formulation, near: bool, steps: int
) -> Sequence_:
    """Random smooth measured motion and reference (near: the reference is the motion plus
    a small smooth offset, so ‖s‖ < ε occurs; far: an unrelated motion, large errors,
    saturation), and a random configuration."""
    h = float(rng.uniform(0.05, 0.15))
    nominal = {k: v * rng.uniform(0.8, 1.2) for k, v in hw.DRISHTI.items()}
    accel: hc.Accel = rng.choice(list(ACCEL_NAMES)).item()
    settings = hc.Settings(
        nominal=nominal,
        formulation=formulation,
        k1=rng.uniform(1.0, 8.0, 5),
        k2=rng.uniform(1.0, 8.0, 5),
        q_pos=float(rng.uniform(0.5, 2.0)),
        q_vel=float(rng.uniform(0.5, 2.0)),
        h=h,
        tau_max=float(rng.choice([50.0, 4.0])),
        accel=accel,
        rate_window=float(rng.uniform(0.0, h)) if accel == "matched" else 0.0,
        eps=float(rng.uniform(0.02, 0.5)),
        n=int(rng.integers(2, hc.MAX_WINDOW + 1)),
        a=float(rng.uniform(0.5, 1.0)),
        alpha=float(rng.uniform(0.0, 0.6)),
        phi=float(rng.uniform(0.0, 3.0)),
        gamma=float(rng.uniform(0.0, 5.0)),
        gain0=float(rng.uniform(0.0, 2.0)),
    )
    p = nominal
    mods = [smooth(rng, 3.0, 0.2, 2.0) for _ in range(2)]
    meas = integrate_pose(
        p, rng.uniform(-2, 2, 5), wheel_profile(pair(rng.uniform(-4, 4, 2)), mods), h, steps
    )
    if near:
        off = [smooth(rng, 0.03, 0.2, 2.0) for _ in range(5)]
        qd = np.array([[off[i](k * h)[0] for i in range(5)] for k in range(steps)])
        qdd = np.array([[off[i](k * h)[1] for i in range(5)] for k in range(steps)])
        ref = (meas[0] + qd, meas[1] + qdd, meas[2] + rng.normal(0, 0.1, meas[2].shape))
    else:
        mods_d = [smooth(rng, 3.0, 0.2, 2.0) for _ in range(2)]
        ref = integrate_pose(
            p, rng.uniform(-2, 2, 5), wheel_profile(pair(rng.uniform(-4, 4, 2)), mods_d), h, steps
        )
    name = f"{'near' if near else 'far'} {kind}/{formulation}"
    return Sequence_(name, settings, meas[0], meas[1], *ref)
