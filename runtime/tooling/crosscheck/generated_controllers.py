"""The four generated C controllers of any robot (double and float32) against its generated
Python controller classes, step by step along measurement sequences.

Sequences, for each controller and each formulation the robot generates:

* ``loop``: what the controller measured in the closed loop (``runtime.sim.loop``: the
  generated plant, RK4 under zero-order hold, encoders and odometry, the C controller at
  the sample instants) tracking constant driven-wheel rates from rest, the plant carrying a
  payload the nominal model does not know (``plant_params_with_payload``), h = 0.1 s;
* ``near`` / ``far``: a random smooth motion (modulated wheel rates integrated through the
  generated kinematics q̇ = S(q) η; q̈ from the generated linearisation) measured, against
  a reference that is the motion plus a small smooth offset (near: ‖s‖ < ε occurs) or an
  unrelated motion (far: large errors, saturation), with a random configuration (gains,
  h, estimator, window, discount, bounds, a torque limit that saturates).

Each C controller steps through the recorded sequence open loop from its own init and is
compared per step with the Python controller (τ, switching gain, ‖s‖, Ĥ1, ``u_discarded``
and the saturation status). The float32 build is restarted every step from the Python
controller's state rounded to float32, on float32-rounded inputs and configuration, so its
deviation measures float32 arithmetic only.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from runtime.bindings.controller import Controller
from runtime.bindings.generated import RobotCode
from runtime.experiment.settings import Experiment, PlantSettings
from runtime.sim import loop
from runtime.sim.reference import wheel_rate_reference
from runtime.tooling.crosscheck.bindings import CModel
from runtime.tooling.crosscheck.deviation import (
    CONTROLLER_IMPLS,
    Arr,
    Deviation,
    Params,
    Row,
    Trace,
    f32,
    generated_deviation,
    perturbed,
)
from runtime.tooling.crosscheck.generated_functions import physical
from runtime.tooling.crosscheck.targets import Target

COVER_KEYS = (
    "steps", "saturated", "inside boundary layer", "outside boundary layer", "TDE active",
    "central estimator", "matched estimator", "window full (n Ω differences)",
)  # fmt: skip
LOOP_H = 0.1


@dataclass
class Run:
    """A measurement/reference sequence and the configuration to run it with."""

    name: str
    kind: str
    formulation: str
    config: Any  # the robot's controllers.Config
    q: Arr
    qdot: Arr
    q_des: Arr
    qdot_des: Arr
    qddot_des: Arr

    def inputs(self, k: int) -> tuple[Arr, Arr, Arr, Arr, Arr]:
        return self.q[k], self.qdot[k], self.q_des[k], self.qdot_des[k], self.qddot_des[k]

    def truncated(self, n: int) -> Run:
        return dataclasses.replace(self, q=self.q[:n], qdot=self.qdot[:n], q_des=self.q_des[:n],
                                   qdot_des=self.qdot_des[:n], qddot_des=self.qddot_des[:n])


def formulation_code(code: RobotCode, formulation: str) -> int:
    return int(getattr(code.controllers, f"FORMULATION_{formulation.upper()}"))


def _base_config(code: RobotCode, formulation: str, h: float) -> Any:
    return code.controllers.Config(
        nominal=dict(code.params), formulation=formulation_code(code, formulation),
        k1=[4.0] * code.nq, k2=[4.0] * code.nq, h=h, tau_max=50.0, eps=0.1,
        alpha=0.35, phi=2.0, gamma=2.0,
    )  # fmt: skip


def loaded_plant(code: RobotCode) -> Params:
    """The plant parameters with a 5 kg payload 0.1 m ahead and 0.05 m left of the root
    body's origin (the generated payload relation), or the defaults if there is none."""
    with_payload = getattr(code.plant, "plant_params_with_payload", None)
    if with_payload is None:
        return dict(code.plant_defaults)
    values = with_payload([5.0, 0.1, 0.05], code.plant_defaults)
    return dict(zip(code.plant_defaults, np.asarray(values, dtype=float).ravel(), strict=True))


def wheel_rates(code: RobotCode) -> Arr:
    """Constant driven-wheel rates for the loop: 2.0 down to 1.5 rad/s (a turn)."""
    return np.linspace(2.0, 1.5, code.nu)


