"""The sampled closed loop of any generated robot, linearised: the pencil J(g) = J0 + g J1.

(The analysis command built on it is :mod:`runtime.stability.analysis`; the configuration
check that refuses an unstable loop, :func:`check_sampled_loop`, is here so that the
simulator can use it without importing the analysis, which simulates.) Any robot the
toolchain generates: n coordinates q whose first three are the root's pose (x, y, θ), m
driven wheels (``ACTUATED``), every other coordinate (a hitch angle, a caster's swivel,
passive wheels) measured by odometry; every controller of the registry whose law is (18)
(K1, K2 fields: TDC, TDROC, ROC, ASMC) and the wheel-velocity PI, in every formulation the
robot's code has.

The closed loop that runs on a robot is a discrete-time system: the plant under zero-order
hold over h, the sensing model (``[sensing]`` of the experiment), the odometry, the
estimator of (17) and the control law, with memory (the encoder angles and odometry of the
last sample, q(t − h), q̇(t − h), q̇(t − 2h), u(t − h), u(t − 2h), the PI's integral, and
the commands still in flight when the experiment states a delay). This module builds that
one-sample map from the generated model and laws and the simulator's RK4 plant
(:mod:`runtime.sim.plant`) and linearises it about a steady motion of the reference (a
relative equilibrium: constant driven-wheel rates, every shape coordinate settled);
stability is read off its spectral radius.

Inside the boundary layer (‖s‖ < ε) every controller of (18) is the same linear law

    u = M̂ (q̈_d + K1 e + K2 ė + g s) + Ĥ,     s = Bᵀ P e  (the (22), (24)/(25) form),

with Ĥ the time-delay estimate (17) (TDC, TDROC) or the nominal model Ĥ(q, q̇) (ROC,
ASMC), and g the boundary-layer gain: 0 for TDC, k̂/ε for TDROC and ASMC, ρ/ε for ROC.
So the linearised map is J(g) = J₀ + g J₁ exactly (s = 0 on the reference), and the
largest g with spectral radius below 1 — ``max_stable_gain`` — is found by bisection on
that pencil. For TDROC, k̂ measured in closed loop then gives the predicted stable range of
ε: ε > k̂ / g_max. The PI has no switching term: J₁ = 0.

Delay (``controller.delay``/``delay_time``): the torque computed at t_k reaches the wheels
at t_k + D. Over a sample the plant sees the command of D/h samples ago until the fraction
frac(D/h) of the sample, then the next one; the commands in flight are loop states (the
augmented state), so the delay is in the map exactly, including D > h.

Frame: a steady motion is invariant under rotation (a circle) or translation (a straight
leg), so the Jacobian of step k is conjugated into the reference's heading frame (the
planar components x, y of every q-space quantity rotated by −θ_d(t_k)); there it is the
same for every k. States the controller never reads (the true pose: it sees odometry) are
outputs, not loop states, and are left out of the spectrum.

Conditions a verdict holds for (all stated in ``Analysis``): the robot's nominal parameters
for the plant unless ``plant="payload"`` (robot plus the experiment's fixed and extra
payload, the heaviest case), no friction, no quantisation (it adds noise, not dynamics),
the experiment's h, gains, sensing, estimator and delay, and the operating point: the
experiment's circle (scaled to the robot as every command scales it; the paper's for
Drishti), or a lawn mower's leg or turn.
"""

from __future__ import annotations

import itertools
import math
import warnings
from dataclasses import dataclass, replace
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from runtime.bindings import cbuild
from runtime.bindings.config import ConfigInputs
from runtime.bindings.generated import ControllerInfo, RobotCode
from runtime.bindings.physical_bounds import check_physical_roc
from runtime.bindings.robots import code_in
from runtime.bindings.uncertainty import roc_bounds
from runtime.experiment.settings import Experiment
from runtime.setting.scale import robot_scale
from runtime.sim import paths
from runtime.sim.payload import plant_params_at
from runtime.sim.plant import library_for
from runtime.sim.reference import START_AT, Reference, WheelProfile, integrate

