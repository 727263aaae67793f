"""The sampled closed loop of the paper's robot, linearised: the pencil J(g) = J0 + g J1.

(The analysis command built on it is :mod:`runtime.stability.analysis`; the configuration
check that refuses an unstable loop, :func:`check_sampled_loop`, is here so that the
simulator can use it without importing the analysis, which simulates.) Written for the
paper's differential drive (five coordinates q = (x_c, y_c, θ, θ_r, θ_l): Drishti and every
``[lumped]``/``[physical]`` robot, :func:`covers`) and the controllers whose law is (18)
with a time-delay or model estimate (those with K1, K2 fields: TDC, TDROC, ROC, ASMC).

The closed loop that runs on a robot is a discrete-time system: the plant under zero-order
hold over h, the sensing model (``[sensing]`` of the experiment), the estimator of (17)
and the control law, with memory (the encoder angles and odometry pose of the last sample,
q(t − h), q̇(t − h), q̇(t − 2h), u(t − h), u(t − 2h)). This module builds that one-sample
map from the generated model and laws and the simulator's RK4 plant
(:mod:`runtime.sim.plant`) and linearises it about the experiment's circle
(:mod:`runtime.sim.paths`: a relative equilibrium, constant wheel rates); stability is
read off its spectral radius.

Inside the boundary layer (‖s‖ < ε) every controller is the same linear law

    u = M̂ (q̈_d + K1 e + K2 ė + g s) + Ĥ,     s = Bᵀ P e  (the (22), (24)/(25) form),

with Ĥ the time-delay estimate (17) (TDC, TDROC) or the nominal model Ĥ(q, q̇) (ROC,
ASMC), and g the boundary-layer gain: 0 for TDC, k̂/ε for TDROC and ASMC, ρ/ε for ROC.
So the linearised map is J(g) = J₀ + g J₁ exactly (s = 0 on the reference), and the
largest g with spectral radius below 1 — ``max_stable_gain`` — is found by bisection on
that pencil. For TDROC, k̂ measured in closed loop then gives the predicted stable range of
ε: ε > k̂ / g_max.

Frame: the circle is invariant under rotation, so the Jacobian of step k is conjugated into
the reference's heading frame (planar components of every q-space quantity rotated by
−θ_d(t_k)); there it is the same for every k. States the controller never reads (the true
pose: it sees odometry) are outputs, not loop states, and are left out of the spectrum.

Conditions a verdict holds for (all stated in ``Analysis``): the robot's nominal parameters
for the plant unless ``plant="payload"`` (robot plus the experiment's fixed and extra
payload, the heaviest case), no friction, no quantisation (it adds noise, not dynamics),
the experiment's h, gains, sensing and estimator, and the wheel rates of the operating
point :data:`OPERATING_CIRCLE`: the paper's circle (R1 = 1.5 m at 0.25 rad/s) for every
robot, unscaled, the point every published verdict was computed at (scaling it with the
experiment belongs to the any-robot stability analysis).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, replace
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from runtime.bindings import cbuild
from runtime.bindings.generated import ControllerInfo, RobotCode
from runtime.bindings.robots import code_in
from runtime.bindings.uncertainty import roc_bounds
from runtime.experiment.settings import Experiment, PathSettings
from runtime.sim import paths
from runtime.sim.payload import plant_params_at
from runtime.sim.plant import library_for

Vec = NDArray[np.float64]
FORMULATIONS = ("paper", "minimal")
ANALYSIS_TIME = 10.0  # s: a sample of the circle well after its start-up ramp
# The circle linearised about (radius, angular rate): the paper's, for every robot.
OPERATING_CIRCLE = (PathSettings().circle_radius, PathSettings().circle_rate)
GAIN_CEILING = 1.0e4  # largest boundary-layer gain searched
# Loop memory: (name, size, kind). kind "q": a q-space vector (rows 0, 1 planar), "pose":
# (x, y, θ), "wheel": wheel-space; the frame change rotates the planar rows.
LAYOUT: tuple[tuple[str, int, str], ...] = (
    ("plant_q", 5, "q"),
    ("plant_eta", 2, "wheel"),
    ("odo_pose", 3, "pose"),
    ("odo_angles", 2, "wheel"),
    ("window_start", 2, "wheel"),
    ("q_prev", 5, "q"),
    ("qdot_prev", 5, "q"),
    ("qdot_prev2", 5, "q"),
    ("u_prev", 5, "q"),
    ("u_prev2", 5, "q"),
)
TRUE_POSE = (0, 1, 2)  # plant_q rows x, y, θ: read by nobody in the loop


def _slices() -> dict[str, slice]:
    out, i = {}, 0
    for name, size, _ in LAYOUT:
        out[name] = slice(i, i + size)
        i += size
    return out


SLICES = _slices()
DIM = sum(size for _, size, _ in LAYOUT)


def frame_rotation(theta: float) -> NDArray[np.float64]:
    """T(θ): rotates the planar rows of every q-space block of the loop state by −θ."""
    c, s = math.cos(theta), math.sin(theta)
    t = np.eye(DIM)
    for name, _, kind in LAYOUT:
        if kind in ("q", "pose"):
            i = SLICES[name].start
            t[i : i + 2, i : i + 2] = [[c, s], [-s, c]]
    return t


@dataclass(frozen=True)
class LoopSetting:
    """What one linearisation depends on."""

    code_folder: str  # the robot's generated code (python/, c/)
    tde: bool  # Ĥ from (17) (TDC, TDROC) or from the nominal model (ROC, ASMC)
    formulation: str
    nominal: tuple[tuple[str, float], ...]  # the controllers' model
    plant: tuple[tuple[str, float], ...]  # the simulated robot (with K_lat)
    h: float
    substeps: int
    k1: tuple[float, ...]  # diagonal of K1 over the five coordinates of (14)
    k2: tuple[float, ...]
    q_pos: float
    q_vel: float
    velocity: str
    rate_window: float
    estimator: str
    circle_radius: float  # the circle linearised about (the experiment's, scaled)
    circle_rate: float


def covers(code: RobotCode) -> bool:
    """Whether the analysis is written for this robot's code: the paper's differential
    drive (five coordinates, the paper formulation generated)."""
    return code.nq == 5 and code.nu == 2 and "paper" in code.formulations


def analysed(info: ControllerInfo) -> bool:
    """Whether the analysis models this controller's law: (18) with K1 and K2, a switching
    term inside its boundary layer and Ĥ from (17) or the nominal model."""
    return {"k1", "k2"} <= set(info.field_names())


def double_library(code: RobotCode) -> cbuild.CLibrary:
    """The simulator's plant in double precision."""
    return library_for(code, False)


