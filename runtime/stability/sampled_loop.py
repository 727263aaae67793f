"""The sampled closed loop of any generated robot and controller, linearised from the
generated law itself: the pencil J(g) = J0 + g J1.

(The analysis command built on it is :mod:`runtime.stability.analysis`; the configuration
check that refuses an unstable loop, :func:`check_sampled_loop`, is here so that the
simulator can use it without importing the analysis, which simulates.) Any robot the
toolchain generates: n coordinates q whose first three are the root's pose (x, y, θ), m
driven wheels (``ACTUATED``), every other coordinate (a hitch angle, a caster's swivel,
passive wheels) measured by odometry; any controller of the registry, in every formulation
the robot's code has. Nothing here knows a law: a controller added to the registry gets
its own verdict, or a sentence saying why the analysis cannot take it
(:class:`NotLinearisable`).

The closed loop that runs on a robot is a discrete-time system: the plant under zero-order
hold over h, the sensing model (``[sensing]`` of the experiment), the odometry, and the
generated controller's step (the robot's NumPy controllers, ``controllers.py``, which the
C mirrors bit for bit) with its whole state: what its ``reset`` assigns. Its reals
(history q(t − h), q̇(t − h), u(t − h), ..., the TDE estimate, k̂'s window, an adapted
gain, an integral) are loop states; its integers (a step counter, a ring's head) are held
at the operating point; a state of any other type is refused. The commands still in
flight when the experiment states a delay are loop states too. This module builds that
one-sample map and linearises it by central differences about the loop's own steady
motion at the reference's wheel rates (a relative equilibrium), found by running the
closed loop from rest (or, where that run does not settle, about the reference itself).

Checked, or refused with the reason: (a) the law and the plant are differentiable there
(forward and backward differences agree on the loop states: a saturation, a jump, a norm
at zero would not); (b) the map is the same at consecutive samples in the reference's
heading frame, which also decides which of the law's q-sized states rotate with the robot
(a formulation's wheel-space quantities kept in a q-sized array do not); (c) for a law
with a switching term, that term is zero at the operating point (s = 0, no steady error).

Inside the boundary layer (‖s‖ < ε) a switching term k s / max(‖s‖, ε) of (22),
(24)/(25) is k s / ε. Its gain is held at k = g ε as the registry declares it
(``ControllerInfo.window``/``bounds``/``adaptive``; :data:`GAIN_HOLDS`): TDROC's k̂ held,
ROC's ρ = φ at α = 0, ASMC's adaptation stopped (γ = 0) at k̂ = gain0. Because s = 0 on
the operating point, the derivative of k's own dynamics multiplies zero, and the
linearised map is exactly J(g) = J₀ + g J₁; the largest g with spectral radius below 1 —
``max_stable_gain`` — is found by bisection on that pencil. For TDROC, k̂ measured in
closed loop then gives the predicted stable range ε > k̂ / g_max. A law with no switching
term (TDC, the PI) has J₁ = 0.

Delay (``controller.delay``/``delay_time``): the torque computed at t_k reaches the wheels
at t_k + D. Over a sample the plant sees the command of D/h samples ago until the fraction
frac(D/h) of the sample, then the next one; the commands in flight are loop states (the
augmented state), so the delay is in the map exactly, including D > h.

Frame: a steady motion is invariant under rotation (a circle) or translation (a straight
leg), so the Jacobian of step k is conjugated into the reference's heading frame (the
planar components x, y of every q-space quantity rotated by −θ_d(t_k)); there it is the
same for every k. States nothing in the loop reads (the true pose: the controller sees
odometry; a torque kept for reporting) are outputs, not loop states, and are left out of
the spectrum.

Conditions a verdict holds for (all stated in ``Analysis``): the robot's nominal parameters
for the plant unless ``plant="payload"`` (robot plus the experiment's fixed and extra
payload, the heaviest case), no friction, no quantisation (it adds noise, not dynamics),
the experiment's h, configuration, sensing and delay, and the operating point: the
experiment's circle (scaled to the robot as every command scales it; the paper's for
Drishti), or a lawn mower's leg or turn.
"""

from __future__ import annotations