Vec = NDArray[np.float64]
FORMULATIONS = ("paper", "minimal")
ANALYSIS_TIME = 10.0  # s: the earliest sample linearised about (well after the start-up ramp)
SETTLE_LIMIT = 400.0  # s: a reference not steady by then has no steady motion to analyse
SETTLED = 1e-9  # rad/s: change of every angle's rate over a sample at a steady motion
GAIN_CEILING = 1.0e4  # largest boundary-layer gain searched
OPERATING_POINTS = ("circle", "lawnmower")  # the steady motions a path is analysed at


@dataclass(frozen=True)
class Layout:
    """The loop state of one robot and controller: (name, size, kind) blocks. kind "q": a
    q-space vector (rows 0, 1 planar), "dep": the dependent coordinates (the pose first),
    "wheel": wheel-space; the frame change rotates the planar rows."""

    blocks: tuple[tuple[str, int, str], ...]

    @property
    def slices(self) -> dict[str, slice]:
        out, i = {}, 0
        for name, size, _ in self.blocks:
            out[name] = slice(i, i + size)
            i += size
        return out

    @property
    def dim(self) -> int:
        return sum(size for _, size, _ in self.blocks)

    def names(self) -> list[str]:
        """One name per state, ``block[i]``."""
        return [f"{name}[{i}]" for name, size, _ in self.blocks for i in range(size)]

    def rotation(self, theta: float) -> NDArray[np.float64]:
        """T(θ): rotates the planar rows of every q-space block by −θ."""
        c, s = math.cos(theta), math.sin(theta)
        t = np.eye(self.dim)
        sl = self.slices
        for name, _, kind in self.blocks:
            if kind in ("q", "dep"):
                i = sl[name].start
                t[i : i + 2, i : i + 2] = [[c, s], [-s, c]]
        return t


def layout(nq: int, nu: int, integrator: bool = False, in_flight: int = 0) -> Layout:
    """The loop state for ``nq`` coordinates, ``nu`` driven wheels, a PI's integral and
    ``in_flight`` delayed commands."""
    blocks = [
        ("plant_q", nq, "q"),
        ("plant_eta", nu, "wheel"),
        ("odo_dependent", nq - nu, "dep"),
        ("odo_angles", nu, "wheel"),
        ("window_start", nu, "wheel"),
        ("q_prev", nq, "q"),
        ("qdot_prev", nq, "q"),
        ("qdot_prev2", nq, "q"),
        ("u_prev", nq, "q"),
        ("u_prev2", nq, "q"),
    ]
    if integrator:
        blocks.append(("integral", nu, "wheel"))
    blocks += [(f"in_flight{i}", nu, "wheel") for i in range(in_flight)]
    return Layout(tuple(blocks))


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
    k1: tuple[float, ...]  # diagonal of K1 over the coordinates of q
    k2: tuple[float, ...]
    q_pos: float
    q_vel: float
    velocity: str
    rate_window: float
    estimator: str
    wheel_rates: tuple[float, ...]  # the steady motion linearised about
    delay: float = 0.0  # s: command computed at t_k applied from t_k + delay
    law: str = "error"  # "error": the laws of (18); "pi": the wheel-velocity PI
    pi_gains: tuple[float, ...] = ()  # kx, ky, ktheta, kp, ki
    tau_max: float = math.inf


def covers(code: RobotCode) -> bool:
    """Whether the analysis is written for this robot's code: driven wheels, and the root's
    pose (x, y, θ) as its first three coordinates, measured by odometry."""
    return code.nu >= 1 and code.dependent[:3] == (0, 1, 2)


def analysed(info: ControllerInfo) -> bool:
    """Whether the analysis models this controller's law: (18) with K1 and K2, a switching
    term inside its boundary layer and Ĥ from (17) or the nominal model; or the PI (an
    integrator on the wheel rates under a pose tracker)."""
    return {"k1", "k2"} <= set(info.field_names()) or is_pi(info)