def closed_loop(code: RobotCode, kind: str, formulation: str, seconds: float) -> Run:
    """What controller ``kind`` measured closing the loop (:func:`runtime.sim.loop.run`, the
    paper's setting at h = ``LOOP_H``, no friction, the payload of :func:`loaded_plant`),
    replayed with the base configuration."""
    h = LOOP_H
    ref = wheel_rate_reference(code, np.zeros(code.nq), wheel_rates(code), h, seconds,
                               code.params)
    exp = Experiment()
    exp = Experiment(controller=dataclasses.replace(exp.controller, h=h, tau_max=50.0),
                     plant=PlantSettings(substeps=10, viscous=0.0, coulomb=0.0,
                                         fixed_payload=0.0, extra_payload=0.0))
    r = loop.run(code, kind, formulation, ref, code.params, exp,
                 plant_params=loaded_plant(code))
    n = len(r.t)
    return Run(f"loop {kind}/{formulation}", kind, formulation,
               _base_config(code, formulation, h), r.q_meas, r.qdot_meas, ref.q[:n],
               ref.qdot[:n], ref.qddot[:n])


def _smooth(rng: np.random.Generator, amp: float, terms: int = 3
            ) -> Callable[[float], tuple[float, float]]:
    """A random smooth signal: (value, derivative) of a sum of sinusoids."""
    a = rng.uniform(0.2, 1.0, terms) * amp / terms
    w = rng.uniform(0.2, 2.0, terms)
    ph = rng.uniform(0, 2 * math.pi, terms)
    return lambda t: (float(np.sum(a * np.sin(w * t + ph))),
                      float(np.sum(a * w * np.cos(w * t + ph))))


def motion(code: RobotCode, rng: np.random.Generator, h: float, steps: int, p: Params,
           sub: int = 10) -> tuple[Arr, Arr, Arr]:
    """Sampled (q, q̇, q̈) of a random motion: wheel rates η(t) = base + sinusoids from a
    random configuration, q̇ = S(q) η (RK4, ``sub`` substeps per sample), and
    q̈ = ∂(S η)/∂q q̇ + S η̇."""
    base = rng.uniform(-4.0, 4.0, code.nu)
    mods = [_smooth(rng, 3.0) for _ in range(code.nu)]

    def rates(t: float) -> tuple[Arr, Arr]:
        vals = [m(t) for m in mods]
        return base + np.array([v for v, _ in vals]), np.array([d for _, d in vals])

    q = rng.uniform(-2.0, 2.0, code.nq)
    qs, qds, qdds = [], [], []
    dt = h / sub
    zero_tau = np.zeros(code.nu)
    for k in range(steps):
        t = k * h
        eta, etad = rates(t)
        qdot = code.velocities(q, eta, p)
        jac, _ = code.model.linearization(q, eta, zero_tau, p)
        qs.append(q.copy())
        qds.append(qdot)
        qdds.append(jac[: code.nq, : code.nq] @ qdot + code.velocities(q, etad, p))
        for j in range(sub):
            tj = t + j * dt

            def f(tt: float, x: Arr) -> Arr:
                return code.velocities(x, rates(tt)[0], p)

            k1 = f(tj, q)
            k2 = f(tj + dt / 2, q + dt / 2 * k1)
            k3 = f(tj + dt / 2, q + dt / 2 * k2)
            k4 = f(tj + dt, q + dt * k3)
            q = q + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return np.array(qs), np.array(qds), np.array(qdds)


def random_config(code: RobotCode, rng: np.random.Generator, kind: str, formulation: str,
                  accel: int) -> Any:
    c = code.controllers
    h = float(rng.uniform(0.05, 0.15))
    while True:  # nominal parameters the model accepts (see generated_functions.physical)
        nominal = {k: v * rng.uniform(0.8, 1.2) for k, v in code.params.items()}
        if physical(code, nominal, rng):
            break
    return c.Config(
        nominal=nominal,
        formulation=formulation_code(code, formulation),
        k1=rng.uniform(1.0, 8.0, code.nq).tolist(), k2=rng.uniform(1.0, 8.0, code.nq).tolist(),
        q_pos=float(rng.uniform(0.5, 2.0)), q_vel=float(rng.uniform(0.5, 2.0)), h=h,
        tau_max=float(rng.choice([50.0, 4.0])), accel_estimator=accel,
        rate_window=float(rng.uniform(0.0, h)) if accel == c.ACCEL_MATCHED else 0.0,
        eps=float(rng.uniform(0.02, 0.5)), n=int(rng.integers(2, c.MAX_WINDOW + 1)),
        a=float(rng.uniform(0.5, 1.0)), alpha=float(rng.uniform(0.0, 0.6)),
        phi=float(rng.uniform(0.0, 3.0)), gamma=float(rng.uniform(0.0, 5.0)),
        gain0=float(rng.uniform(0.0, 2.0)) if kind == "asmc" else 0.0,
    )  # fmt: skip


