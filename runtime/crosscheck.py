"""``python -m runtime crosscheck``: every implementation against the hand-written equations.

Reference: ``runtime/handwritten`` (the paper's equations typed by hand in NumPy,
independent of modeling/ and codegen/). Compared with it, on identical inputs:

* ``gen-python`` — generated/python (``wmr_model`` functions, ``controllers`` classes);
* ``C double``  — generated/c compiled with cffi (``runtime.cbuild``, cached under build/);
* ``CasADi``    — generated/casadi/*.casadi (model functions, and the law kernels — TDE,
  TDROC gain, the four laws — fed the inputs the reference computed in each step);
* ``C float32`` — generated/c built with -DWMR_FLOAT32.

Inputs: random samples for the model functions; for the controllers, measurement sequences
from a closed-loop run (the hand-written controller driving the generated Python forward
dynamics + kinematics with perturbed "true" parameters, RK4) and from random smooth motions
with random configurations (random nominal parameters, per-coordinate gains, window,
discount, estimator, bounds, a torque limit that saturates). Each controller sees the
recorded measurement sequence open loop, runs its own state machine and is compared step by
step (τ, switching gain, ‖s‖, Ĥ1, ‖u₁₋₃‖).

Deviation of a quantity: max over samples of ‖x − x_ref‖∞ / max(‖x_ref‖∞, 10⁻³·S), S the
largest ‖x_ref‖∞ of the sequence (the floor keeps near-zero samples from dominating).

Tolerances: 1e-9 for the double implementations. Float32 (see ``FLOAT32_TOL``) is compared
per step on identical inputs: inputs, parameters and the controller state are rounded to
float32 and the reference is evaluated on exactly those rounded values (in double), so the
deviation measures float32 arithmetic only, never the amplification of earlier differences
through the loop.

Exit status 1 if any deviation exceeds its tolerance. ``--perturb IMPL:KEY=FACTOR``
multiplies parameter KEY of the (nominal) parameters passed to IMPL (python, c64, c32,
casadi) by FACTOR: the check must then fail (used by the tests).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from runtime.handwritten import controllers as hc
from runtime.handwritten import model as hw

ROOT = Path(__file__).resolve().parent.parent
CASADI_DIR = ROOT / "generated" / "casadi"
DOUBLE_TOL = 1e-9
#: float32 tolerance. Unit roundoff u = 2⁻²⁴ ≈ 6.0e-8. Each generated output is a
#: straight-line expression of at most ~200 operations, so a few tens of u is the normal
#: normwise error; cancellation (θ̇_r² − θ̇_l² in H, Ĥ1 = u(t−h) − M̂ q̈ in (17), Ω(i) − Ω(i+1)
#: in (25), the sum in (16)) is amplified at most 10³× by the 10⁻³·S floor of the metric, so
#: rounding alone stays below ~10³ u ≈ 6e-5 (observed: ≤ 4e-6). 1e-4 (≈ 1700 u) therefore
#: separates rounding from a real difference (a 1 % parameter error gives > 1e-3).
FLOAT32_TOL = 1e-4
IMPLS = ("python", "c64", "casadi", "c32")
# accel_estimator codes of the generated configs (WMR_ACCEL_*).
ACCEL_CODES: dict[str, int] = {"backward": 0, "central": 1, "matched": 2}
IMPL_TITLES = {"python": "gen-python", "c64": "C double", "casadi": "CasADi", "c32": "C float32"}
Arr = NDArray[np.float64]
Params = dict[str, float]


# ============================================================================ utilities


def f32(x: Any) -> Any:
    """Round to float32 (returned as float64 / float)."""
    if isinstance(x, float | int):
        return float(np.float32(x))
    return np.asarray(x, dtype=np.float64).astype(np.float32).astype(np.float64)


def f32_params(p: Mapping[str, float]) -> Params:
    return {k: f32(float(v)) for k, v in p.items()}


@dataclass
class Deviation:
    """Largest deviation of one implementation, over samples and quantities."""

    value: float = 0.0
    worst: str = ""

    def add(self, name: str, got: Sequence[Any], ref: Sequence[Any]) -> None:
        """Per-sample normwise relative deviation of quantity ``name``."""
        g = [np.atleast_1d(np.asarray(x, dtype=np.float64)).ravel() for x in got]
        r = [np.atleast_1d(np.asarray(x, dtype=np.float64)).ravel() for x in ref]
        if len(g) != len(r):
            raise ValueError(f"{name}: {len(g)} samples against {len(r)}")
        if not r:
            return
        scale = max(float(np.max(np.abs(x))) if x.size else 0.0 for x in r)
        floor = max(1e-3 * scale, 1e-300)
        dev = 0.0
        for a, b in zip(g, r, strict=True):
            if a.shape != b.shape:
                dev = math.inf
                break
            err = float(np.max(np.abs(a - b))) if a.size else 0.0
            if not math.isfinite(err):
                dev = math.inf
                break
            dev = max(dev, err / max(float(np.max(np.abs(b))), floor))
        self.merge(dev, name)

    def merge(self, value: float, name: str) -> None:
        if value > self.value or (math.isnan(value)):
            self.value, self.worst = value, name


@dataclass
class Row:
    name: str
    cells: dict[str, Deviation] = field(default_factory=dict)


def perturbed(
    p: Mapping[str, float], impl: str, perturb: Mapping[str, Mapping[str, float]]
) -> Params:
    out = {k: float(v) for k, v in p.items()}
    for key, factor in perturb.get(impl, {}).items():
        out[key] *= factor
    return out


# ============================================================================ implementations


@cache
def c_library(float32: bool) -> Any:
    from runtime import cbuild

    return cbuild.build(float32)


@cache
def casadi_function(name: str) -> Any:
    import casadi

    return casadi.Function.load(str(CASADI_DIR / f"{name}.casadi"))


def casadi_call(name: str, *args: Any) -> list[Arr]:
    out = casadi_function(name).call([np.asarray(a, dtype=np.float64).reshape(-1, 1) for a in args])
    return [np.asarray(o, dtype=np.float64).ravel() for o in out]


def pvec(p: Mapping[str, float]) -> Arr:
    return np.array([float(p[k]) for k in hw.PARAM_KEYS])


class CModel:
    """The generated model functions through cffi."""

    def __init__(self, float32: bool) -> None:
        self.lib = c_library(float32)
        self.ffi, self.c = self.lib.ffi, self.lib.lib

    def arr(self, x: Any) -> Any:
        return self.ffi.new("wmr_real_t[]", [float(v) for v in np.asarray(x).ravel()])

    def out(self, n: int) -> Any:
        return self.ffi.new("wmr_real_t[]", n)

    def params(self, p: Mapping[str, float]) -> Any:
        from runtime import cbuild

        return cbuild.fill_params(self.ffi.new("wmr_params_t *"), {k: p[k] for k in hw.PARAM_KEYS})

    def read(self, buf: Any, n: int) -> Arr:
        return np.array([buf[i] for i in range(n)], dtype=np.float64)

    def call(self, fn: str, p: Mapping[str, float], args: Sequence[Any], n_out: int) -> Arr:
        out = self.out(n_out)
        status = getattr(self.c, f"wmr_{fn}")(self.params(p), *map(self.arr, args), out)
        if status not in (None, 0):
            raise RuntimeError(f"wmr_{fn} returned {status}")
        return self.read(out, n_out)


# ============================================================================ model functions

ModelFn = Callable[[str, Params, tuple[Arr, ...]], Arr]

# name, hand-written function, argument layout, generated python name, C name, output size
MODEL_FUNCTIONS: tuple[tuple[str, Callable[..., Arr], str, int], ...] = (
    ("M (14)", hw.mass_matrix_14, "mass_matrix", 25),
    ("H (14)", hw.bias_14, "bias_forces", 5),
    ("forward dynamics (14)", hw.forward_dynamics_14, "forward_dynamics", 5),
    ("kinematics (31)", hw.kinematics_31, "kinematics", 3),
    ("Mbar = S'MS", hw.minimal_mass_matrix, "minimal_mass_matrix", 4),
    ("Hbar = S'(M Sdot eta + H)", hw.minimal_bias, "minimal_bias_forces", 2),
    ("minimal forward dynamics", hw.minimal_forward_dynamics, "minimal_forward_dynamics", 2),
)


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


def check_models(
    samples: list[tuple[Params, Arr, Arr, Arr]], perturb: Mapping[str, Mapping[str, float]]
) -> list[Row]:
    from runtime.generated_modules import wmr_model

    cm = {"c64": CModel(False), "c32": CModel(True)}
    rows = []
    for title, ref_fn, gen, n_out in MODEL_FUNCTIONS:
        row = Row(title)
        results: dict[str, list[Arr]] = {k: [] for k in (*IMPLS, "ref", "ref32")}
        for p, q, eta, tau in samples:
            args = model_args(gen, q, eta, tau, p)
            results["ref"].append(np.ravel(ref_fn(*args, p)))
            results["python"].append(
                np.ravel(getattr(wmr_model, gen)(*args, perturbed(p, "python", perturb)))
            )
            results["c64"].append(cm["c64"].call(gen, perturbed(p, "c64", perturb), args, n_out))
            results["casadi"].append(
                casadi_call(gen, pvec(perturbed(p, "casadi", perturb)), *args)[0]
            )
            # float32: rounded inputs; the reference sees exactly those rounded values.
            p32 = f32_params(p)
            args32 = tuple(f32(a) for a in model_args(gen, f32(q), f32(eta), f32(tau), p32))
            results["ref32"].append(np.ravel(ref_fn(*args32, p32)))
            results["c32"].append(
                cm["c32"].call(gen, perturbed(p32, "c32", perturb), args32, n_out)
            )
        for impl in IMPLS:
            dev = Deviation()
            dev.add(title, results[impl], results["ref32" if impl == "c32" else "ref"])
            row.cells[impl] = dev
        rows.append(row)
    return rows


# ============================================================================ derivation checks


def self_checks(samples: list[tuple[Params, Arr, Arr, Arr]]) -> list[tuple[str, float, bool]]:
    """Consistency of the hand-written equations with each other and with (9):
    (name, max relative deviation, gated)."""
    import scipy.linalg

    checks: dict[str, Deviation] = {}

    def add(name: str, got: Any, ref: Any) -> None:
        checks.setdefault(name, Deviation()).add(name, [got], [ref])

    for p, q, eta, tau in samples:
        S, A = hw.null_space(q, p), hw.constraint_matrix(q, p)
        M9, qdot = hw.mass_matrix_9(q, p), hw.qdot_on_manifold(q, eta, p)
        Ma, Sa = M9[:3, :3], S[:3]
        block = np.block([[Ma, -Ma @ Sa], [Sa.T @ Ma, p["Iw"] * np.eye(2)]])
        add(
            "A(q) S(q) = 0, (31) corrected vs (6)-(8) [abs. residual]", A @ S + 1.0, np.ones((3, 2))
        )
        add("M (14) printed = [[Ma, -Ma Sa], [Sa' Ma, Iw]] derived", hw.mass_matrix_14(q, p), block)
        h_block = np.concatenate(
            [-Ma @ hw.null_space_rate_times_eta(q, eta, p)[:3], Sa.T @ hw.bias_9(q, qdot, p)[:3]]
        )
        add("H (14) printed = [-Ma Sdot_a eta; Sa' Ha] derived", hw.bias_14(q, qdot, p), h_block)
        mbar = hw.minimal_mass_matrix(q, p)
        q0 = np.array([q[0], q[1], 0.0, q[3], q[4]])
        add(
            "||M (14)^-1||_F independent of heading (TDROC gain of (25))",
            np.linalg.norm(np.linalg.inv(hw.mass_matrix_14(q, p))),
            np.linalg.norm(np.linalg.inv(hw.mass_matrix_14(q0, p))),
        )
        add(
            "M (14) S = [0; Mbar]", hw.mass_matrix_14(q, p) @ S, np.vstack([np.zeros((3, 2)), mbar])
        )
        # (14) against the constrained Lagrange equations (9) + (6)-(8), solved as KKT system.
        th, thd = q[2], qdot[2]
        adot = np.array(
            [
                [-math.cos(th) * thd, -math.sin(th) * thd, 0.0, 0.0, 0.0],
                [math.sin(th) * thd, -math.cos(th) * thd, 0.0, 0.0, 0.0],
                [math.sin(th) * thd, -math.cos(th) * thd, 0.0, 0.0, 0.0],
            ]
        )
        kkt = np.block([[M9, A.T], [A, np.zeros((3, 3))]])
        rhs = np.concatenate([hw.input_matrix_9() @ tau - hw.bias_9(q, qdot, p), -adot @ qdot])
        add(
            "forward dynamics (14) = KKT solve of (9) with (6)-(8)",
            hw.forward_dynamics_14(q, qdot, tau, p),
            np.linalg.solve(kkt, rhs)[:5],
        )
        add(
            "forward dynamics (14) = S etadot + Sdot eta (minimal)",
            hw.forward_dynamics_14(q, qdot, tau, p),
            hw.pose_acceleration(q, eta, hw.minimal_forward_dynamics(q, eta, tau, p), p),
        )
        k1, k2, qp, qv = (float(x) for x in np.abs(tau[:1].tolist() + eta.tolist() + [p["m"]]))
        k1, k2 = 1.0 + k1 % 7, 1.0 + k2 % 7
        qp, qv = 0.5 + qp % 2, 0.5 + qv % 2
        a_mat = np.array([[0.0, 1.0], [-k1, -k2]])
        pm = scipy.linalg.solve_continuous_lyapunov(a_mat.T, -np.diag([qp, qv]))
        p11, p12, p22 = hc.lyapunov_p(k1, k2, qp, qv)
        add(
            "lyapunov_p = scipy solve_continuous_lyapunov",
            [p11, p12, p22],
            [pm[0, 0], pm[0, 1], pm[1, 1]],
        )
    gated = [(name, d.value, True) for name, d in checks.items()]
    # Information only: how far the printed (31) (b where b/2 belongs) is from (6)-(8).
    printed = Deviation()
    for p, q, eta, _ in samples:
        printed.add(
            "printed", [hw.kinematics_31_as_printed(q, eta, p)], [hw.kinematics_31(q, eta, p)]
        )
    gated.append(
        ("(31) as printed (b, not b/2) vs corrected [erratum, info]", printed.value, False)
    )
    return gated


# ============================================================================ sequences


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


def closed_loop(kind: hc.Kind, formulation: hc.Formulation, seconds: float) -> Sequence_:
    """The hand-written controller driving the generated forward dynamics + kinematics
    (true parameters ≠ nominal: +9 kg payload behind C), tracking a circle with modulated
    wheel rates (R1 = 1.5 m, θ̇d = 0.25 rad/s as in the paper), RK4 at h/10."""
    from runtime.generated_modules import wmr_model

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
        qdot = np.concatenate([wmr_model.kinematics(q, eta, true), eta])
        return np.concatenate([qdot, wmr_model.forward_dynamics(q, qdot, tau, true)[3:5]])

    qs, qds = [], []
    sub = 10
    dt = h / sub
    for k in range(steps):
        q, eta = x[:5].copy(), x[5:].copy()
        qdot = np.concatenate([wmr_model.kinematics(q, eta, true), eta])
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
    accel: hc.Accel = rng.choice(list(ACCEL_CODES)).item()
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


# ============================================================================ controller runs


@dataclass
class Trace:
    """Per-step outputs of one implementation."""

    tau: list[Arr] = field(default_factory=list)
    gain: list[float] = field(default_factory=list)
    s_norm: list[float] = field(default_factory=list)
    H1hat: list[Arr] = field(default_factory=list)
    u_discarded: list[float] = field(default_factory=list)
    saturated: list[bool] = field(default_factory=list)

    def record(
        self, tau: Any, gain: float, s_norm: float, h1: Any, u_disc: float, sat: bool
    ) -> None:
        self.tau.append(np.array(tau, dtype=np.float64))
        self.gain.append(float(gain))
        self.s_norm.append(float(s_norm))
        self.H1hat.append(np.array(h1, dtype=np.float64))
        self.u_discarded.append(float(u_disc))
        self.saturated.append(bool(sat))


def compare_traces(dev: Deviation, got: Trace, ref: Trace, nc: int, check_status: bool) -> None:
    dev.add("tau", got.tau, ref.tau)
    dev.add("gain", got.gain, ref.gain)
    dev.add("|s|", got.s_norm, ref.s_norm)
    dev.add("H1hat", [h[:nc] for h in got.H1hat], [h[:nc] for h in ref.H1hat])
    dev.add("|u_1..3|", got.u_discarded, ref.u_discarded)
    if check_status and got.saturated != ref.saturated:
        dev.merge(math.inf, "saturation status")


def hand_run(seq: Sequence_, kind: hc.Kind) -> tuple[Trace, list[hc.StepRecord]]:
    ctrl = hc.Controller(kind, seq.settings)
    trace, records = Trace(), []
    for k in range(len(seq.q)):
        ctrl.step(seq.q[k], seq.qdot[k], seq.q_des[k], seq.qdot_des[k], seq.qddot_des[k])
        hs = ctrl.history
        trace.record(hs.tau, hs.gain, hs.s_norm, hs.H1hat, hs.u_discarded, ctrl.saturated)
        assert ctrl.last is not None
        records.append(ctrl.last)
    return trace, records


def python_run(seq: Sequence_, kind: hc.Kind, nominal: Params) -> Trace:
    from runtime.generated_modules import controllers as gc

    s = seq.settings
    cfg = gc.Config(
        nominal=nominal,
        formulation=gc.FORMULATION_PAPER if s.formulation == "paper" else gc.FORMULATION_MINIMAL,
        k1=np.asarray(s.k1, dtype=np.float64).tolist(),
        k2=np.asarray(s.k2, dtype=np.float64).tolist(),
        q_pos=s.q_pos,
        q_vel=s.q_vel,
        h=s.h,
        tau_max=s.tau_max,
        accel_estimator=ACCEL_CODES[s.accel],
        rate_window=s.rate_window,
        eps=s.eps,
        n=s.n,
        a=s.a,
        alpha=s.alpha,
        phi=s.phi,
        gamma=s.gamma,
        gain0=s.gain0,
    )
    ctrl = getattr(gc, kind.upper())(cfg)
    trace = Trace()
    for k in range(len(seq.q)):
        ctrl.step(seq.q[k], seq.qdot[k], seq.q_des[k], seq.qdot_des[k], seq.qddot_des[k])
        trace.record(
            ctrl.tau,
            ctrl.gain,
            ctrl.s_norm,
            ctrl.H1hat,
            ctrl.u_discarded,
            ctrl.last_status == "WMR_WARN_SATURATED",
        )
    return trace


class CController:
    """A generated C controller (config + state structs) through cffi."""

    def __init__(self, float32: bool, kind: hc.Kind, s: hc.Settings, nominal: Params) -> None:
        self.m = CModel(float32)
        ffi = self.m.ffi
        self.kind = kind
        self.cfg = ffi.new(f"wmr_{kind}_config_t *")
        fields = {name for name, _ in ffi.typeof(f"wmr_{kind}_config_t").fields}
        from runtime import cbuild

        cbuild.fill_params(self.cfg.nominal, {k: nominal[k] for k in hw.PARAM_KEYS})
        self.cfg.formulation = 0 if s.formulation == "paper" else 1
        for i in range(5):
            self.cfg.k1[i] = float(np.asarray(s.k1)[i])
            self.cfg.k2[i] = float(np.asarray(s.k2)[i])
        values: dict[str, float | int] = {
            "q_pos": s.q_pos, "q_vel": s.q_vel, "h": s.h, "tau_max": s.tau_max,
            "accel_estimator": ACCEL_CODES[s.accel], "rate_window": s.rate_window,
            "eps": s.eps, "n": s.n,
            "a": s.a, "alpha": s.alpha, "phi": s.phi, "gamma": s.gamma, "gain0": s.gain0,
        }  # fmt: skip
        for key, value in values.items():
            if key in fields:
                setattr(self.cfg, key, value)
        self.state = ffi.new(f"wmr_{kind}_state_t *")
        self.state_fields = {name for name, _ in ffi.typeof(f"wmr_{kind}_state_t").fields}
        status = getattr(self.m.c, f"wmr_{kind}_init")(self.state, self.cfg)
        if status != 0:
            raise RuntimeError(f"wmr_{kind}_init returned {status}")
        self.tau = ffi.new("wmr_real_t[2]")

    def step(self, q: Arr, qdot: Arr, qd: Arr, qdd: Arr, qddd: Arr) -> int:
        a = self.m.arr
        fn = getattr(self.m.c, f"wmr_{self.kind}_step")
        status: int = fn(self.state, self.cfg, a(q), a(qdot), a(qd), a(qdd), a(qddd), self.tau)
        if status < 0:
            raise RuntimeError(f"wmr_{self.kind}_step returned {status}")
        return status

    def record(self, trace: Trace, status: int) -> None:
        st, rd = self.state, self.m.read
        trace.record(
            rd(st.tau, 2), st.gain, st.s_norm, rd(st.H1hat, 5), st.u_discarded, status == 1
        )

    def load(self, hist: hc.History, p12: Arr, p22: Arr) -> None:
        """Overwrite the C state with a (float32-representable) reference history."""
        st = self.state
        st.steps = hist.steps
        for i in range(5):
            st.p12[i], st.p22[i] = float(p12[i]), float(p22[i])
            st.q_prev[i], st.qdot_prev[i] = float(hist.q_prev[i]), float(hist.qdot_prev[i])
            st.qdot_prev2[i], st.u_prev[i] = float(hist.qdot_prev2[i]), float(hist.u_prev[i])
            st.u_prev2[i] = float(hist.u_prev2[i])
            st.H1hat[i] = float(hist.H1hat[i])
        if "omega" in self.state_fields:
            for i in range(hc.MAX_WINDOW + 1):
                for j in range(5):
                    st.omega[i][j] = float(hist.omega[i, j])
            st.omega_count = hist.omega_count
        st.gain, st.s_norm, st.u_discarded = hist.gain, hist.s_norm, hist.u_discarded
        st.tau[0], st.tau[1] = float(hist.tau[0]), float(hist.tau[1])


def c_run(seq: Sequence_, kind: hc.Kind, nominal: Params) -> Trace:
    ctrl = CController(False, kind, seq.settings, nominal)
    trace = Trace()
    for k in range(len(seq.q)):
        status = ctrl.step(seq.q[k], seq.qdot[k], seq.q_des[k], seq.qdot_des[k], seq.qddot_des[k])
        ctrl.record(trace, status)
    return trace


def rounded_history(h: hc.History) -> hc.History:
    return hc.History(
        steps=h.steps, q_prev=f32(h.q_prev), qdot_prev=f32(h.qdot_prev),
        qdot_prev2=f32(h.qdot_prev2), u_prev=f32(h.u_prev), u_prev2=f32(h.u_prev2),
        omega=f32(h.omega),
        omega_count=h.omega_count, H1hat=f32(h.H1hat), gain=f32(h.gain),
        s_norm=f32(h.s_norm), u_discarded=f32(h.u_discarded), tau=f32(h.tau),
    )  # fmt: skip


def rounded_settings(s: hc.Settings, nominal: Params) -> hc.Settings:
    return hc.Settings(
        nominal=f32_params(nominal), formulation=s.formulation, k1=f32(s.k1), k2=f32(s.k2),
        q_pos=f32(s.q_pos), q_vel=f32(s.q_vel), h=f32(s.h), tau_max=f32(s.tau_max),
        accel=s.accel, rate_window=f32(s.rate_window), eps=f32(s.eps), n=s.n, a=f32(s.a),
        alpha=f32(s.alpha), phi=f32(s.phi),
        gamma=f32(s.gamma), gain0=f32(s.gain0),
    )  # fmt: skip


def c32_synced_run(
    seq: Sequence_, kind: hc.Kind, perturb: Mapping[str, Mapping[str, float]]
) -> tuple[Trace, Trace]:
    """float32 C per step from the reference's state, on identical (float32) inputs.

    Returns (float32 trace, reference trace on the same rounded inputs and states)."""
    s32 = rounded_settings(seq.settings, dict(seq.settings.nominal))
    ref = hc.Controller(kind, s32)
    ref.p12, ref.p22 = f32(ref.p12), f32(ref.p22)
    c32 = CController(True, kind, s32, perturbed(dict(s32.nominal), "c32", perturb))
    got, want = Trace(), Trace()
    for k in range(len(seq.q)):
        ref.history = rounded_history(ref.history)
        c32.load(ref.history, ref.p12, ref.p22)
        args = [f32(x[k]) for x in (seq.q, seq.qdot, seq.q_des, seq.qdot_des, seq.qddot_des)]
        status = c32.step(*args)
        c32.record(got, status)
        ref.step(*args)
        hs = ref.history
        want.record(hs.tau, hs.gain, hs.s_norm, hs.H1hat, hs.u_discarded, ref.saturated)
    return got, want


def casadi_kernels(
    seq: Sequence_, kind: hc.Kind, records: list[hc.StepRecord], nominal: Params
) -> Deviation:
    """The CasADi law kernels on the inputs the reference used, step by step."""
    form = seq.settings.formulation
    pv = pvec(nominal)
    dev = Deviation()
    got: dict[str, list[Any]] = {}
    want: dict[str, list[Any]] = {}

    def add(name: str, g: Any, w: Any) -> None:
        got.setdefault(name, []).append(g)
        want.setdefault(name, []).append(w)

    s = seq.settings
    for rec in records:
        if rec.tde_inputs is not None:
            q_prev, u_prev, now, then, span = rec.tde_inputs
            add(
                "tde",
                casadi_call(f"{form}_tde", pv, q_prev, u_prev, now, then, [span])[0],
                rec.H1hat,
            )
        if rec.window is not None:
            om, w, minv_norm = rec.window
            if casadi_function(f"{form}_tdroc_gain").name_in(0) == "minv_norm":
                add("minv_norm", casadi_call(f"{form}_minv_norm", pv)[0], [minv_norm])
                gain = casadi_call(f"{form}_tdroc_gain", [minv_norm], om.ravel(), w)[0]
            else:  # older signature: (p, q, omega, w)
                gain = casadi_call(f"{form}_tdroc_gain", pv, rec.q, om.ravel(), w)[0]
            add("tdroc_gain", gain, [rec.gain_in])
        common = (rec.e, rec.edot, rec.qdd_des, rec.k1, rec.k2, rec.p12, rec.p22)
        if kind == "tdc":
            out = casadi_call(f"{form}_tdc_law", pv, rec.q, *common, rec.H1hat)
            add("u", out[0], rec.u)
        elif kind == "tdroc":
            out = casadi_call(
                f"{form}_tdroc_law", pv, rec.q, *common, rec.H1hat, [rec.gain_in], [s.eps]
            )
            add("u", out[0], rec.u)
            add("s", out[1], rec.s)
            add("|s|", out[2], [rec.s_norm])
        elif kind == "roc":
            out = casadi_call(
                f"{form}_roc_law", pv, rec.q, rec.qdot, *common, [s.alpha, s.phi], [s.eps]
            )
            add("u", out[0], rec.u)
            add("|s|", out[2], [rec.s_norm])
            add("gain", out[3], [rec.gain_out])
        else:
            out = casadi_call(
                f"{form}_asmc_law",
                pv,
                rec.q,
                rec.qdot,
                *common,
                [rec.gain_in],
                [s.eps],
                [s.gamma, s.h],
            )
            add("u", out[0], rec.u)
            add("|s|", out[2], [rec.s_norm])
            add("gain", out[3], [rec.gain_out])
    # P of (20): the Lyapunov kernel for every coordinate.
    k1, k2 = np.asarray(s.k1), np.asarray(s.k2)
    for i in range(5):
        add("lyapunov_p", casadi_call("lyapunov_p", [k1[i], k2[i], s.q_pos, s.q_vel])[0][1:],
            hc.lyapunov_p(k1[i], k2[i], s.q_pos, s.q_vel)[1:])  # fmt: skip
    for name in got:
        dev.add(name, got[name], want[name])
    return dev


def check_controllers(
    sequences: list[tuple[hc.Kind, Sequence_]], perturb: Mapping[str, Mapping[str, float]]
) -> tuple[list[Row], dict[str, int]]:
    """Rows of the controller table, and how often each branch of the step was exercised."""
    rows: dict[str, Row] = {}
    cover = dict.fromkeys(
        ("steps", "saturated", "inside boundary layer", "outside boundary layer",
         "TDE active", "central estimator", "matched estimator",
         "window full (n Ω differences)"), 0
    )  # fmt: skip
    for kind, seq in sequences:
        form = seq.settings.formulation
        nc = 5 if form == "paper" else 2
        row = rows.setdefault(f"{kind}/{form}", Row(f"{kind}/{form}"))
        nominal = dict(seq.settings.nominal)
        ref, records = hand_run(seq, kind)
        s = seq.settings
        for rec in records:
            cover["steps"] += 1
            cover["saturated"] += rec.saturated
            if kind != "tdc":
                cover["inside boundary layer"] += rec.s_norm < s.eps
                cover["outside boundary layer"] += rec.s_norm >= s.eps
            cover["TDE active"] += rec.tde_inputs is not None
            cover["central estimator"] += rec.tde_inputs is not None and s.accel == "central"
            cover["matched estimator"] += rec.tde_inputs is not None and s.accel == "matched"
            cover["window full (n Ω differences)"] += (
                rec.window is not None and int(np.count_nonzero(rec.window[1])) == s.n
            )
        cells = {impl: row.cells.setdefault(impl, Deviation()) for impl in IMPLS}
        compare_traces(
            cells["python"],
            python_run(seq, kind, perturbed(nominal, "python", perturb)),
            ref,
            nc,
            True,
        )
        compare_traces(
            cells["c64"], c_run(seq, kind, perturbed(nominal, "c64", perturb)), ref, nc, True
        )
        kd = casadi_kernels(seq, kind, records, perturbed(nominal, "casadi", perturb))
        cells["casadi"].merge(kd.value, kd.worst)
        got32, want32 = c32_synced_run(seq, kind, perturb)
        compare_traces(cells["c32"], got32, want32, nc, False)
    return list(rows.values()), cover


# ============================================================================ report


def tolerance(impl: str) -> float:
    return FLOAT32_TOL if impl == "c32" else DOUBLE_TOL


def table(title: str, rows: list[Row], width: int = 28) -> tuple[str, int]:
    """The deviation table; each cell is the largest deviation and the quantity where it
    occurs; cells above tolerance are marked FAIL."""
    cw = 24
    lines = [title, f"{'':{width}}" + "".join(f"{IMPL_TITLES[i]:<{cw}}" for i in IMPLS)]
    failures = 0
    for row in rows:
        cells = []
        for impl in IMPLS:
            dev = row.cells[impl]
            ok = dev.value <= tolerance(impl)
            failures += not ok
            worst = dev.worst if dev.worst != row.name and len(dev.worst) <= 10 else ""
            text = f"{dev.value:8.1e} {worst:<8}{'' if ok else ' FAIL'}"
            cells.append(f"{text:<{cw}}")
        lines.append((f"{row.name:{width}}" + "".join(cells)).rstrip())
    return "\n".join(lines), failures


def parse_perturb(items: Sequence[str]) -> dict[str, dict[str, float]]:
    out: dict[str, dict[str, float]] = {}
    for item in items:
        try:
            impl, rest = item.split(":", 1)
            key, factor = rest.split("=", 1)
        except ValueError:
            raise SystemExit(f"--perturb {item!r}: expected IMPL:KEY=FACTOR") from None
        if impl not in IMPLS or key not in hw.PARAM_KEYS:
            raise SystemExit(f"--perturb {item!r}: IMPL in {IMPLS}, KEY in {hw.PARAM_KEYS}")
        out.setdefault(impl, {})[key] = float(factor)
    return out


@dataclass
class Report:
    """Everything the crosscheck measured."""

    checks: list[tuple[str, float, bool]]
    model_rows: list[Row]
    ctrl_rows: list[Row]
    cover: dict[str, int]
    n_samples: int
    n_sequences: int
    n_steps: int
    seconds: float
    perturb: dict[str, dict[str, float]]

    def failing(self) -> set[tuple[str, str]]:
        """(row, implementation) pairs above tolerance; ("self", name) for derivation checks."""
        bad = {("self", n) for n, v, gated in self.checks if gated and not v <= DOUBLE_TOL}
        for row in (*self.model_rows, *self.ctrl_rows):
            bad |= {(row.name, i) for i, d in row.cells.items() if not d.value <= tolerance(i)}
        return bad

    def render(self) -> str:
        out = ["Hand-written equations: derivation checks (max relative deviation)"]
        for name, value, gated in self.checks:
            bad = gated and not value <= DOUBLE_TOL
            out.append(f"  {name:64} {value:9.2e}{' FAIL' if bad else ''}")
        text, _ = table(
            f"\nModel functions vs hand-written ({self.n_samples} random samples, "
            "parameters ±30 %)",
            self.model_rows,
        )
        out.append(text)
        text, _ = table(
            f"\nController steps vs hand-written ({self.n_sequences} sequences, {self.n_steps} "
            "steps: closed loop + random near/far; quantities τ, gain, ‖s‖, Ĥ1, ‖u₁₋₃‖; "
            "CasADi: TDE, ‖M̂⁻¹‖, TDROC gain, law and Lyapunov kernels)",
            self.ctrl_rows,
        )
        out.append(text)
        out.append("Steps per branch: " + ", ".join(f"{k} {v}" for k, v in self.cover.items()))
        out.append(
            f"\nTolerance: {DOUBLE_TOL:.0e} relative for double implementations, "
            f"{FLOAT32_TOL:.0e} for float32 (per step, identical float32 inputs and state)."
        )
        if self.perturb:
            out.append(f"Perturbed parameters: {self.perturb}")
        n = len(self.failing())
        verdict = "FAILED" if n else "PASSED"
        out.append(f"{verdict}: {n} deviation(s) above tolerance; {self.seconds:.1f} s")
        return "\n".join(out)


def crosscheck(
    seed: int = 20170316, quick: bool = False, perturb: dict[str, dict[str, float]] | None = None
) -> Report:
    """Run every comparison; ``quick``: fewer samples and shorter sequences."""
    perturb = perturb or {}
    t0 = time.perf_counter()
    rng = np.random.default_rng(seed)
    n_samples = 40 if quick else 200
    loop_seconds, rand_steps = (3.0, 15) if quick else (6.0, 40)
    samples = model_samples(rng, n_samples)
    checks = self_checks(samples)
    model_rows = check_models(samples, perturb)
    sequences: list[tuple[hc.Kind, Sequence_]] = []
    for kind in hc.KINDS:
        for form in hc.FORMULATIONS:
            sequences.append((kind, closed_loop(kind, form, loop_seconds)))
            for near in (True, False):
                sequences.append((kind, random_sequence(rng, kind, form, near, rand_steps)))
    ctrl_rows, cover = check_controllers(sequences, perturb)
    return Report(
        checks, model_rows, ctrl_rows, cover, n_samples, len(sequences),
        sum(len(s.q) for _, s in sequences), time.perf_counter() - t0, perturb,
    )  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m runtime crosscheck",
        description="Compare the generated Python, C (double, float32) and CasADi code with "
        "the hand-written equations (runtime/handwritten).",
    )
    parser.add_argument("--seed", type=int, default=20170316)
    parser.add_argument("--quick", action="store_true", help="fewer samples and shorter runs")
    parser.add_argument(
        "--perturb", action="append", default=[], metavar="IMPL:KEY=FACTOR",
        help="scale parameter KEY passed to IMPL (python, c64, c32, casadi); the check must fail",
    )  # fmt: skip
    args = parser.parse_args(argv)
    report = crosscheck(args.seed, args.quick, parse_perturb(args.perturb))
    print(report.render())
    return 1 if report.failing() else 0


if __name__ == "__main__":
    sys.exit(main())