def is_pi(info: ControllerInfo) -> bool:
    """The wheel-velocity PI: an integrator, no error dynamics of (18)."""
    return {"kp", "ki", "kx", "ky", "ktheta"} <= set(info.field_names())


def double_library(code: RobotCode) -> cbuild.CLibrary:
    """The simulator's plant in double precision."""
    return library_for(code, False)


def delay_split(delay: float, h: float) -> tuple[int, float]:
    """(j, f): a command computed at t_k acts from t_{k+j} + f h, 0 ≤ f < 1."""
    ratio = delay / h
    j = math.floor(ratio + 1e-12)
    f = ratio - j
    return j, (0.0 if f < 1e-12 else f)


def in_flight_count(delay: float, h: float) -> int:
    """Commands computed but not yet (fully) applied at a sample instant."""
    j, f = delay_split(delay, h)
    return j + (1 if f > 0 else 0)


def steady_reference(code: RobotCode, params: dict[str, float], exp: Experiment,
                     rates: tuple[float, ...], name: str) -> tuple[Reference, int]:
    """The motion under the driven-wheel rates ``rates`` (ramped up from rest, as the paths
    start) and the first sample from :data:`ANALYSIS_TIME` at which it is steady: every
    angle's rate constant over a sample (a trailer's hitch settled)."""
    h = exp.controller.h
    duration = ANALYSIS_TIME + 20 * h
    start = np.zeros(code.nq)
    start[:2] = exp.paths.circle_radius, exp.paths.circle_radius
    tol = SETTLED * max(1.0, float(np.abs(rates).max()))
    k0 = round(ANALYSIS_TIME / h)
    while True:
        ref = integrate(code, name, WheelProfile((START_AT,), (rates,)), start, params, h,
                        duration)
        # change[i]: how much the angles' rates move from sample i to i + 1; sample k is
        # used with k - 2 .. k + 1
        change = np.abs(np.diff(ref.qdot[:, 2:], axis=0)).max(axis=1)
        for k in range(max(k0, 2), len(ref.t) - 2):
            if change[k - 2 : k + 1].max() <= tol:
                return ref, k
        if duration >= SETTLE_LIMIT:
            raise ValueError(f"robot '{code.name}': the reference at wheel rates "
                             f"{tuple(round(r, 4) for r in rates)} rad/s does not settle to a "
                             f"steady motion within {SETTLE_LIMIT:g} s (a towed body that does "
                             "not follow?); no operating point to linearise about")
        duration = min(2 * duration, SETTLE_LIMIT)