def random_run(code: RobotCode, rng: np.random.Generator, kind: str, formulation: str,
               near: bool, steps: int, accel: int) -> Run:
    config = random_config(code, rng, kind, formulation, accel)
    h, p = float(config.h), dict(config.nominal)
    q, qd, qdd = motion(code, rng, h, steps, p)
    if near:
        off = [_smooth(rng, 0.03) for _ in range(code.nq)]
        o = np.array([[off[i](k * h) for i in range(code.nq)] for k in range(steps)])
        ref = (q + o[:, :, 0], qd + o[:, :, 1], qdd + rng.normal(0.0, 0.1, qdd.shape))
    else:
        ref = motion(code, rng, h, steps, p)
    name = f"{'near' if near else 'far'} {kind}/{formulation}"
    return Run(name, kind, formulation, config, q, qd, *ref)


def sequences(target: Target, rng: np.random.Generator, quick: bool) -> list[Run]:
    code = target.code
    loop_seconds, steps = (3.0, 15) if quick else (6.0, 40)
    c = code.controllers
    # Each estimator in each time-delay controller's random runs (the loops use backward).
    estimators = (c.ACCEL_CENTRAL, c.ACCEL_MATCHED, c.ACCEL_BACKWARD)
    runs = []
    for i, kind in enumerate(code.controller_names):
        for form in code.controller(kind).formulations:
            runs.append(closed_loop(code, kind, form, loop_seconds))
            for near in (True, False):
                accel = estimators[(2 * i + (not near)) % 3]
                runs.append(random_run(code, rng, kind, form, near, steps, accel))
    return runs


# ------------------------------------------------------------------------ the runs
def _record_python(trace: Trace, ctl: Any) -> None:
    trace.record(ctl.tau, ctl.gain, ctl.s_norm, ctl.H1hat, ctl.u_discarded,
                 ctl.last_status.endswith("_WARN_SATURATED"))


def python_run(code: RobotCode, run: Run, cover: dict[str, int]) -> tuple[Run, Trace]:
    """The Python controller over ``run`` (cut before a step it rejects), counting the
    branches it took."""
    cls = code.controller_class(run.kind)
    ctl, c = cls(run.config), run.config
    trace = Trace()
    for k in range(len(run.q)):
        before = ctl.steps
        try:
            ctl.step(*run.inputs(k))
        except ValueError:
            return run.truncated(k), trace
        _record_python(trace, ctl)
        tde = cls.tde and before >= 2
        cover["steps"] += 1
        cover["saturated"] += trace.saturated[-1]
        if cls.switching:
            cover["inside boundary layer"] += ctl.s_norm < c.eps
            cover["outside boundary layer"] += ctl.s_norm >= c.eps
        cover["TDE active"] += tde
        cover["central estimator"] += tde and c.accel_estimator == code.controllers.ACCEL_CENTRAL
        cover["matched estimator"] += tde and c.accel_estimator == code.controllers.ACCEL_MATCHED
        cover["window full (n Ω differences)"] += bool(
            cls.window and not c.hold_gain and ctl.omega_count - 1 >= c.n)
    return run, trace


class CController:
    """A generated C controller through the bindings' wrapper
    (:class:`runtime.bindings.controller.Controller`), configured from a Python ``Config``
    (the crosscheck's own test configurations)."""

    def __init__(self, target: Target, float32: bool, kind: str, config: Any) -> None:
        self.m = CModel(target, float32)
        ffi, pre = self.m.ffi, self.m.prefix
        self.code = target.code
        self.kind = kind
        ctype = f"{pre}_{kind}_config_t"
        self.cfg = ffi.new(f"{ctype} *")
        for name, ftype in ffi.typeof(ctype).fields:
            value = getattr(config, name)
            if name == "nominal":
                self.m_fill(self.cfg.nominal, value)
            elif ftype.type.kind == "array":
                setattr(self.cfg, name, [float(v) for v in value])
            elif ftype.type.cname in ("int", "long"):
                setattr(self.cfg, name, int(value))
            else:
                setattr(self.cfg, name, float(value))
        self.ctl = Controller(self.m.lib, pre, kind, self.cfg, self.code.nq, self.code.nu)
        self.state = self.ctl.state
        self.state_fields = [n for n, _ in ffi.typeof(self.state[0]).fields]
        status = self.ctl.init()
        if status != 0:
            raise RuntimeError(f"{pre}_{kind}_init returned {status}")
        self.saturated = next(v for k, v in self.code.controllers.STATUS.items()
                              if k.endswith("_WARN_SATURATED"))

    def m_fill(self, obj: Any, values: Mapping[str, float]) -> None:
        from runtime.bindings import cbuild

        keys = self.code.controllers.PARAM_KEYS
        cbuild.fill_params(obj, {k: values[k] for k in keys}, self.m.field_names)

    def step(self, *inputs: Arr) -> int:
        status = self.ctl.step([np.asarray(v, dtype=float).tolist() for v in inputs])
        if status < 0:
            raise RuntimeError(f"{self.m.prefix}_{self.kind}_step returned {status}")
        return status

    def record(self, trace: Trace, status: int) -> None:
        st = self.state
        trace.record(list(st.tau), st.gain, st.s_norm, list(st.H1hat), st.u_discarded,
                     status == self.saturated)

    def load(self, ctl: Any) -> None:
        """Overwrite the C state with the Python controller's (same field names; the
        validity mark, the configuration copy and the cached ‖M̂⁻¹‖ stay the C's own: C
        keeps and compares the float32 values it holds)."""
        for name in self.state_fields:
            if name in ("magic", "config", "minv_norm") or not hasattr(ctl, name):
                continue
            value = getattr(ctl, name)
            if isinstance(value, np.ndarray):
                value = value.tolist()
            setattr(self.state, name, value)