class ClosedLoop:
    """The one-sample map z_k ↦ z_{k+1} of the sampled closed loop (no quantisation,
    no saturation, no friction), in the global frame, about the circle reference."""

    def __init__(self, s: LoopSetting) -> None:
        self.s = s
        self.code = code = code_in(Path(s.code_folder))
        self.model, self.laws = code.model, code.laws
        self.nom = dict(s.nominal)
        self.plant = dict(s.plant)
        self.paper = s.formulation == "paper"
        self.sl = slice(0, 5) if self.paper else slice(3, 5)
        self.lib = double_library(code)
        ffi, pre = self.lib.ffi, code.prefix
        self.pp = ffi.new(f"{pre}_plant_params_t *")
        cbuild.fill_params(self.pp, self.plant, code.controllers.C_FIELD_NAMES)
        self.friction = ffi.new("sim_friction_t *", [0.0, 0.0, 0.05])
        self.x = ffi.new(f"{pre}_real_t[7]")
        self.tau = ffi.new(f"{pre}_real_t[2]")
        pm = [self.laws.lyapunov_p([a, b, s.q_pos, s.q_vel]) for a, b in zip(s.k1, s.k2,
                                                                             strict=True)]
        self.p12 = np.array([p[1] for p in pm])
        self.p22 = np.array([p[2] for p in pm])
        exp = Experiment()
        exp = replace(exp, controller=replace(exp.controller, h=s.h),
                      paths=replace(PathSettings(), circle_radius=s.circle_radius,
                                    circle_rate=s.circle_rate,
                                    circle_duration=ANALYSIS_TIME + 20 * s.h))
        self.ref = paths.circle(code, dict(self.nom), exp)
        self.k = round(ANALYSIS_TIME / s.h)

    # -- one sample ------------------------------------------------------------------
    def measure(self, z: Vec) -> tuple[Vec, Vec, Vec, Vec]:
        """(q, q̇) as the controller sees them, the new odometry pose and encoder angles."""
        s, v = self.s, self.s.velocity
        angles = z[SLICES["plant_q"]][3:5]
        delta = angles - z[SLICES["odo_angles"]]
        pose = z[SLICES["odo_pose"]]
        p = self.nom
        mid = np.array([pose[0], pose[1], pose[2] + p["r"] * (delta[0] - delta[1]) / p["b"] / 2])
        pose = pose + self.model.kinematics(np.array([*mid, 0.0, 0.0]), delta, p)[:3]
        if v == "sample-instant":
            rates = z[SLICES["plant_eta"]].copy()
        elif v == "encoder-average":
            rates = delta / s.h
        else:
            rates = (angles - z[SLICES["window_start"]]) / s.rate_window
        q = np.concatenate([pose, angles])
        qdot = np.concatenate([self.model.kinematics(q, rates, p), rates])
        return q, qdot, pose, angles

    def estimate(self, z: Vec, q: Vec, qdot: Vec) -> Vec:
        """Ĥ of the law: (17) with the configured estimator, or the nominal model."""
        s, sl, p = self.s, self.sl, self.nom
        if s.estimator == "model":
            if self.paper:
                return np.asarray(self.model.bias_forces(q, qdot, p))
            return np.asarray(self.model.minimal_bias_forces(q, qdot[3:5], p))
        central = s.estimator == "central"
        c2 = s.rate_window / (2 * s.h) if s.estimator == "matched" else 0.0
        up = (1 - c2) * z[SLICES["u_prev"]] + c2 * z[SLICES["u_prev2"]]
        then = z[SLICES["qdot_prev2" if central else "qdot_prev"]]
        span = 2 * s.h if central else s.h
        tde = self.laws.paper_tde if self.paper else self.laws.minimal_tde
        return np.asarray(tde(z[SLICES["q_prev"]], up[sl], qdot[sl], then[sl], [span], p))

    def law(self, q: Vec, qdot: Vec, k: int, h1: Vec, gain: float) -> Vec:
        """u = M̂ (q̈_d + K1 e + K2 ė + g s) + Ĥ: the TDROC kernel inside its boundary layer
        (ε = 1 ≫ ‖s‖ of a linearisation), which is every controller's law there."""
        sl, ref = self.sl, self.ref
        e, edot = ref.q[k, sl] - q[sl], ref.qdot[k, sl] - qdot[sl]
        fn = self.laws.paper_tdroc_law if self.paper else self.laws.minimal_tdroc_law
        u, _, s_norm = fn(
            q, e, edot, ref.qddot[k, sl], list(self.s.k1[sl]), list(self.s.k2[sl]),
            self.p12[sl], self.p22[sl], h1, [gain], [1.0], self.nom,
        )  # fmt: skip
        if not s_norm[0] < 1.0:
            raise ArithmeticError("linearisation left the boundary layer")
        return np.asarray(u)

    def step(self, z: Vec, k: int, gain: float) -> Vec:
        """z_{k+1} = F(z_k) for the sample at t_k."""
        s = self.s
        q, qdot, pose, angles = self.measure(z)
        u = self.law(q, qdot, k, self.estimate(z, q, qdot), gain)
        tau = u[3:5] if self.paper else u
        out = z.copy()
        out[SLICES["odo_pose"]] = pose
        out[SLICES["odo_angles"]] = angles
        out[SLICES["q_prev"]] = q
        out[SLICES["qdot_prev2"]] = z[SLICES["qdot_prev"]]
        out[SLICES["qdot_prev"]] = qdot
        out[SLICES["u_prev2"]] = z[SLICES["u_prev"]]
        out[SLICES["u_prev"]] = [0.0, 0.0, 0.0, tau[0], tau[1]]
        x = self.x
        x[0:5] = list(z[SLICES["plant_q"]])
        x[5:7] = list(z[SLICES["plant_eta"]])
        self.tau[0:2] = [float(tau[0]), float(tau[1])]
        dt, n_win = s.h / s.substeps, round(s.rate_window / (s.h / s.substeps))
        if s.velocity != "motor-encoder":
            n_win = 0
        adv = self.lib.lib.sim_plant_advance
        if adv(self.pp, self.friction, x, self.tau, dt, s.substeps - n_win) != 0:
            raise ArithmeticError("plant diverged during the linearisation")
        if n_win:
            out[SLICES["window_start"]] = [x[3], x[4]]
            adv(self.pp, self.friction, x, self.tau, dt, n_win)
        out[SLICES["plant_q"]] = [x[i] for i in range(5)]
        out[SLICES["plant_eta"]] = [x[5], x[6]]
        return out

    # -- operating point and Jacobian ------------------------------------------------
    def operating_point(self, k: int) -> Vec:
        """The loop state on the reference at sample k (zero error, steady wheel rates),
        with u(t − h) the torque that keeps the true plant on the circle."""
        ref, p = self.ref, self.nom
        eta = ref.qdot[k, 3:5]
        tau = np.asarray(self.model.minimal_bias_forces(ref.q[k], eta, self.plant_lumped()))
        z = np.zeros(DIM)
        z[SLICES["plant_q"]] = ref.q[k]
        z[SLICES["plant_eta"]] = eta
        z[SLICES["odo_pose"]] = ref.q[k - 1, :3]
        z[SLICES["odo_angles"]] = ref.q[k - 1, 3:5]
        z[SLICES["window_start"]] = ref.q[k, 3:5] - self.s.rate_window * eta
        z[SLICES["q_prev"]] = ref.q[k - 1]
        for name, j in (("qdot_prev", k - 1), ("qdot_prev2", k - 2)):
            z[SLICES[name]] = np.concatenate([self.model.kinematics(ref.q[j], eta, p), eta])
        z[SLICES["u_prev"]] = z[SLICES["u_prev2"]] = [0.0, 0.0, 0.0, tau[0], tau[1]]
        return z

    def plant_lumped(self) -> dict[str, float]:
        """The plant's lumped parameters for the generated model (K_lat dropped: the
        minimal bias forces of the steady circle are the operating point only)."""
        return {k: v for k, v in self.plant.items() if k != "K_lat"}

    def jacobian(self, gain: float, k: int | None = None) -> NDArray[np.float64]:
        """∂z_{k+1}/∂z_k by central differences, in the reference's heading frame."""
        k = self.k if k is None else k
        z0 = self.operating_point(k)
        jac = np.zeros((DIM, DIM))
        for i in range(DIM):
            d = 1e-6 * max(1.0, abs(z0[i]))
            zp, zm = z0.copy(), z0.copy()
            zp[i] += d
            zm[i] -= d
            jac[:, i] = (self.step(zp, k, gain) - self.step(zm, k, gain)) / (2 * d)
        th = self.ref.q
        return frame_rotation(th[k + 1, 2]) @ jac @ np.linalg.inv(frame_rotation(th[k, 2]))