class ClosedLoop:
    """The one-sample map z_k ↦ z_{k+1} of the sampled closed loop (no quantisation,
    no saturation, no friction), in the global frame, about a steady motion."""

    def __init__(self, s: LoopSetting) -> None:
        self.s = s
        self.code = code = code_in(Path(s.code_folder))
        self.model, self.laws = code.model, code.laws
        self.nom = dict(s.nominal)
        self.plant = dict(s.plant)
        self.paper = s.formulation == "paper"
        self.act = list(code.actuated)
        self.dep = list(code.dependent)
        self.rows = list(range(code.nq)) if self.paper else self.act
        self.pi = s.law == "pi"
        self.lag, self.frac = delay_split(s.delay, s.h)
        self.layout = layout(code.nq, code.nu, self.pi, in_flight_count(s.delay, s.h))
        self.sl = self.layout.slices
        self.dim = self.layout.dim
        self.lib = double_library(code)
        ffi, pre = self.lib.ffi, code.prefix
        self.pp = ffi.new(f"{pre}_plant_params_t *")
        cbuild.fill_params(self.pp, self.plant, code.controllers.C_FIELD_NAMES)
        self.friction = ffi.new("sim_friction_t *", [0.0, 0.0, 0.05])
        self.x = ffi.new(f"{pre}_real_t[{code.nq + code.nu}]")
        self.tau = ffi.new(f"{pre}_real_t[{code.nu}]")
        pm = [self.laws.lyapunov_p([a, b, s.q_pos, s.q_vel]) for a, b in zip(s.k1, s.k2,
                                                                             strict=True)]
        self.p12 = np.array([p[1] for p in pm])
        self.p22 = np.array([p[2] for p in pm])
        exp = Experiment()
        exp = replace(exp, controller=replace(exp.controller, h=s.h))
        self.ref, self.k = steady_reference(code, self.nom, exp, s.wheel_rates, "steady")

    # -- one sample ------------------------------------------------------------------
    def measure(self, z: Vec) -> tuple[Vec, Vec]:
        """(q, q̇) as the controller sees them: the encoder angles, the dependent coordinates
        by odometry (the midpoint rule of :class:`runtime.sim.sensors.Sensors`), the rates
        by the sensing model and q̇ = S(q) η."""
        s, v, sl = self.s, self.s.velocity, self.sl
        angles = z[sl["plant_q"]][self.act]
        delta = angles - z[sl["odo_angles"]]
        q = np.empty(self.code.nq)
        q[self.dep] = z[sl["odo_dependent"]]
        q[self.act] = z[sl["odo_angles"]]
        kin, p = self.model.kinematics, self.nom
        mid = q.copy()
        mid[self.dep] = q[self.dep] + 0.5 * np.asarray(kin(q, delta, p))
        q[self.dep] = q[self.dep] + np.asarray(kin(mid, delta, p))
        q[self.act] = angles
        if v == "sample-instant":
            rates = z[sl["plant_eta"]].copy()
        elif v == "encoder-average":
            rates = delta / s.h
        else:
            rates = (angles - z[sl["window_start"]]) / s.rate_window
        return q, self.code.velocities(q, rates, p)

    def estimate(self, z: Vec, q: Vec, qdot: Vec) -> Vec:
        """Ĥ of the law: (17) with the configured estimator, or the nominal model."""
        s, rows, p, sl = self.s, self.rows, self.nom, self.sl
        if s.estimator == "model":
            if self.paper:
                return np.asarray(self.model.bias_forces(q, qdot, p))
            return np.asarray(self.model.minimal_bias_forces(q, qdot[self.act], p))
        central = s.estimator == "central"
        c2 = s.rate_window / (2 * s.h) if s.estimator == "matched" else 0.0
        up = (1 - c2) * z[sl["u_prev"]] + c2 * z[sl["u_prev2"]]
        then = z[sl["qdot_prev2" if central else "qdot_prev"]]
        span = 2 * s.h if central else s.h
        tde = self.laws.paper_tde if self.paper else self.laws.minimal_tde
        return np.asarray(tde(z[sl["q_prev"]], up[rows], qdot[rows], then[rows], [span], p))

    def law(self, z: Vec, q: Vec, qdot: Vec, k: int, gain: float) -> tuple[Vec, Vec | None]:
        """(τ, the PI's next integral). The laws of (18): u = M̂ (q̈_d + K1 e + K2 ė + g s) + Ĥ,
        the TDROC kernel inside its boundary layer (ε = 1 ≫ ‖s‖ of a linearisation), which
        is every such controller's law there; τ = Bᵀu. The PI: its generated kernel."""
        rows, ref, s = self.rows, self.ref, self.s
        if self.pi:
            u, integral = self.laws.minimal_pi_law(
                q, qdot, ref.q[k], ref.qdot[k], z[self.sl["integral"]], list(s.pi_gains),
                [s.h, s.tau_max], self.nom)
            return np.asarray(u), np.asarray(integral)
        e, edot = ref.q[k, rows] - q[rows], ref.qdot[k, rows] - qdot[rows]
        fn = self.laws.paper_tdroc_law if self.paper else self.laws.minimal_tdroc_law
        h1 = self.estimate(z, q, qdot)
        k1, k2 = np.array(s.k1)[rows], np.array(s.k2)[rows]
        u, _, s_norm = fn(q, e, edot, ref.qddot[k, rows], list(k1), list(k2),
                          self.p12[rows], self.p22[rows], h1, [gain], [1.0], self.nom)
        if not s_norm[0] < 1.0:
            raise ArithmeticError("linearisation left the boundary layer")
        u = np.asarray(u)
        return (u[self.act] if self.paper else u), None

    def step(self, z: Vec, k: int, gain: float) -> Vec:
        """z_{k+1} = F(z_k) for the sample at t_k."""
        s, sl = self.s, self.sl
        q, qdot = self.measure(z)
        tau, integral = self.law(z, q, qdot, k, gain)
        out = z.copy()
        out[sl["odo_dependent"]] = q[self.dep]
        out[sl["odo_angles"]] = q[self.act]
        out[sl["q_prev"]] = q
        out[sl["qdot_prev2"]] = z[sl["qdot_prev"]]
        out[sl["qdot_prev"]] = qdot
        out[sl["u_prev2"]] = z[sl["u_prev"]]
        u_prev = np.zeros(self.code.nq)
        u_prev[self.act] = tau
        out[sl["u_prev"]] = u_prev
        if integral is not None:
            out[sl["integral"]] = integral
        flight = [z[sl[f"in_flight{i}"]] for i in range(in_flight_count(s.delay, s.h))]
        for i, cmd in enumerate([tau, *flight[:-1]] if flight else []):
            out[sl[f"in_flight{i}"]] = cmd
        x = self.x
        nq, nu = self.code.nq, self.code.nu
        x[0:nq] = list(z[sl["plant_q"]])
        x[nq:nq + nu] = list(z[sl["plant_eta"]])
        window = s.rate_window if s.velocity == "motor-encoder" else 0.0
        if not flight:
            self._advance_held(tau, window, out)
        else:  # the command of `lag` samples ago from f h on, the one before it until then
            now = tau if self.lag == 0 else flight[self.lag - 1]
            before = flight[self.lag] if self.frac > 0 else now
            self._advance_pieces([(0.0, before), (self.frac * s.h, now)], window, out)
        out[sl["plant_q"]] = [x[i] for i in range(nq)]
        out[sl["plant_eta"]] = [x[nq + i] for i in range(nu)]
        return out

    def _advance_held(self, tau: Vec, window: float, out: Vec) -> None:
        """The plant over h under τ held, reading the motor-encoder window's start."""
        s, x = self.s, self.x
        dt = s.h / s.substeps
        n_win = round(window / dt)
        self.tau[0:self.code.nu] = [float(v) for v in tau]
        adv = self.lib.lib.sim_plant_advance
        if adv(self.pp, self.friction, x, self.tau, dt, s.substeps - n_win) != 0:
            raise ArithmeticError("plant diverged during the linearisation")
        if n_win:
            out[self.sl["window_start"]] = [x[i] for i in self.act]
            adv(self.pp, self.friction, x, self.tau, dt, n_win)

    def _advance_pieces(self, pieces: list[tuple[float, Vec]], window: float,
                        out: Vec) -> None:
        """The plant over h under piecewise-constant torques (start time, τ), each piece
        integrated in steps no longer than h / substeps, the window's start read on the
        way."""
        s, x = self.s, self.x
        marks = sorted({0.0, s.h, *(t for t, _ in pieces if 0 < t < s.h),
                        *([s.h - window] if window > 0 else [])})
        adv = self.lib.lib.sim_plant_advance
        for a, b in itertools.pairwise(marks):
            if window > 0 and abs(a - (s.h - window)) < 1e-12:
                out[self.sl["window_start"]] = [x[i] for i in self.act]
            tau = [cmd for t, cmd in pieces if t <= a + 1e-12][-1]
            self.tau[0:self.code.nu] = [float(v) for v in tau]
            n = max(1, math.ceil((b - a) / (s.h / s.substeps) - 1e-9))
            if adv(self.pp, self.friction, x, self.tau, (b - a) / n, n) != 0:
                raise ArithmeticError("plant diverged during the linearisation")

    # -- operating point and Jacobian ------------------------------------------------
    def operating_point(self, k: int) -> Vec:
        """The loop state on the reference at sample k (zero error, steady wheel rates),
        with u(t − h) the torque that keeps the true plant on the steady motion."""
        ref, p, sl, act = self.ref, self.nom, self.sl, self.act
        eta = ref.qdot[k, act]
        tau = np.asarray(self.model.minimal_bias_forces(ref.q[k], eta, self.plant_lumped()))
        z = np.zeros(self.dim)
        z[sl["plant_q"]] = ref.q[k]
        z[sl["plant_eta"]] = eta
        z[sl["odo_dependent"]] = ref.q[k - 1, self.dep]
        z[sl["odo_angles"]] = ref.q[k - 1, act]
        z[sl["window_start"]] = ref.q[k, act] - self.s.rate_window * eta
        z[sl["q_prev"]] = ref.q[k - 1]
        for name, j in (("qdot_prev", k - 1), ("qdot_prev2", k - 2)):
            z[sl[name]] = self.code.velocities(ref.q[j], eta, p)
        u = np.zeros(self.code.nq)
        u[act] = tau
        z[sl["u_prev"]] = z[sl["u_prev2"]] = u
        if self.pi:  # the integral holds the steady torque less the P term (zero error)
            z[sl["integral"]] = tau
        for i in range(in_flight_count(self.s.delay, self.s.h)):
            z[sl[f"in_flight{i}"]] = tau
        return z

    def plant_lumped(self) -> dict[str, float]:
        """The plant's parameters for the generated model (K_lat dropped: the minimal bias
        forces of the steady motion are the operating point only)."""
        return {k: v for k, v in self.plant.items() if k != "K_lat"}

    def jacobian(self, gain: float, k: int | None = None) -> NDArray[np.float64]:
        """∂z_{k+1}/∂z_k by central differences, in the reference's heading frame."""
        k = self.k if k is None else k
        z0 = self.operating_point(k)
        jac = np.zeros((self.dim, self.dim))
        for i in range(self.dim):
            d = 1e-6 * max(1.0, abs(z0[i]))
            zp, zm = z0.copy(), z0.copy()
            zp[i] += d
            zm[i] -= d
            jac[:, i] = (self.step(zp, k, gain) - self.step(zm, k, gain)) / (2 * d)
        th = self.ref.q
        rot = self.layout.rotation
        return rot(th[k + 1, 2]) @ jac @ np.linalg.inv(rot(th[k, 2]))