def c_run(target: Target, run: Run, config: Any) -> Trace:
    ctl = CController(target, False, run.kind, config)
    trace = Trace()
    for k in range(len(run.q)):
        ctl.record(trace, ctl.step(*run.inputs(k)))
    return trace


def _round_config(config: Any) -> Any:
    changes: dict[str, Any] = {}
    for f in dataclasses.fields(config):
        v = getattr(config, f.name)
        if isinstance(v, Mapping):
            changes[f.name] = {k: f32(float(x)) for k, x in v.items()}
        elif isinstance(v, float):
            changes[f.name] = f32(v)
        elif isinstance(v, list | tuple | np.ndarray):
            changes[f.name] = f32(np.asarray(v, dtype=float)).tolist()
    return dataclasses.replace(config, **changes)


def _round_state(ctl: Any, names: list[str]) -> None:
    for name in names:
        if isinstance(getattr(type(ctl), name, None), property):
            continue  # derived from the rounded fields (omega_ring, trig_prev)
        v = getattr(ctl, name, None)
        if isinstance(v, float) or (isinstance(v, np.ndarray) and v.dtype.kind == "f"):
            setattr(ctl, name, f32(v))


def c32_synced_run(target: Target, run: Run, perturb: Mapping[str, Mapping[str, float]]
                   ) -> tuple[Trace, Trace]:
    """float32 C per step from the Python controller's rounded state, on rounded inputs.

    Returns (float32 trace, Python trace on the same rounded inputs and states)."""
    config = _round_config(run.config)
    ref = target.code.controller_class(run.kind)(config)
    c_config = dataclasses.replace(config, nominal=perturbed(config.nominal, "c32", perturb))
    c32 = CController(target, True, run.kind, c_config)
    got, want = Trace(), Trace()
    for k in range(len(run.q)):
        _round_state(ref, c32.state_fields)
        c32.load(ref)
        args = [f32(x) for x in run.inputs(k)]
        c32.record(got, c32.step(*args))
        ref.step(*args)
        _record_python(want, ref)
    return got, want


def compare(dev: Deviation, got: Trace, ref: Trace, check_status: bool) -> None:
    dev.add("tau", got.tau, ref.tau)
    dev.add("gain", got.gain, ref.gain)
    dev.add("|s|", got.s_norm, ref.s_norm)
    dev.add("H1hat", got.H1hat, ref.H1hat)
    dev.add("u_disc", got.u_discarded, ref.u_discarded)
    if check_status and got.saturated != ref.saturated:
        dev.merge(math.inf, "saturation status")


def check_controllers(
    target: Target, runs: list[Run], perturb: Mapping[str, Mapping[str, float]]
) -> tuple[list[Row], dict[str, int], int]:
    """Rows (controller/formulation) of the C double and float32 deviations from the
    Python classes, the branch counts, and the number of steps compared."""
    rows: dict[str, Row] = {}
    cover = dict.fromkeys(COVER_KEYS, 0)
    n_steps = 0
    for run in runs:
        run, ref = python_run(target.code, run, cover)
        n_steps += len(run.q)
        row = rows.setdefault(f"{run.kind}/{run.formulation}", Row(f"{run.kind}/{run.formulation}"))
        cells = {impl: row.cells.setdefault(impl, generated_deviation(impl))
                 for impl in CONTROLLER_IMPLS}
        c64_config = dataclasses.replace(
            run.config, nominal=perturbed(run.config.nominal, "c64", perturb))
        try:
            compare(cells["c64"], c_run(target, run, c64_config), ref, True)
        except RuntimeError as exc:
            cells["c64"].merge(math.inf, str(exc).split()[-1])
        try:
            got32, want32 = c32_synced_run(target, run, perturb)
            compare(cells["c32"], got32, want32, False)
        except RuntimeError as exc:
            cells["c32"].merge(math.inf, str(exc).split()[-1])
    return list(rows.values()), cover, n_steps