def loop_states(jac: NDArray[np.float64], tol: float = 1e-9) -> list[int]:
    """The states that feed the loop: those from which a chain of nonzero Jacobian entries
    reaches the controller's output u(t − h). The rest (the true pose, which the
    controller never reads; memory the configured estimator does not use) are driven by
    the loop but do not act on it, so leaving them out does not change the loop's
    spectrum; they are marginal by nature (a pose integrates the motion)."""
    scale = max(1.0, float(np.abs(jac).max()))
    acts = np.abs(jac) > tol * scale  # acts[i, j]: state j acts on state i
    reach = set(range(SLICES["u_prev"].start, SLICES["u_prev"].stop))
    reach = {i for i in reach if acts[i].any()}
    frontier = list(reach)
    while frontier:
        i = frontier.pop()
        for j in np.flatnonzero(acts[i]):
            if int(j) not in reach:
                reach.add(int(j))
                frontier.append(int(j))
    return sorted(reach)


NEUTRAL_TOL = 1e-6


def neutral_count(eigs: NDArray[Any]) -> int:
    return int(np.count_nonzero(np.abs(eigs - 1.0) < NEUTRAL_TOL))


@dataclass(frozen=True)
class Pencil:
    """J(g) = J0 + g J1 restricted to the loop states. ``neutral``: eigenvalues at exactly
    1 for every gain — error directions the law does not act on and the plant does not
    move (the paper formulation's τ = Bᵀu ignores a combination of pose and wheel-angle
    error): a constant offset, neither decaying nor growing, reported apart."""

    j0: NDArray[np.float64]
    j1: NDArray[np.float64]
    states: tuple[int, ...]
    neutral: int

    def eigenvalues(self, gain: float) -> NDArray[np.complex128]:
        """The loop's eigenvalues at gain g, the neutral ones removed."""
        eigs = np.linalg.eigvals(self.j0 + gain * self.j1)
        order = np.argsort(np.abs(eigs - 1.0))
        return np.asarray(eigs[np.sort(order[self.neutral :])])

    def radius(self, gain: float) -> float:
        return float(np.abs(self.eigenvalues(gain)).max())

    def max_stable_gain(self) -> float:
        """Largest g such that every g' in [0, g] gives a spectral radius below 1 (0 if the
        loop is unstable without any switching gain; inf if stable up to GAIN_CEILING)."""
        if self.radius(0.0) >= 1.0:
            return 0.0
        grid = np.geomspace(1e-3, GAIN_CEILING, 241)
        lo = 0.0
        for g in grid:
            if self.radius(float(g)) >= 1.0:
                hi = float(g)
                for _ in range(40):
                    mid = 0.5 * (lo + hi)
                    lo, hi = (mid, hi) if self.radius(mid) < 1.0 else (lo, mid)
                return lo
            lo = float(g)
        return math.inf