import itertools
import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import cache, cached_property
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from runtime.bindings import cbuild
from runtime.bindings.config import ConfigInputs, source_value
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
    """The loop state of one robot and controller: (name, size, kind) blocks. kind "q": one
    or more q-space vectors of ``nq`` entries one after the other (rows 0, 1 of each
    planar), "dep": the dependent coordinates (the pose first), "wheel" and "fixed": not
    rotated; the frame change rotates the planar rows."""

    blocks: tuple[tuple[str, int, str], ...]
    nq: int

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

    def planar_rows(self, planar: frozenset[str] | None = None) -> NDArray[np.intp]:
        """The first row of each planar pair (x, y) of the q-space blocks (of the law's
        blocks named in ``planar`` only, if given, besides the plant's and the odometry's)."""
        sl = self.slices
        out: list[int] = []
        for name, size, kind in self.blocks:
            if planar is not None and name.startswith(LAW_PREFIX) and name not in planar:
                continue
            out += (range(sl[name].start, sl[name].start + size, self.nq) if kind == "q"
                    else [sl[name].start] if kind == "dep" else [])
        return np.array(out, dtype=np.intp)

    def rotation(self, theta: float, planar: frozenset[str] | None = None
                 ) -> NDArray[np.float64]:
        """T(θ): rotates the planar rows of every q-space block by −θ."""
        return rotate_rows(np.eye(self.dim), self.planar_rows(planar), theta)


def rotate_rows(a: NDArray[np.float64], rows: NDArray[np.intp], theta: float
                ) -> NDArray[np.float64]:
    """T(θ) a for T the rotation by −θ of each pair (i, i + 1), i in ``rows``."""
    c, s = math.cos(theta), math.sin(theta)
    out = a.copy()
    top, bottom = a[rows], a[rows + 1]
    out[rows] = c * top + s * bottom
    out[rows + 1] = -s * top + c * bottom
    return out


LAW_PREFIX = "law."  # the blocks of the generated controller's own state


def sensing_blocks(nq: int, nu: int) -> list[tuple[str, int, str]]:
    """The plant's and the sensing model's part of the loop state (not the law's)."""
    return [
        ("plant_q", nq, "q"),
        ("plant_eta", nu, "wheel"),
        ("odo_dependent", nq - nu, "dep"),
        ("odo_angles", nu, "wheel"),
        ("window_start", nu, "wheel"),
    ]


class NotLinearisable(ValueError):
    """A law whose structure the sampled-loop analysis cannot take (a state it cannot see,
    a switching gain it cannot hold, a discontinuity at the operating point, a map that is
    not time-invariant in the reference's frame): the sentence names the law and why."""


@dataclass(frozen=True)
class LoopSetting:
    """What one linearisation depends on: the robot's generated code, the controller (by
    its registry name) and its configuration as the generated step takes it, the plant,
    the sampling, the sensing and the steady motion."""

    code_folder: str  # the robot's generated code (python/, c/)
    controller: str
    formulation: str
    nominal: tuple[tuple[str, float], ...]  # the controllers' model
    plant: tuple[tuple[str, float], ...]  # the simulated robot (with K_lat)
    h: float
    substeps: int
    velocity: str
    rate_window: float
    wheel_rates: tuple[float, ...]  # the steady motion linearised about
    # the configuration fields after ``nominal`` (a vector as a tuple), by registry name
    config: tuple[tuple[str, Any], ...]
    estimator: str = "model"  # for the report: the TDE's estimator, or "model"
    delay: float = 0.0  # s: command computed at t_k applied from t_k + delay
    in_flight: int = 0  # at least this many commands in flight kept in the state (jitter)


# How each declared kind of switching gain (``ControllerInfo.window``/``bounds``/``adaptive``,
# from the registry's ``Gain``) is held at k = g ε while the map is linearised: the
# configuration fields, by their declared *source* (robot.py's ``CONTROLLERS``), set to a
# value (K: the held gain k). Inside the boundary layer ‖s‖ < ε the switching term
# k s / max(‖s‖, ε) of (22), (24)/(25) is k s / ε, and s = 0 at the operating point, so
# the Jacobian is J0 + (k/ε) J1 whatever k's own dynamics (k̂'s window, ASMC's adaptation
# by ‖s‖, ROC's α-term): their derivative multiplies s = 0.
HELD_GAIN = "K"
GAIN_HOLDS: dict[str, dict[str, Any]] = {
    "window": {"hold_gain": 1, "held_gain": HELD_GAIN},  # k̂ of (25) held
    "bounds": {"roc_bounds.alpha": 0.0, "roc_bounds.phi": HELD_GAIN},  # ρ = φ at α = 0
    "adaptive": {"experiment.controller.gamma": 0.0, "zero": HELD_GAIN},  # γ = 0 at gain0
}
EPS_SOURCE = "experiment.controller.eps"  # the switching term's boundary layer ε


