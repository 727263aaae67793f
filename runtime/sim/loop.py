"""The closed loop: a robot's generated C controller against a plant, for every robot and
every command.

Each sample k (t = k h), in this order:

1. the sensors (:class:`runtime.sim.sensors.Sensors`) read the plant's driven-wheel
   encoders and give (q, q̇) as measured (sample 0: the reference's start at rest);
   faults (:mod:`runtime.sim.faults`) miscount encoders, repeat or drop the sample;
2. the controller's ``_step`` (:class:`runtime.bindings.controller.Controller`, configured
   by :func:`runtime.bindings.config.controller_config`) turns them and the reference into
   τ; a status < 0 stops the run there; a dropped sample keeps the last τ (zero-order hold);
3. the plant (:class:`runtime.sim.plant.Plant`, the one ``[plant] model`` names; default
   the generated model in C, :class:`runtime.sim.plant.GeneratedPlant`) gets its true
   parameters and payload (payload schedule, :mod:`runtime.sim.payload`) when they change, the
   actuators deliver τ (a torque limit fault clips it), and the robot moves for h under it
   (``substeps`` RK4 steps; the motor-encoder's window start is read on the way). With a
   delay (``controller.delay``/``delay_time``, each sample's within ± the jitter bound,
   drawn by a seeded generator), the torque computed at t_k reaches the actuators at
   t_k + D_k: until then the plant gets the latest command that has arrived
   (:class:`Latency`).

Nothing here knows the robot or the controller: sizes, actuated coordinates, controller
features and state fields come from the generated code.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from runtime.bindings.config import controller_config
from runtime.bindings.controller import Controller
from runtime.bindings.generated import RobotCode
from runtime.experiment.settings import Experiment
from runtime.sim.faults import Fault, schedule
from runtime.sim.payload import payload_mass, payload_masses, plant_params_at
from runtime.sim.plant import Plant, library_for, make_plant
from runtime.sim.reference import Reference
from runtime.sim.sensors import Sensors

Array = NDArray[np.float64]
NOT_CALLED = -(2**31)  # Run.status of a sample whose step was not called (dropped)
NON_FINITE = "non-finite plant state"  # Run.stop_reason when the plant's state blew up
JITTER_SEED = 29  # the jitter's draws: the same run every time


class Latency:
    """The commands in flight between the controller and the actuators: each command is
    delivered ``delay`` s after its sample, ± a uniform draw within ``jitter`` (never
    before its sample); a command overtaken by a later one that arrived first is dropped."""

    def __init__(self, delay: float, jitter: float, initial: Array) -> None:
        self.delay, self.jitter = delay, jitter
        self.rng = np.random.default_rng(JITTER_SEED)
        self.active = np.array(initial, dtype=np.float64)
        self.sent = -1  # index of the command now active
        self.pending: list[tuple[float, int, Array]] = []  # (arrival, index, τ)

    def send(self, t: float, k: int, tau: Array) -> None:
        """The command of sample k (at time t) leaves the controller."""
        d = self.delay
        if self.jitter > 0:
            d += float(self.rng.uniform(-self.jitter, self.jitter))
        self.pending.append((t + max(0.0, d), k, np.array(tau, dtype=np.float64)))
        self.pending.sort(key=lambda p: (p[0], p[1]))

    def pieces(self, t0: float, t1: float) -> list[tuple[float, Array]]:
        """The torque the actuators get over [t0, t1): (start, τ) pieces."""
        out = [(t0, self.active.copy())]
        while self.pending and self.pending[0][0] < t1 - 1e-12:
            arrival, k, tau = self.pending.pop(0)
            if k < self.sent:
                continue  # a later command is already acting
            self.sent, self.active = k, tau
            if arrival <= out[-1][0] + 1e-12:
                out[-1] = (out[-1][0], tau.copy())
            else:
                out.append((arrival, tau.copy()))
        return out


@dataclass(frozen=True)
class Run:
    """One closed-loop run, sampled at the control instants (N samples; N × nq, N × nu)."""

    controller: str
    formulation: str
    path: str
    t: Array
    q: Array  # true q
    q_meas: Array  # q as the controller was given it
    qdot_meas: Array
    q_des: Array
    tau: Array  # commanded (held on a dropped sample)
    tau_applied: Array  # what the actuators delivered (differs under a torque limit)
    gain: Array  # the state's switching gain after each step (k̂, ρ)
    s_norm: Array  # ‖s‖ of each step
    u_discarded: Array  # ‖u rows τ = Bᵀu discards‖ (paper formulation)
    h1hat: Array  # the controller's Ĥ1 (TDC/TDROC) or Ĥ per step
    error_norm: Array  # ‖(e, ė)‖ over the controlled coordinates, as the controller measures
    wheel_switching: Array  # Δu_a = k s / max(‖s‖, ε) of (24)/(25) on the driven-wheel rows
    payload: Array  # payload on board (kg)
    status: Array  # what step returned per sample (NOT_CALLED: a dropped sample)
    saturated: int  # samples whose torque was clipped to tau_max
    failed_at: float | None  # t of the sample that stopped the run
    stop_status: int | None = None  # the status < 0 that stopped it, if a step did
    stop_reason: str | None = None  # why it stopped (a status name, NON_FINITE, init refused)
    init_status: int = 0  # what _init returned (not 0: refused, no sample ran)

    @property
    def position_error(self) -> Array:
        """Distance of the root's frame origin (x, y) from its reference."""
        return np.asarray(np.linalg.norm(self.q[:, :2] - self.q_des[:, :2], axis=1))


