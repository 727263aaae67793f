"""Closed loop of any generated robot through its generated C, with the experiment's
sensors, friction and payload schedule.

What :mod:`runtime.paper.simulate` does for the paper's robot, for a robot known only by its
generated code (``generated/<dir>/{c,python}``):

* Plant: the generated C ``<prefix>_plant_state_derivative`` (x = (q, η), the constrained
  dynamics in the minimal form), fixed-step RK4 under zero-order hold at ``substeps / h``;
  viscous and Coulomb friction (tanh-smoothed below 0.05 rad/s) on each driven wheel,
  unknown to the controllers; a payload on the root body by the generated
  ``plant_params_with_payload`` (the fixed one always, the extra one on for half of each
  period), as in the paper's experiment.
* Sensors: the driven wheels' encoders (angles quantised to 4 × ppr counts per revolution,
  times the gear ratio for a motor-side encoder), their rates by the experiment's velocity
  model, and every other coordinate (pose, hitch, passive wheels) by odometry: the
  generated kinematics q̇ = S(q) η integrated over each sample's encoder increments
  (midpoint rule).
* Controllers: the generated C ``<prefix>_<ctrl>_init`` / ``_step`` called through cffi.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from runtime import cbuild
from runtime.closed_loop import Reference, velocities
from runtime.experiment import ACCEL_CODES, Experiment
from runtime.generated_modules import RobotCode
from runtime.robot_model_checks import ModelBounds, model_bounds

Array = NDArray[np.float64]
COULOMB_SPEED = 0.05  # rad/s, as runtime/paper/csrc/wmr_sim.c


@dataclass(frozen=True)
class RobotRun:
    """One closed-loop run at the sample instants."""

    controller: str
    formulation: str
    path: str
    t: Array
    q: Array  # true q (N × n)
    q_meas: Array
    q_des: Array
    tau: Array  # (N × m)
    gain: Array
    saturated: int
    failed_at: float | None
    status: str  # the name of the first failing status, or "ok"

    @property
    def position_error(self) -> Array:
        """Distance of the root body's frame origin from its reference."""
        return np.asarray(np.linalg.norm(self.q[:, :2] - self.q_des[:, :2], axis=1))


def plant_params_at(code: RobotCode, exp: Experiment, t: float,
                    base: dict[str, float] | None = None) -> dict[str, float]:
    """The simulated robot's parameters at time t (keys in the generated ``PLANT_PARAMS``
    order): ``base`` (default: the robot's) with the experiment's fixed payload, and the
    extra one when it is on."""
    pl = exp.plant
    keys = list(code.plant_defaults)
    p = dict(code.plant_defaults if base is None else base)
    loads = [(pl.fixed_payload, pl.fixed_payload_x, pl.fixed_payload_y)]
    if pl.extra_on(t):
        loads.append((pl.extra_payload, pl.extra_payload_x, pl.extra_payload_y))
    for load in loads:
        if load[0] > 0:
            values = code.plant.plant_params_with_payload(list(load), p)
            p = dict(zip(keys, (float(v) for v in values), strict=True))
    return {k: p[k] for k in keys}


def controller_config(lib: cbuild.CLibrary, code: RobotCode, name: str, formulation: str,
                      nominal: dict[str, float], exp: Experiment,
                      bounds: ModelBounds | tuple[float, float] | None = None,
                      held_gain: float | None = None) -> Any:
    """``<prefix>_<name>_config_t`` from the experiment's [controller] and [sensing].
    ``bounds``: ROC's (α, φ) (default: :func:`model_bounds` over the experiment's box);
    ``held_gain`` (TDROC only) holds k̂ at that value instead of (25)."""
    c = exp.controller
    cfg = lib.ffi.new(f"{code.prefix}_{name}_config_t *")
    cfg.nominal = cbuild.params_struct(lib, nominal, f"{code.prefix}_params_t",
                                       code.controllers.C_FIELD_NAMES)[0]
    cfg.formulation = getattr(code.controllers, f"FORMULATION_{formulation.upper()}")
    cfg.k1 = [c.k1] * code.nq
    cfg.k2 = [c.k2] * code.nq
    cfg.q_pos, cfg.q_vel, cfg.h, cfg.tau_max = c.q_pos, c.q_vel, c.h, c.tau_max
    if name in ("tdc", "tdroc"):
        cfg.accel_estimator = ACCEL_CODES[exp.sensing.accel_estimator]
        cfg.rate_window = exp.sensing.rate_window(c.h)
    if name != "tdc":
        cfg.eps = c.eps
    if name == "tdroc":
        cfg.n, cfg.a = c.n, c.a
        if held_gain is not None:
            cfg.hold_gain, cfg.held_gain = 1, held_gain
    elif held_gain is not None:
        raise ValueError(f"held_gain applies to TDROC only, not {name}")
    if name == "roc":
        b = bounds or model_bounds(code, nominal, c.uncertainty, formulation)
        cfg.alpha, cfg.phi = (b.alpha, b.phi) if isinstance(b, ModelBounds) else b
    if name == "asmc":
        cfg.gamma, cfg.gain0 = c.gamma, 0.0
    return cfg