def gain_kind(info: ControllerInfo) -> str | None:
    """The declared kind of ``info``'s switching gain (None: no switching term);
    :class:`NotLinearisable` if it switches with a gain the analysis cannot hold."""
    if not info.switching:
        return None
    kinds = [k for k in GAIN_HOLDS if getattr(info, k)]
    sources = {f.source for f in info.fields}
    if len(kinds) != 1 or EPS_SOURCE not in sources:
        raise NotLinearisable(
            f"{info.label} ({info.name}): its switching term's gain is declared as none of "
            f"{', '.join(GAIN_HOLDS)} (or without ε), so the analysis cannot hold it to "
            "linearise inside the boundary layer")
    missing = set(GAIN_HOLDS[kinds[0]]) - sources
    if missing:
        raise NotLinearisable(
            f"{info.label} ({info.name}): a {kinds[0]} gain without the configuration "
            f"sources {', '.join(sorted(missing))} that hold it")
    return kinds[0]


def refusal(info: ControllerInfo) -> str:
    """Why the analysis refuses ``info`` before linearising it ("" if it does not)."""
    try:
        gain_kind(info)
    except NotLinearisable as exc:
        return str(exc)
    return ""


def held_config(info: ControllerInfo, config: tuple[tuple[str, Any], ...], gain: float
                ) -> dict[str, Any]:
    """``config`` with the switching gain held at k = ``gain`` ε (:data:`GAIN_HOLDS`)."""
    out = dict(config)
    kind = gain_kind(info)
    if kind is None:
        return out
    by_source = {f.source: f.name for f in info.fields}
    eps = float(out[by_source[EPS_SOURCE]])
    for source, value in GAIN_HOLDS[kind].items():
        out[by_source[source]] = gain * eps if value == HELD_GAIN else value
    return out


def state_keys(ctrl: Any) -> list[str]:
    """The attributes the generated controller's ``reset`` assigns: its state (what its
    step reads and commits), in the order ``reset`` lists them."""
    assigned: list[str] = []

    class Probe(type(ctrl)):  # type: ignore[misc]
        def __setattr__(self, name: str, value: Any) -> None:
            if name not in assigned:
                assigned.append(name)
            object.__setattr__(self, name, value)

    probe = object.__new__(Probe)
    probe.__dict__.update(vars(ctrl))
    probe.reset()
    return assigned


def law_state(ctrl: Any, label: str) -> tuple[list[tuple[str, tuple[int, ...]]], list[str]]:
    """(continuous states as (name, shape), discrete ones held at the operating point) of
    a generated controller: reals are loop states, integers and labels (a step counter,
    a ring's head, the last status) are held; anything else is refused."""
    cont: list[tuple[str, tuple[int, ...]]] = []
    held: list[str] = []
    for key in state_keys(ctrl):
        v = getattr(ctrl, key)
        if isinstance(v, bool | int | np.integer | str):
            held.append(key)
        elif isinstance(v, float | np.floating):
            cont.append((key, ()))
        elif isinstance(v, np.ndarray) and v.dtype.kind == "f":
            cont.append((key, tuple(v.shape)))
        else:
            raise NotLinearisable(f"{label}: its state '{key}' is a {type(v).__name__}, not "
                                  "reals the analysis can take as loop states")
    return cont, held