def run(
    code: RobotCode,
    name: str,
    formulation: str,
    ref: Reference,
    nominal: Mapping[str, float],
    exp: Experiment,
    *,
    plant_params: Mapping[str, float] | None = None,
    plant: Plant | None = None,
    float32: bool = False,
    held_gain: float | None = None,
    check: bool = False,
    faults: Sequence[Fault] = (),
    bounds: tuple[float, float] | None = None,
) -> Run:
    """Simulate controller ``name`` in ``formulation`` on ``ref`` with the nominal model
    ``nominal``. ``plant_params``: the simulated robot before payload (default: the nominal
    model with the plant-only parameters at the robot's defaults, e.g. K_lat = 0); ``plant``:
    a :class:`Plant` instance (default: the one the experiment's ``[plant] model`` names,
    :func:`runtime.sim.plant.make_plant`); ``float32``: the single-precision build of the
    controllers and the plant; ``held_gain``: k̂ held at that value (the stability
    analysis' verification); ``check``: refuse a configuration the toolchain's checks refuse
    (``ValueError``: the TDE condition over the uncertainty box, the sampled loop's
    predicted stability); ``faults``: injected as ``runtime.sim.faults`` describes;
    ``bounds``: ROC's (α, φ) if not sampled."""
    if check:
        from runtime.stability.checks import check_configuration

        check_configuration(code, name, formulation, nominal, exp)
    lib = library_for(code, float32)
    info = code.controller(name)
    cfg = controller_config(lib, code, name, formulation, nominal, exp, held_gain=held_gain,
                            bounds=bounds)
    ctl = Controller(lib, code.prefix, name, cfg, code.nq, code.nu)
    status = ctl.init()
    if status != 0:  # the configuration is refused (e.g. ROC's bounds): nothing runs
        return _refused(code, name, formulation, ref, status, ctl.status_name(status))
    base = dict({**code.plant_defaults, **nominal} if plant_params is None else plant_params)
    if plant is None:
        plant = make_plant(code, lib, exp, base)
    h, nsub = exp.controller.h, exp.plant.substeps
    plant.start(ref.q[0])
    sensors = Sensors(code, np.array(ref.q[0]), exp, dict(nominal))
    # Substeps before the motor-encoder window opens (none for the other models).
    motor = exp.sensing.velocity == "motor-encoder"
    n_window = round(sensors.window / (h / nsub)) if motor else 0
    window_start: Array | None = None
    n = len(ref.t)
    sched = schedule(faults, h, n)
    if sched.encoder_offset.shape[1] != code.nu:
        raise ValueError(f"robot '{code.name}': the faults are written for two driven wheels, "
                         f"it has {code.nu}")
    act = list(code.actuated)
    rows = list(range(code.nq)) if formulation == "paper" else act
    delay, jitter = exp.controller.delay_seconds(), exp.controller.jitter_seconds()
    latency = Latency(delay, jitter, np.zeros(code.nu)) if delay or jitter else None
    rec: dict[str, list[Any]] = {k: [] for k in (
        "q", "qm", "qdm", "tau", "ta", "gain", "s", "ud", "h1", "en", "sw", "load", "st")}
    delivered = (ref.q[0].copy(), np.zeros(code.nq))
    saturated, failed_at = 0, None
    stop_status: int | None = None
    stop_reason: str | None = None
    prev_gain = float(ctl.read("gain"))  # an adaptive gain before each step's adaptation
    payload_on: bool | None = None  # the payload state the plant's parameters were set for
    eps = exp.controller.eps
    for k in range(n):
        t = float(ref.t[k])
        true_q = plant.q
        wheel_angles, wheel_rates = plant.wheels()
        sensors.offset = sched.encoder_offset[k]
        sensors.window_offset = sched.encoder_offset[k - 1] if k else np.zeros(code.nu)
        sensed = (sensors.measure(wheel_angles, wheel_rates, window_start) if k
                  else (ref.q[0].copy(), np.zeros(code.nq)))
        # A repeated sample delivers the previous delivery again.
        q_meas, qdot_meas = delivered if sched.repeated[k] else sensed
        delivered = (q_meas, qdot_meas)
        if sched.dropped[k]:  # the step is not called; the drive holds the last torque
            status = NOT_CALLED
        else:
            status = ctl.step((q_meas, qdot_meas, ref.q[k], ref.qdot[k], ref.qddot[k]))
            if status < 0:
                failed_at, stop_status = t, status
                stop_reason = ctl.status_name(status)
                break
            saturated += status == 1
        if exp.plant.extra_on(t) != payload_on:  # the payload changes at its switches
            payload_on = exp.plant.extra_on(t)
            plant.set_parameters(plant_params_at(code, exp, t, base))
            plant.set_payload(payload_masses(exp, t))
        tau = [ctl.tau[i] for i in range(code.nu)]
        gain = ctl.read("gain")
        s_norm = ctl.read("s_norm")
        rec["q"].append(true_q)
        rec["qm"].append(q_meas)
        rec["qdm"].append(qdot_meas)
        rec["tau"].append(tau)
        rec["gain"].append(gain)
        rec["s"].append(s_norm)
        rec["ud"].append(ctl.read("u_discarded"))
        h1 = ctl.read("H1hat", None)
        rec["h1"].append([h1[i] for i in range(code.nq)] if h1 is not None
                         else [0.0] * code.nq)
        rec["load"].append(payload_mass(exp, t))
        err = np.concatenate([ref.q[k, rows] - q_meas[rows], ref.qdot[k, rows] - qdot_meas[rows]])
        rec["en"].append(float(np.linalg.norm(err)))
        rec["sw"].append(_switching(ctl, info.switching, prev_gain if info.adaptive else gain,
                                    s_norm, eps, ref, k, q_meas, qdot_meas, act))
        prev_gain = gain
        plant.set_faults(sched.traction_loss[k], sched.torque_limit[k])
        if latency is None:
            applied = plant.actuate(np.asarray(tau))
            rec["st"].append(status)
            rec["ta"].append(applied)
            if k == n - 1:
                break
            ok = plant.advance(applied, h / nsub, nsub - n_window)
            if ok and n_window:  # the motor encoder's window opens n_window substeps before t + h
                window_start = plant.wheels()[0]
                ok = plant.advance(applied, h / nsub, n_window)
        else:
            if not sched.dropped[k]:
                latency.send(t, k, np.asarray(tau))
            pieces = [(a - t, plant.actuate(cmd)) for a, cmd in latency.pieces(t, t + h)]
            rec["st"].append(status)
            rec["ta"].append(pieces[-1][1])
            if k == n - 1:
                break
            ok, start = advance_pieces(plant, pieces, h, nsub, sensors.window if motor else 0.0)
            window_start = start if motor else None
        if not ok:
            failed_at, stop_reason = t, NON_FINITE
            break
    m = len(rec["q"])
    return Run(
        name, formulation, ref.name, ref.t[:m],
        np.array(rec["q"]).reshape(-1, code.nq),
        np.array(rec["qm"]).reshape(-1, code.nq),
        np.array(rec["qdm"]).reshape(-1, code.nq),
        ref.q[:m],
        np.array(rec["tau"]).reshape(-1, code.nu),
        np.array(rec["ta"]).reshape(-1, code.nu),
        np.array(rec["gain"]), np.array(rec["s"]), np.array(rec["ud"]),
        np.array(rec["h1"]).reshape(-1, code.nq), np.array(rec["en"]),
        np.array(rec["sw"]).reshape(-1, code.nu), np.array(rec["load"]),
        np.array(rec["st"], dtype=np.int64), int(saturated), failed_at, stop_status,
        stop_reason,
    )