class Odometry:
    """Encoders on the driven wheels and every other coordinate integrated from them."""

    def __init__(self, code: RobotCode, q0: Array, exp: Experiment, params: dict[str, float]):
        self.code, self.params = code, params
        self.sensing = exp.sensing
        self.h = exp.controller.h
        self.window = self.sensing.rate_window(self.h)
        self.counts_per_rad = self.sensing.counts_per_wheel_rev() / (2 * math.pi)
        self.act = list(code.actuated)
        self.q = np.array(q0, dtype=float)
        self.q[self.act] = self.quantise(self.q[self.act])

    def quantise(self, angles: Array) -> Array:
        return np.asarray(np.floor(angles * self.counts_per_rad) / self.counts_per_rad)

    def measure(self, true_angles: Array, true_rates: Array,
                window_start: Array | None) -> tuple[Array, Array]:
        """(q, q̇) as the controller sees them at a sample instant."""
        angles = self.quantise(true_angles)
        delta = angles - self.q[self.act]
        # q̇ = S(q) η is linear in η: the increment over the sample is S(q_mid) Δθ.
        mid = self.q + 0.5 * velocities(self.code, self.q, delta, self.params)
        step = velocities(self.code, mid, delta, self.params)
        v = self.sensing.velocity
        if v == "sample-instant":
            rates = true_rates.copy()
        elif v == "encoder-average":
            rates = delta / self.h
        else:
            assert window_start is not None, "motor-encoder needs the angles at t - window"
            rates = (angles - self.quantise(window_start)) / self.window
        self.q = self.q + step
        self.q[self.act] = angles
        return self.q.copy(), velocities(self.code, self.q, rates, self.params)


class _Plant:
    """RK4 of the generated C plant with wheel friction, on preallocated buffers."""

    def __init__(self, lib: cbuild.CLibrary, code: RobotCode, exp: Experiment):
        self.ffi, self.code = lib.ffi, code
        self.f = getattr(lib.lib, f"{code.prefix}_plant_state_derivative")
        self.pp = lib.ffi.new(f"{code.prefix}_plant_params_t *")
        self.viscous, self.coulomb = exp.plant.viscous, exp.plant.coulomb
        real = "float" if lib.float32 else "double"
        self.dtype = np.float32 if lib.float32 else np.float64
        self.xin = np.zeros(code.nq + code.nu, self.dtype)
        self.tin = np.zeros(code.nu, self.dtype)
        self.out = np.zeros(code.nq + code.nu, self.dtype)
        self.cx = lib.ffi.cast(f"{real} *", lib.ffi.from_buffer(self.xin))
        self.ct = lib.ffi.cast(f"{real} *", lib.ffi.from_buffer(self.tin))
        self.co = lib.ffi.cast(f"{real} *", lib.ffi.from_buffer(self.out))

    def set_params(self, params: dict[str, float]) -> None:
        cbuild.fill_params(self.pp, params, self.code.controllers.C_FIELD_NAMES)

    def rhs(self, x: Array, tau: Array) -> Array:
        eta = x[self.code.nq:]
        self.xin[:] = x
        self.tin[:] = tau - self.viscous * eta - self.coulomb * np.tanh(eta / COULOMB_SPEED)
        self.f(self.pp, self.cx, self.ct, self.co)
        return self.out.astype(np.float64)

    def advance(self, x: Array, tau: Array, dt: float, nsub: int) -> Array:
        for _ in range(nsub):
            k1 = self.rhs(x, tau)
            k2 = self.rhs(x + dt / 2 * k1, tau)
            k3 = self.rhs(x + dt / 2 * k2, tau)
            k4 = self.rhs(x + dt * k3, tau)
            x = x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        return x