# A closed-loop run whose wheel rates are this close (relative) to the reference's at the
# analysed sample has settled onto its steady motion; else (diverging, or still moving)
# the law is linearised about the reference.
SETTLED_RATES = 1e-5
KINK_TOL = 1e-4  # relative one-sided difference that marks a discontinuity or a kink
# Relative change of the heading-frame Jacobian from one sample to the next: a law state
# rotated wrongly changes it by about ω h (1e-2 of the largest entry on the circle); a loop
# still settling onto its steady motion near a stability boundary, by about 1e-5.
FRAME_TOL = 1e-3
# What the switching term may add at the operating point, relative to the state: the
# residual of a run that converged to the steady motion, not a steady error.
SWITCH_TOL = 1e-6


def covers(code: RobotCode) -> bool:
    """Whether the analysis is written for this robot's code: driven wheels, and the root's
    pose (x, y, θ) as its first three coordinates, measured by odometry."""
    return code.nu >= 1 and code.dependent[:3] == (0, 1, 2)


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
                     rates: tuple[float, ...], name: str, tail: int = 20
                     ) -> tuple[Reference, int]:
    """The motion under the driven-wheel rates ``rates`` (ramped up from rest, as the paths
    start) and the first sample from :data:`ANALYSIS_TIME` at which it is steady: every
    angle's rate constant over a sample (a trailer's hitch settled)."""
    h = exp.controller.h
    duration = ANALYSIS_TIME + tail * h
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
    no friction), in the global frame, about the loop's own steady motion: the plant
    under ZOH, the sensing model and the odometry, and the generated controller's step
    (the robot's NumPy controllers, ``controllers.py``) with its whole state (history,
    window, adaptive gain, integral) as loop states."""

    def __init__(self, s: LoopSetting, tail: int = 20) -> None:
        self.s = s
        self.code = code = code_in(Path(s.code_folder))
        self.info = info = code.controller(s.controller)
        self.label = f"{info.label} ({info.name}/{s.formulation})"
        self.switching = gain_kind(info) is not None
        self.model = code.model
        self.nom = dict(s.nominal)
        self.plant = dict(s.plant)
        self.act = list(code.actuated)
        self.dep = list(code.dependent)
        self.lag, self.frac = delay_split(s.delay, s.h)
        self.period = s.h  # the plant's sampling period (the law's h unless timed apart)
        self.flights = max(in_flight_count(s.delay, s.h), s.in_flight)
        self.cls = code.controller_class(s.controller)
        self._controllers: dict[float, Any] = {}
        cont, self.held = law_state(self.controller(0.0), self.label)
        self.shapes = {LAW_PREFIX + k: shape for k, shape in cont}
        nq, nu = code.nq, code.nu
        blocks = sensing_blocks(nq, nu)
        for name, shape in self.shapes.items():
            size = int(np.prod(shape)) if shape else 1
            blocks.append((name, size, "q" if shape and shape[-1] == nq else "fixed"))
        blocks += [(f"in_flight{i}", nu, "wheel") for i in range(self.flights)]
        self.layout = Layout(tuple(blocks), nq)
        self.sl = self.layout.slices
        self.dim = self.layout.dim
        self.lib = double_library(code)
        ffi, pre = self.lib.ffi, code.prefix
        self.pp = ffi.new(f"{pre}_plant_params_t *")
        cbuild.fill_params(self.pp, self.plant, code.controllers.C_FIELD_NAMES)
        self.friction = ffi.new("sim_friction_t *", [0.0, 0.0, 0.05])
        self.x = ffi.new(f"{pre}_real_t[{nq + nu}]")
        self.tau = ffi.new(f"{pre}_real_t[{nu}]")
        exp = Experiment()
        exp = replace(exp, controller=replace(exp.controller, h=s.h))
        self.ref, self.k = steady_reference(code, self.nom, exp, s.wheel_rates, "steady", tail)
        self.points, self.held_at, self.how = self.operating_points()

    def controller(self, gain: float) -> Any:
        """The generated controller configured as the setting says, its switching gain held
        at k = ``gain`` ε (one instance per gain; its state is loaded before each step)."""
        if gain not in self._controllers:
            values = held_config(self.info, self.s.config, gain)
            cfg = self.code.controllers.Config(
                nominal=self.nom, **{k: list(v) if isinstance(v, tuple) else v
                                     for k, v in values.items()})
            try:
                self._controllers[gain] = self.cls(cfg)
            except ValueError as exc:  # ControllerError: the configuration is refused
                raise NotLinearisable(f"{self.label}: the generated controller refuses the "
                                      f"configuration: {exc}") from None
        return self._controllers[gain]

    # -- the law's state in the loop state ----------------------------------------------
    def at_gain(self, z: Vec, gain: float) -> Vec:
        """``z`` with the law's states that carry the held gain (those whose reset value
        the gain changes: ASMC's adapted k̂, a held k̂ the step reports) at ``gain``'s."""
        if gain == 0.0:
            return z
        base, held = np.zeros(self.dim), np.zeros(self.dim)
        for g, out in ((0.0, base), (gain, held)):
            ctrl = self.controller(g)
            ctrl.reset()
            self.store(ctrl, out)
        out = z.copy()
        moved = base != held
        out[moved] = held[moved]
        return out

    def load(self, ctrl: Any, z: Vec, held: dict[str, Any]) -> None:
        for name, shape in self.shapes.items():
            v = z[self.sl[name]]
            setattr(ctrl, name.removeprefix(LAW_PREFIX),
                    v.reshape(shape).copy() if shape else float(v[0]))
        for key, value in held.items():
            setattr(ctrl, key, value)

    def store(self, ctrl: Any, out: Vec) -> None:
        for name in self.shapes:
            out[self.sl[name]] = np.ravel(getattr(ctrl, name.removeprefix(LAW_PREFIX)))

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

    def step(self, z: Vec, k: int, gain: float, held: dict[str, Any] | None = None) -> Vec:
        """z_{k+1} = F(z_k) for the sample at t_k: the generated step on the measurement,
        its state loaded from z_k (and the discrete part from ``held``, default the
        operating point's)."""
        s, sl, ref = self.s, self.sl, self.ref
        q, qdot = self.measure(z)
        ctrl = self.controller(gain)
        self.load(ctrl, z, self.held_at[0] if held is None else held)
        tau = np.asarray(ctrl.step(q, qdot, ref.q[k], ref.qdot[k], ref.qddot[k]), dtype=float)
        out = z.copy()
        out[sl["odo_dependent"]] = q[self.dep]
        out[sl["odo_angles"]] = q[self.act]
        self.store(ctrl, out)
        flight = [z[sl[f"in_flight{i}"]] for i in range(self.flights)]
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
            self._advance_pieces([(0.0, before), (self.frac * self.period, now)], window, out)
        out[sl["plant_q"]] = [x[i] for i in range(nq)]
        out[sl["plant_eta"]] = [x[nq + i] for i in range(nu)]
        return out

    def _advance_held(self, tau: Vec, window: float, out: Vec) -> None:
        """The plant over h under τ held, reading the motor-encoder window's start."""
        s, x = self.s, self.x
        dt = self.period / s.substeps
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
        h = self.period
        marks = sorted({0.0, h, *(t for t, _ in pieces if 0 < t < h),
                        *([h - window] if window > 0 else [])})
        adv = self.lib.lib.sim_plant_advance
        for a, b in itertools.pairwise(marks):
            if window > 0 and abs(a - (h - window)) < 1e-12:
                out[self.sl["window_start"]] = [x[i] for i in self.act]
            tau = [cmd for t, cmd in pieces if t <= a + 1e-12][-1]
            self.tau[0:self.code.nu] = [float(v) for v in tau]
            n = max(1, math.ceil((b - a) / (h / s.substeps) - 1e-9))
            if adv(self.pp, self.friction, x, self.tau, (b - a) / n, n) != 0:
                raise ArithmeticError("plant diverged during the linearisation")

    # -- operating point and Jacobian ------------------------------------------------
    def pin(self, z: Vec, j: int) -> None:
        """Put the plant and the sensing on the reference at sample j (odometry of j − 1)."""
        ref, sl, act = self.ref, self.sl, self.act
        eta = ref.qdot[j, act]
        z[sl["plant_q"]] = ref.q[j]
        z[sl["plant_eta"]] = eta
        z[sl["odo_dependent"]] = ref.q[max(j - 1, 0), self.dep]
        z[sl["odo_angles"]] = ref.q[max(j - 1, 0), act]
        z[sl["window_start"]] = ref.q[j, act] - self.s.rate_window * eta

    def operating_points(self) -> tuple[list[Vec], list[dict[str, Any]], str]:
        """The loop states at samples k and k + 1 (and the law's discrete state there),
        from rest at the reference's start: the closed loop run itself, so the point is the
        loop's own steady motion (zero error for a law that reaches it; a steady error
        otherwise); where that run has not settled (:data:`SETTLED_RATES`: diverging, or
        too slow to tell), the law fed the reference exactly, the plant pinned to it (the
        linearisation is then about the reference, which an unsettled loop need not hold).
        The third item says which."""
        rates = np.asarray(self.s.wheel_rates)
        for pinned in (False, True):
            ctrl = self.controller(0.0)
            ctrl.reset()
            z = np.zeros(self.dim)
            self.pin(z, 0)
            self.store(ctrl, z)
            points: list[Vec] = []
            held: list[dict[str, Any]] = []
            try:
                with np.errstate(all="ignore"):
                    for j in range(self.k + 2):
                        if pinned:
                            self.pin(z, j)
                        if j >= self.k:
                            points.append(z.copy())
                            held.append({key: getattr(ctrl, key) for key in self.held})
                        z = self.step(z, j, 0.0, held={})
            except (ArithmeticError, ValueError):
                continue
            scale = max(1.0, float(np.abs(rates).max()))
            off = (float(np.abs(points[0][self.sl["plant_eta"]] - rates).max())
                   if all(np.all(np.isfinite(p)) for p in points) else math.inf)
            if off < SETTLED_RATES * scale or pinned:
                return points, held, ("the reference (the closed loop has not settled onto a "
                                      "steady motion there)" if pinned
                                      else "the closed loop's steady motion")
        raise NotLinearisable(f"{self.label}: the generated step fails on the reference "
                              "itself; no operating point to linearise about")

    def raw_jacobian(self, gain: float, i: int = 0, columns: Sequence[int] | None = None
                     ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(∂z_{k+i+1}/∂z_{k+i} by central differences in the global frame (its
        ``columns`` only, if given), the gap between the forward and the backward
        difference, entry by entry: a kink or a jump of the law or the plant shows there)."""
        z0, k, held = self.at_gain(self.points[i], gain), self.k + i, self.held_at[i]
        f0 = self.step(z0, k, gain, held)
        jac = np.zeros((self.dim, self.dim))
        gap = np.zeros((self.dim, self.dim))
        for c in range(self.dim) if columns is None else columns:
            d = 1e-6 * max(1.0, abs(z0[c]))
            zp, zm = z0.copy(), z0.copy()
            zp[c] += d
            zm[c] -= d
            fp, fm = self.step(zp, k, gain, held), self.step(zm, k, gain, held)
            jac[:, c] = (fp - fm) / (2 * d)
            gap[:, c] = np.abs((fp - f0) - (f0 - fm)) / d
        return jac, gap

    def conjugate(self, jac: NDArray[np.float64], i: int, planar: frozenset[str]
                  ) -> NDArray[np.float64]:
        """The Jacobian of sample k + i in the reference's heading frame."""
        th, rows = self.ref.q[:, 2], self.layout.planar_rows(planar)
        k = self.k + i
        return rotate_rows(rotate_rows(jac, rows, th[k + 1]).T, rows, th[k]).T

    def frame(self, now: NDArray[np.float64], then: NDArray[np.float64],
              states: Sequence[int]) -> tuple[frozenset[str], float]:
        """Which of the law's q-sized states are planar vectors (their rows 0, 1 rotate with
        the robot) and which are not (a formulation's wheel-space quantities stored in a
        q-sized array): the choice under which the heading-frame Jacobians of samples k and
        k + 1 agree on the loop ``states``, and their relative difference there."""
        sl, kept = self.layout.slices, set(states)
        names = [n for n, _, kind in self.layout.blocks if n.startswith(LAW_PREFIX)
                 and kind == "q" and kept & set(range(sl[n].start, sl[n].stop))]
        ix = np.ix_(states, states)
        scale = max(1.0, float(np.abs(now[ix]).max()))
        best: tuple[float, frozenset[str]] = (math.inf, frozenset())
        for r in range(len(names) + 1):
            for subset in itertools.combinations(names, r):
                planar = frozenset(subset)
                diff = np.abs(self.conjugate(now, 0, planar)[ix]
                              - self.conjugate(then, 1, planar)[ix])
                best = min(best, (float(diff.max()) / scale, planar), key=lambda b: b[0])
        return best[1], best[0]

    def jacobian(self, gain: float, i: int = 0) -> NDArray[np.float64]:
        """∂z_{k+i+1}/∂z_{k+i} (i = 0 or 1) at ``gain`` in the reference's heading frame."""
        return self.conjugate(self.raw_jacobian(gain, i)[0], i, self.planar)

    def timed_jacobian(self, gain: float, period: float, delay: float) -> NDArray[np.float64]:
        """∂z_{k+1}/∂z_k in the heading frame at the operating point of the setting's own
        timing, for one sample whose plant period is ``period`` and whose command's latency
        is ``delay`` (< period, one command in flight: :mod:`runtime.stability.jitter`)."""
        if not (0.0 <= delay < period and self.flights >= 1):
            raise ValueError(f"a timed sample needs 0 <= delay < period and a command in "
                             f"flight, got delay {delay:g} s, period {period:g} s")
        saved = self.period, self.lag, self.frac
        self.period, self.lag, self.frac = period, 0, delay / period
        try:
            return self.conjugate(self.raw_jacobian(gain, 0)[0], 0, self.planar)
        finally:
            self.period, self.lag, self.frac = saved

    @cached_property
    def planar(self) -> frozenset[str]:
        """The law's states that rotate with the robot (:meth:`frame`)."""
        return self.checked()[0]

    def checked(self) -> tuple[frozenset[str], NDArray[np.float64], NDArray[np.float64],
                               list[int]]:
        """(planar states, J0, J1 in the heading frame, the loop states), every assumption
        the pencil rests on checked: the switching term is zero at the operating point
        (s = 0), the law and the plant are smooth there (forward and backward differences
        agree), and the map is the same at consecutive samples in the reference's frame."""
        j0w, gap0 = self.raw_jacobian(0.0, 0)
        j1w, gaps = np.zeros_like(j0w), [gap0]
        if self.switching:
            held = self.held_at[0]
            at0, at1 = (self.step(self.at_gain(self.points[0], g), self.k, g, held)
                        for g in (0.0, 1.0))
            plant = [*range(self.sl["plant_q"].start, self.sl["plant_eta"].stop)]
            if float(np.abs(at1 - at0)[plant].max()) > SWITCH_TOL * max(
                    1.0, float(np.abs(at0[plant]).max())):
                raise NotLinearisable(
                    f"{self.label}: its switching term acts at {self.how} (s ≠ 0 there: a "
                    "steady error), so the loop is not the boundary layer's linear pencil")
            j1w, gap1 = self.raw_jacobian(1.0, 0)
            j1w = j1w - j0w
            gaps.append(gap1)
        eta = self.sl["plant_eta"]
        # the pattern of both, with the planar pairs of every q-sized block merged
        pattern = np.abs(j0w) + np.abs(j1w)
        rows = self.layout.planar_rows()
        pattern = pattern + np.abs(rotate_rows(rotate_rows(pattern, rows, 0.7).T, rows, 0.7).T)
        states = loop_states(pattern, range(eta.start, eta.stop))
        scale = max(1.0, float(np.abs(j0w + j1w).max()))
        ix = np.ix_(states, states)
        for gap in gaps:
            r, c = np.unravel_index(int(np.argmax(gap[ix])), (len(states), len(states)))
            if gap[ix][r, c] > KINK_TOL * scale:
                names = self.layout.names()
                raise NotLinearisable(
                    f"{self.label}: not differentiable at {self.how}: the one-sided "
                    f"differences of {names[states[r]]} in {names[states[c]]} differ by "
                    f"{gap[ix][r, c]:.3g} (a discontinuity, a saturation or a norm at zero)")
        planar, change = self.frame(j0w, self.raw_jacobian(0.0, 1, states)[0], states)
        if change > FRAME_TOL:
            raise NotLinearisable(
                f"{self.label}: its one-sample map changes from one sample to the next in the "
                f"reference's frame (relative change {change:.2g} about {self.how}): a "
                "time-varying law, or a state the analysis cannot place")
        self.__dict__["planar"] = planar
        j0 = self.conjugate(j0w, 0, planar)
        return planar, j0, self.conjugate(j0w + j1w, 0, planar) - j0, states

    def pencil(self) -> Pencil:
        """J(g) = J0 + g J1 on the loop states (:meth:`checked`)."""
        _, j0, j1, states = self.checked()
        ix = np.ix_(states, states)
        neutral = min(neutral_count(np.linalg.eigvals(j0[ix] + g * j1[ix]))
                      for g in (0.0, 1.0, 10.0))
        names = self.layout.names()
        return Pencil(j0[ix], j1[ix], tuple(states), neutral,
                      tuple(names[i] for i in states), self.how)


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
    names: tuple[str, ...] = ()  # of the loop states (``Layout.names``)
    about: str = ""  # the operating point: the loop's steady motion, or the reference

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
    """The pencil of the loop ``s`` (:meth:`ClosedLoop.pencil`); :class:`NotLinearisable`
    names the law and the reason where the analysis cannot take it."""
    return ClosedLoop(s).pencil()


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


def law_config(code: RobotCode, info: ControllerInfo, formulation: str,
               robot: dict[str, float], exp: Experiment) -> tuple[tuple[str, Any], ...]:
    """The generated controller's configuration at the experiment's setting, every field
    from its registry source (:func:`runtime.bindings.config.source_value`, as the C's
    :func:`~runtime.bindings.config.controller_config`); the fields that hold the switching
    gain for the linearisation are left at their declared hold (:data:`GAIN_HOLDS`), so
    ROC's bounds are not computed here."""
    kind = gain_kind(info)
    skip = set(GAIN_HOLDS[kind]) if kind is not None else set()
    inputs = ConfigInputs(code, info, formulation, robot, exp)
    out: list[tuple[str, Any]] = []
    for f in info.fields:
        value = 0.0 if f.source in skip else source_value(f.source, inputs)
        out.append((f.name, (float(value),) * code.nq if f.kind == "vector" else value))
    return tuple(out)


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
    if formulation not in FORMULATIONS:
        raise ValueError(f"formulation must be 'paper' or 'minimal', got {formulation!r}")
    if formulation not in info.formulations:
        raise ValueError(f"{controller} is not generated in the {formulation} formulation for "
                         f"robot '{code.name}' (it has {', '.join(info.formulations)})")
    c, sen = exp.controller, exp.sensing
    if rates is None:
        rates = operating_rates(code, robot, exp)[0][1]
    return LoopSetting(
        code_folder=str(code.folder.resolve()),
        controller=controller,
        formulation=formulation,
        nominal=tuple(sorted((k, float(v)) for k, v in robot.items())),
        plant=tuple(sorted(plant_parameters(code, robot, exp, plant).items())),
        h=c.h,
        substeps=exp.plant.substeps,
        velocity=sen.velocity,
        rate_window=sen.rate_window(c.h),
        wheel_rates=tuple(float(r) for r in rates),
        config=law_config(code, info, formulation, robot, exp),
        estimator=sen.accel_estimator if info.tde else "model",
        delay=c.delay_seconds(),
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


class NoVerdictWarning(UserWarning):
    """The sampled-loop analysis cannot linearise a configuration's law: it runs unchecked."""


class SwitchingGainWarning(UserWarning):
    """A switching gain at the configuration's setting exceeds the stable boundary-layer gain."""


def check_sampled_loop(code: RobotCode, name: str, formulation: str,
                       nominal: dict[str, float], exp: Experiment) -> None:
    """Refuse a configuration whose sampled closed loop (:mod:`runtime.stability.analysis`:
    plant under ZOH, the experiment's sensing, estimator and delay, the law, linearised on
    the circle) is unstable without any switching gain; warn when ROC's gain at zero error
    (ρ/ε) is beyond the largest stable boundary-layer gain."""
    s = setting(code, name, formulation, nominal, exp)
    try:
        pen = pencil(s)
    except NotLinearisable as exc:  # no verdict: said, not replaced by another law's
        warnings.warn(f"no sampled-data check of {name}/{formulation}: {exc}",
                      NoVerdictWarning, stacklevel=2)
        return
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