@cache
def pencil(s: LoopSetting) -> Pencil:
    loop = ClosedLoop(s)
    j0 = loop.jacobian(0.0)
    j1 = loop.jacobian(1.0) - j0
    states = loop_states(j0 + j1)
    ix = np.ix_(states, states)
    neutral = min(neutral_count(np.linalg.eigvals(j0[ix] + g * j1[ix])) for g in (0.0, 1.0, 10.0))
    return Pencil(j0[ix], j1[ix], tuple(states), neutral)


def plant_parameters(code: RobotCode, robot: dict[str, float], exp: Experiment,
                     plant: str) -> dict[str, float]:
    """The analysed robot: the nominal one (plant-only parameters at their defaults, e.g.
    K_lat = 0), or with the experiment's heaviest payload."""
    base = {**code.plant_defaults, **robot}
    if plant == "nominal":
        return base
    if plant != "payload":
        raise ValueError(f"plant must be 'nominal' or 'payload', got {plant!r}")
    t = exp.plant.extra_on_at
    assert exp.plant.extra_on(t)
    return plant_params_at(code, exp, t, base)


def setting(
    code: RobotCode,
    controller: str,
    formulation: str,
    robot: dict[str, float],
    exp: Experiment,
    plant: str = "nominal",
) -> LoopSetting:
    """What the linearisation of ``controller`` in ``formulation`` on the robot whose code
    is ``code`` and parameters ``robot`` depends on, at the experiment's setting."""
    if not covers(code):
        raise ValueError(f"robot '{code.name}': the sampled-loop analysis is written for the "
                         "paper's differential drive (a [lumped] or [physical] robot file)")
    info = code.controller(controller)
    if not analysed(info):
        raise ValueError(f"{controller}: the sampled-loop analysis models the laws of (18) "
                         "(controllers with K1, K2); not this one")
    if formulation not in FORMULATIONS:
        raise ValueError(f"formulation must be 'paper' or 'minimal', got {formulation!r}")
    c, sen = exp.controller, exp.sensing
    return LoopSetting(
        code_folder=str(code.folder.resolve()),
        tde=info.tde,
        formulation=formulation,
        nominal=tuple(sorted((k, float(v)) for k, v in robot.items())),
        plant=tuple(sorted(plant_parameters(code, robot, exp, plant).items())),
        h=c.h,
        substeps=exp.plant.substeps,
        k1=(float(c.k1),) * 5,
        k2=(float(c.k2),) * 5,
        q_pos=c.q_pos,
        q_vel=c.q_vel,
        velocity=sen.velocity,
        rate_window=sen.rate_window(c.h),
        estimator=sen.accel_estimator if info.tde else "model",
        circle_radius=OPERATING_CIRCLE[0],
        circle_rate=OPERATING_CIRCLE[1],
    )