def loop_states(jac: NDArray[np.float64], outputs: range, tol: float = 1e-9) -> list[int]:
    """The states that feed the loop: those from which a chain of nonzero Jacobian entries
    reaches the controller's output ``outputs`` (the rows of u(t − h)). The rest (the true
    pose, which the controller never reads; memory the configured estimator does not use)
    are driven by the loop but do not act on it, so leaving them out does not change the
    loop's spectrum; they are marginal by nature (a pose integrates the motion)."""
    scale = max(1.0, float(np.abs(jac).max()))
    acts = np.abs(jac) > tol * scale  # acts[i, j]: state j acts on state i
    reach = {i for i in outputs if acts[i].any()}
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
    error; a rigid rotation of every odometric angle where the law reads a relative one):
    a constant offset, neither decaying nor growing, reported apart."""

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
        if not np.any(self.j1):
            return math.inf  # no switching term (the PI)
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
    j1 = np.zeros_like(j0) if loop.pi else loop.jacobian(1.0) - j0
    u_rows = loop.sl["u_prev"]
    states = loop_states(j0 + j1, range(u_rows.start, u_rows.stop))
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


def operating_rates(code: RobotCode, robot: dict[str, float], exp: Experiment,
                    path: str = "circle") -> list[tuple[str, tuple[float, ...]]]:
    """The steady motions a path is analysed at, as (label, driven-wheel rates): the
    circle's steady state (the experiment's circle, already scaled to the robot), or the
    lawn mower's straight leg and its two U-turns."""
    if path not in OPERATING_POINTS:
        raise ValueError(f"path must be one of {', '.join(OPERATING_POINTS)}, got {path!r}")
    geometry = robot_scale(code, robot)
    if path == "circle":
        return [("circle", paths.circle_rates(geometry, exp.paths))]
    fast, slow = exp.paths.lawnmower_fast, exp.paths.lawnmower_slow
    return [("leg", (fast, fast)), ("left turn", (fast, slow)), ("right turn", (slow, fast))]