def advance_pieces(plant: Plant, pieces: list[tuple[float, list[float]]], h: float,
                   nsub: int, window: float) -> tuple[bool, Array | None]:
    """The plant over one sample under piecewise-constant torques ((start within the sample,
    τ) pieces), each piece in RK4 steps no longer than h / nsub; (finite, the driven wheels'
    angles at the window's start h − ``window`` if ``window``)."""
    marks = sorted({0.0, h, *(a for a, _ in pieces if 0 < a < h),
                    *([h - window] if window > 0 else [])})
    start: Array | None = None
    for a, b in itertools.pairwise(marks):
        if window > 0 and abs(a - (h - window)) < 1e-12:
            start = plant.wheels()[0]
        tau = [cmd for t0, cmd in pieces if t0 <= a + 1e-12][-1]
        steps = max(1, math.ceil((b - a) / (h / nsub) - 1e-9))
        if not plant.advance(tau, (b - a) / steps, steps):
            return False, start
    return True, start


def _switching(ctl: Controller, switching: bool, gain: float, s_norm: float, eps: float,
               ref: Reference, k: int, q_meas: Array, qdot_meas: Array,
               act: list[int]) -> list[float]:
    """Δu_a = k s / max(‖s‖, ε) of (24)/(25) on the driven-wheel rows, s_j = p12_j e_j +
    p22_j ė_j (from the state's P), with the gain and ‖s‖ the C step used (an adaptive
    gain: the one before adaptation); zeros without a switching term."""
    if not switching:
        return [0.0] * len(act)
    p12, p22 = ctl.read("p12"), ctl.read("p22")
    s_w = [p12[i] * (ref.q[k, i] - q_meas[i]) + p22[i] * (ref.qdot[k, i] - qdot_meas[i])
           for i in act]
    denom = max(s_norm, eps)
    return [gain * v / denom for v in s_w]


def _refused(code: RobotCode, name: str, formulation: str, ref: Reference, status: int,
             status_name: str) -> Run:
    """The record of a run whose configuration ``_init`` refused: no sample."""
    def empty(width: int) -> Array:
        return np.zeros((0, width))

    none = np.zeros(0)
    return Run(name, formulation, ref.name, ref.t[:0], empty(code.nq), empty(code.nq),
               empty(code.nq), ref.q[:0], empty(code.nu), empty(code.nu), none, none, none,
               empty(code.nq), none, empty(code.nu), none, np.zeros(0, dtype=np.int64), 0,
               0.0, status, f"init refused the configuration: {status_name} ({status})",
               status)