def on_operating_circle(exp: Experiment) -> Experiment:
    """``exp`` with its circle at the analysis' operating point (:data:`OPERATING_CIRCLE`),
    for the closed-loop runs that measure k̂ there."""
    radius, rate = OPERATING_CIRCLE
    return replace(exp, paths=replace(exp.paths, circle_radius=radius, circle_rate=rate))


def roc_gain(code: RobotCode, formulation: str, robot: dict[str, float],
             exp: Experiment) -> float:
    """ROC's boundary-layer gain at zero error, ρ/ε, with ρ = φ/(1 − α) (q̈_d = 0 on the
    wheels) and (α, φ) of :func:`runtime.bindings.uncertainty.roc_bounds`."""
    alpha, phi = roc_bounds(code, robot, exp.controller.uncertainty, formulation,
                            exp.controller.roc_max_rate)
    if not alpha < 1.0:  # ρ = φ/(1 − α) exists only for α < 1; ROC's init refuses the rest
        raise ValueError(f"ROC needs alpha < 1 over the uncertainty box, got {alpha:.3g}")
    return phi / (1 - alpha) / exp.controller.eps


class UnstableConfiguration(ValueError):
    """The sampled closed loop of a configuration is predicted unstable on its robot."""


class SwitchingGainWarning(UserWarning):
    """A switching gain at the configuration's setting exceeds the stable boundary-layer gain."""