def setting(
    code: RobotCode,
    controller: str,
    formulation: str,
    robot: dict[str, float],
    exp: Experiment,
    plant: str = "nominal",
    rates: tuple[float, ...] | None = None,
) -> LoopSetting:
    """What the linearisation of ``controller`` in ``formulation`` on the robot whose code
    is ``code`` and parameters ``robot`` depends on, at the experiment's setting, about the
    steady motion at the driven-wheel ``rates`` (default: the experiment's circle)."""
    if not covers(code):
        raise ValueError(f"robot '{code.name}': the sampled-loop analysis needs the root's pose "
                         "(x, y, θ) as the first three coordinates and driven wheels")
    info = code.controller(controller)
    if not analysed(info):
        raise ValueError(f"{controller}: the sampled-loop analysis models the laws of (18) "
                         "(controllers with K1, K2) and the wheel PI; not this one")
    if formulation not in FORMULATIONS:
        raise ValueError(f"formulation must be 'paper' or 'minimal', got {formulation!r}")
    if formulation not in info.formulations:
        raise ValueError(f"{controller} is not generated in the {formulation} formulation for "
                         f"robot '{code.name}' (it has {', '.join(info.formulations)})")
    c, sen = exp.controller, exp.sensing
    pi = is_pi(info)
    gains: tuple[float, ...] = ()
    if pi:
        inputs = ConfigInputs(code, info, formulation, robot, exp)
        gains = (c.pi_kx, c.pi_ky, c.pi_ktheta, inputs.pi_kp, inputs.pi_ki)
    if rates is None:
        rates = operating_rates(code, robot, exp)[0][1]
    return LoopSetting(
        code_folder=str(code.folder.resolve()),
        tde=info.tde,
        formulation=formulation,
        nominal=tuple(sorted((k, float(v)) for k, v in robot.items())),
        plant=tuple(sorted(plant_parameters(code, robot, exp, plant).items())),
        h=c.h,
        substeps=exp.plant.substeps,
        k1=(float(c.k1),) * code.nq,
        k2=(float(c.k2),) * code.nq,
        q_pos=c.q_pos,
        q_vel=c.q_vel,
        velocity=sen.velocity,
        rate_window=sen.rate_window(c.h),
        estimator=sen.accel_estimator if info.tde else "model",
        wheel_rates=tuple(float(r) for r in rates),
        delay=c.delay_seconds(),
        law="pi" if pi else "error",
        pi_gains=gains,
        tau_max=c.tau_max,
    )