def run(lib: cbuild.CLibrary, code: RobotCode, name: str, formulation: str, path: str,
        ref: Reference, nominal: dict[str, float], exp: Experiment,
        bounds: ModelBounds | None = None,
        plant_base: dict[str, float] | None = None) -> RobotRun:
    """One controller on one reference; the plant starts on it at rest and has the
    parameters ``plant_base`` (default: the robot's defaults) with the experiment's
    payload schedule."""
    ffi, clib = lib.ffi, lib.lib
    cfg = controller_config(lib, code, name, formulation, nominal, exp, bounds)
    state = ffi.new(f"{code.prefix}_{name}_state_t *")
    status = getattr(clib, f"{code.prefix}_{name}_init")(state, cfg)
    if status != 0:  # the configuration is refused (e.g. ROC's bounds): nothing runs
        empty = np.zeros((0, code.nq))
        return RobotRun(name, formulation, path, ref.t[:0], empty, empty, empty,
                        np.zeros((0, code.nu)), np.zeros(0), 0, 0.0,
                        f"init refused the configuration: {_status_name(code, status)}")
    step = getattr(clib, f"{code.prefix}_{name}_step")
    real = f"{code.prefix}_real_t"
    buf = {k: ffi.new(f"{real}[{code.nq}]") for k in ("q", "qdot", "qd", "qdd", "qddd")}
    tau = ffi.new(f"{real}[{code.nu}]")
    plant = _Plant(lib, code, exp)
    h, nsub = exp.controller.h, exp.plant.substeps
    sensors = Odometry(code, ref.q[0], exp, nominal)
    motor = exp.sensing.velocity == "motor-encoder"
    n_window = round(sensors.window / (h / nsub)) if motor else 0
    act = list(code.actuated)
    x = np.concatenate([ref.q[0], np.zeros(code.nu)])
    window_start: Array | None = None
    rec: dict[str, list[Any]] = {k: [] for k in ("q", "qm", "tau", "gain")}
    saturated, failed_at, failure = 0, None, "ok"
    extra_on: bool | None = None  # the payload state the plant's parameters were set for
    for k in range(len(ref.t)):
        t = float(ref.t[k])
        q_true = x[: code.nq]
        q_meas, qdot_meas = (sensors.measure(q_true[act], x[code.nq:], window_start) if k
                             else (ref.q[0].copy(), np.zeros(code.nq)))
        for key, value in (("q", q_meas), ("qdot", qdot_meas), ("qd", ref.q[k]),
                           ("qdd", ref.qdot[k]), ("qddd", ref.qddot[k])):
            buf[key][0:code.nq] = value.tolist()
        status = step(state, cfg, buf["q"], buf["qdot"], buf["qd"], buf["qdd"], buf["qddd"], tau)
        if status < 0:
            failed_at, failure = t, _status_name(code, status)
            break
        saturated += status == 1
        tau_now = np.array([tau[i] for i in range(code.nu)])
        rec["q"].append(q_true.copy())
        rec["qm"].append(q_meas)
        rec["tau"].append(tau_now)
        rec["gain"].append(float(state.gain))
        if k == len(ref.t) - 1:
            break
        if exp.plant.extra_on(t) != extra_on:  # the payload changes only at its switches
            extra_on = exp.plant.extra_on(t)
            plant.set_params(plant_params_at(code, exp, t, plant_base))
        x = plant.advance(x, tau_now, h / nsub, nsub - n_window)
        if n_window:  # the motor encoder's window opens n_window substeps before t + h
            window_start = x[act].copy()
            x = plant.advance(x, tau_now, h / nsub, n_window)
        if not np.all(np.isfinite(x)):
            failed_at, failure = t, "non-finite plant state"
            break
    m = len(rec["q"])
    return RobotRun(name, formulation, path, ref.t[:m], np.array(rec["q"]), np.array(rec["qm"]),
                    ref.q[:m], np.array(rec["tau"]), np.array(rec["gain"]), int(saturated),
                    failed_at, failure)


def _status_name(code: RobotCode, status: int) -> str:
    names = {v: k for k, v in code.controllers.STATUS.items()}
    return f"{names.get(status, 'unknown status')} ({status})"