def check_sampled_loop(code: RobotCode, name: str, formulation: str,
                       nominal: dict[str, float], exp: Experiment) -> None:
    """Refuse a configuration whose sampled closed loop (:mod:`runtime.stability.analysis`:
    plant under ZOH, the experiment's sensing and estimator, the law, linearised on the
    circle) is unstable without any switching gain; warn when ROC's gain at zero error (ρ/ε)
    is beyond the largest stable boundary-layer gain."""
    pen = pencil(setting(code, name, formulation, nominal, exp))
    radius = pen.radius(0.0)
    if radius >= 1.0:
        other = "minimal" if formulation == "paper" else "paper"
        alt = pencil(setting(code, name, other, nominal, exp)).radius(0.0)
        hint = (
            f"; the {other} formulation is predicted stable (spectral radius {alt:.3f})"
            if alt < 1.0
            else f"; the {other} formulation is unstable too (spectral radius {alt:.3f})"
        )
        raise UnstableConfiguration(
            f"{name}/{formulation}: the sampled closed loop is predicted unstable on this "
            f"robot (spectral radius {radius:.3f} >= 1 per sample of h = {exp.controller.h} s "
            f"with {exp.sensing.velocity} rates, before any switching gain){hint}. "
            "See `wmr stability` and docs/CONTROLLERS.md."
        )
    if code.controller(name).bounds:
        g = roc_gain(code, formulation, nominal, exp)
        g_max = pen.max_stable_gain()
        if g >= g_max:
            warnings.warn(
                f"roc/{formulation}: the switching gain at zero error rho/eps = {g:.3g} is "
                f"beyond the largest stable boundary-layer gain {g_max:.3g}: expect "
                "chattering or divergence inside the boundary layer (raise eps)",
                SwitchingGainWarning,
                stacklevel=2,
            )