def with_delay(s: LoopSetting, delay: float) -> LoopSetting:
    """The same loop with the commands applied ``delay`` s after their sample."""
    return replace(s, delay=max(0.0, float(delay)))


def delay_radius(s: LoopSetting, gain: float, jitter: float) -> float:
    """The largest spectral radius over the delays D − J, D, D + J (J: the jitter bound;
    D − J clipped at 0): the loop at the extreme constant delays the jitter allows. A
    necessary condition: a delay that varies from sample to sample within the bound is a
    switched system, which a spectral radius below 1 at each constant delay does not
    guarantee (the closed loop simulates it)."""
    delays = sorted({max(0.0, s.delay - jitter), s.delay, s.delay + jitter})
    return max(pencil(with_delay(s, d)).radius(gain) for d in delays)


MAX_DELAY_SAMPLES = 2.0  # the tolerated delay is searched up to this many samples


def max_delay(s: LoopSetting, gain: float, rel_tol: float = 0.02) -> float:
    """The largest delay D (s) such that the loop at ``gain`` is stable for every constant
    delay in [0, D] (bisection on a grid of h/8; 0 if unstable without delay; inf if stable
    up to :data:`MAX_DELAY_SAMPLES` h)."""
    if not math.isfinite(gain) or pencil(with_delay(s, 0.0)).radius(gain) >= 1.0:
        return 0.0
    lo = 0.0
    for d in np.arange(1, round(8 * MAX_DELAY_SAMPLES) + 1) * s.h / 8:
        if pencil(with_delay(s, float(d))).radius(gain) >= 1.0:
            hi = float(d)
            while hi - lo > rel_tol * hi:
                mid = 0.5 * (lo + hi)
                lo, hi = (mid, hi) if pencil(with_delay(s, mid)).radius(gain) < 1.0 else (lo, mid)
            return lo
        lo = float(d)
    return math.inf


def roc_gain(code: RobotCode, formulation: str, robot: dict[str, float],
             exp: Experiment) -> float:
    """ROC's boundary-layer gain at zero error, ρ/ε, with ρ = φ/(1 − α) (q̈_d = 0 on the
    wheels) and (α, φ) of :func:`runtime.bindings.uncertainty.roc_bounds`, or over the
    experiment's ``[physical_uncertainty]`` where it declares one
    (:func:`runtime.bindings.physical_bounds.check_physical_roc`, which refuses naming the
    physical range that breaks α < 1), as ROC's configuration takes them."""
    if exp.physical:
        alpha, phi = check_physical_roc(code, robot, exp.physical, formulation,
                                        exp.controller.roc_max_rate)
        return phi / (1 - alpha) / exp.controller.eps
    alpha, phi = roc_bounds(code, robot, exp.controller.uncertainty, formulation,
                            exp.controller.roc_max_rate)
    if not alpha < 1.0:  # ρ = φ/(1 − α) exists only for α < 1; ROC's init refuses the rest
        raise ValueError(f"ROC needs alpha < 1 over the ±{exp.controller.uncertainty:.0%} "
                         f"box of the nominal parameters, got {alpha:.3g} (its init refuses "
                         "the bounds: BAD_BOUNDS)")
    return phi / (1 - alpha) / exp.controller.eps


class UnstableConfiguration(ValueError):
    """The sampled closed loop of a configuration is predicted unstable on its robot."""


class SwitchingGainWarning(UserWarning):
    """A switching gain at the configuration's setting exceeds the stable boundary-layer gain."""


def check_sampled_loop(code: RobotCode, name: str, formulation: str,
                       nominal: dict[str, float], exp: Experiment) -> None:
    """Refuse a configuration whose sampled closed loop (:mod:`runtime.stability.analysis`:
    plant under ZOH, the experiment's sensing, estimator and delay, the law, linearised on
    the circle) is unstable without any switching gain; warn when ROC's gain at zero error
    (ρ/ε) is beyond the largest stable boundary-layer gain."""
    s = setting(code, name, formulation, nominal, exp)
    pen = pencil(s)
    radius = delay_radius(s, 0.0, exp.controller.jitter_seconds())
    if radius >= 1.0:
        others = [f for f in code.controller(name).formulations if f != formulation]
        hint = ""
        for other in others:
            alt = pencil(setting(code, name, other, nominal, exp)).radius(0.0)
            hint = (
                f"; the {other} formulation is predicted stable (spectral radius {alt:.3f})"
                if alt < 1.0
                else f"; the {other} formulation is unstable too (spectral radius {alt:.3f})"
            )
        delay = exp.controller.delay_seconds()
        raise UnstableConfiguration(
            f"{name}/{formulation}: the sampled closed loop is predicted unstable on this "
            f"robot (spectral radius {radius:.3f} >= 1 per sample of h = {exp.controller.h} s "
            f"with {exp.sensing.velocity} rates"
            + (f" and a {delay:g} s delay" if delay > 0 else "")
            + f", before any switching gain){hint}. See `wmr stability` and docs/CONTROLLERS.md."
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

