"""The closed loop: a robot's generated C controller against a plant, for every robot and
every command.

Each sample k (t = k h), in this order:

1. the sensors (:class:`runtime.sim.sensors.Sensors`) read the plant's driven-wheel
   encoders and give (q, q̇) as measured (sample 0: the reference's start at rest);
   faults (:mod:`runtime.experiment.faults`) miscount encoders, repeat or drop the sample;
2. the controller's ``_step`` (:class:`runtime.bindings.controller.Controller`, configured
   by :func:`runtime.bindings.config.controller_config`) turns them and the reference into
   τ; a status < 0 stops the run there; a dropped sample keeps the last τ (zero-order hold);
3. the plant (:class:`runtime.sim.plant.Plant`, the one ``[plant] model`` names, built by
   the registry :mod:`runtime.plants`; default the generated model in C,
   :class:`runtime.sim.plant.GeneratedPlant`) gets its true
   parameters and payload (payload schedule, :mod:`runtime.sim.payload`) when they change, the
   actuators deliver τ (a torque limit fault clips it), and the robot moves for h under it
   (``substeps`` RK4 steps; the motor-encoder's window start is read on the way). With a
   delay (``controller.delay``/``delay_time``, each sample's within ± the jitter bound,
   drawn by a seeded generator, or a given sequence of periods and latencies:
   :mod:`runtime.sim.timing`), the torque computed at t_k reaches the actuators at
   t_k + D_k: until then the plant gets the latest command that has arrived
   (:class:`Latency`; without a delay, the command of t_k from t_k on). The plant
   advances over the sample piece by piece (:func:`advance_pieces`).

The switching term Δu_a of (24)/(25) recorded per sample (:attr:`Run.wheel_switching`) is
computed here from the state's P, gain and ‖s‖ (:func:`_switching`): the generated C state
keeps ‖s‖ and the gain, not Δu_a itself.

Nothing here knows the robot or the controller: sizes, actuated coordinates, controller
features and state fields come from the generated code.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from runtime.bindings.config import controller_config
from runtime.bindings.controller import Controller
from runtime.bindings.generated import RobotCode
from runtime.experiment.faults import Fault, schedule
from runtime.experiment.settings import Experiment
from runtime.sim.payload import payload_mass, payload_masses, plant_params_at
from runtime.sim.plant import Plant, generated_plant, library_for, plant_base
from runtime.sim.reference import Reference
from runtime.sim.sensors import Sensors
from runtime.sim.timing import DrawnTiming, Schedule

Array = NDArray[np.float64]
NOT_CALLED = -(2**31)  # Run.status of a sample whose step was not called (dropped)
NON_FINITE = "non-finite plant state"  # Run.stop_reason when the plant's state blew up


class Latency:
    """The commands in flight between the controller and the actuators: each command is
    delivered its sample's latency after its sample (the timing :class:`Schedule`; never
    before its sample); a command overtaken by a later one that arrived first is dropped.
    Without delay nor jitter each command acts from its own sample on: one piece per
    sample, the zero-order hold (every run goes through here, delayed or not)."""

    def __init__(self, timing: Schedule, initial: Array) -> None:
        self.timing = timing
        self.active = np.array(initial, dtype=np.float64)
        self.sent = -1  # index of the command now active
        self.pending: list[tuple[float, int, Array]] = []  # (arrival, index, τ)

    def send(self, t: float, k: int, tau: Array) -> None:
        """The command of sample k (at time t) leaves the controller."""
        d = self.timing.latency(k)
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
    refused: str | None = None  # why the configuration checks refused it (no sample ran)

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
    faults: Sequence[Fault] = (),
    bounds: tuple[float, float] | None = None,
    timing: Schedule | None = None,
) -> Run:
    """Simulate controller ``name`` in ``formulation`` on ``ref`` with the nominal model
    ``nominal``. ``plant_params``: the simulated robot before payload (default: the nominal
    model with the plant-only parameters at the robot's defaults,
    :func:`runtime.sim.plant.plant_base`); ``plant``: the :class:`Plant` to run (default:
    the generated model, the default ``[plant] model``; another model's plant is built by
    the registry, :func:`runtime.plants.plant_for`); ``float32``: the single-precision
    build of the controllers and the plant; ``held_gain``: k̂ held at that value (the
    stability analysis' verification); ``faults``: injected as ``runtime.experiment.faults``
    describes; ``bounds``: ROC's (α, φ) if not sampled; ``timing``: each sample's
    period and latency (:mod:`runtime.sim.timing`; default the experiment's h and delay ±
    jitter, :class:`runtime.sim.timing.DrawnTiming`). The run does not judge the
    configuration: refusing one the toolchain predicts will fail is the caller's
    (:func:`runtime.stability.checks.check_configuration`)."""
    lib = library_for(code, float32)
    info = code.controller(name)
    cfg = controller_config(lib, code, name, formulation, nominal, exp, held_gain=held_gain,
                            bounds=bounds)
    ctl = Controller(lib, code.prefix, name, cfg, code.nq, code.nu)
    status = ctl.init()
    if status != 0:  # the configuration is refused (e.g. ROC's bounds): nothing runs
        return not_run(code, name, formulation, ref, "init refused the configuration: "
                       f"{ctl.status_name(status)} ({status})", status)
    base = plant_base(code, nominal, plant_params)
    if plant is None:
        if exp.plant.model != "generated":
            raise ValueError(f"[plant] model {exp.plant.model!r}: pass its plant "
                             "(runtime.plants.plant_for); the loop builds only the generated one")
        plant = generated_plant(code, lib, exp)
    h, nsub, n = exp.controller.h, exp.plant.substeps, len(ref.t)
    plant.start(ref.q[0])
    sensors = Sensors(code, np.array(ref.q[0]), exp, dict(nominal))
    # The motor encoder's rate spans the sample's last `window` s: the plant is read there.
    window = sensors.window if exp.sensing.velocity == "motor-encoder" else 0.0
    window_start: Array | None = None
    sched = schedule(faults, h, n)
    if sched.encoder_offset.shape[1] != code.nu:
        raise ValueError(f"robot '{code.name}': the faults are written for two driven wheels, "
                         f"it has {code.nu}")
    act = list(code.actuated)
    rows = list(range(code.nq)) if formulation == "paper" else act
    if timing is None:
        timing = DrawnTiming(ref.t, h, exp.controller.delay_seconds(),
                             exp.controller.jitter_seconds())
    # Without a delay each command acts from its own sample on (one piece per sample).
    latency = Latency(timing, np.zeros(code.nu))
    rec = _Record()
    delivered = (ref.q[0].copy(), np.zeros(code.nq))
    prev_gain = float(ctl.read("gain"))  # an adaptive gain before each step's adaptation
    payload_on: bool | None = None  # the payload state the plant's parameters were set for
    for k in range(n):
        # the plant's clock and period (the law keeps ref.t[k] and its configured h)
        t, hk = timing.start(k), timing.period(k)
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
                rec.stop = (t, status, ctl.status_name(status))
                break
            rec.saturated += status == 1
            latency.send(t, k, ctl.torque())
        if exp.plant.extra_on(t) != payload_on:  # the payload changes at its switches
            payload_on = exp.plant.extra_on(t)
            plant.set_parameters(plant_params_at(code, exp, t, base))
            plant.set_payload(payload_masses(exp, t))
        plant.set_faults(sched.traction_loss[k], sched.torque_limit[k])
        # What the actuators deliver over [t, t + h_k): (start within the sample, τ) pieces.
        pieces = [(a - t, plant.actuate(cmd)) for a, cmd in latency.pieces(t, t + hk)]
        gain, s_norm = ctl.read("gain"), ctl.read("s_norm")
        h1 = ctl.read("H1hat", None)
        err = np.concatenate([ref.q[k, rows] - q_meas[rows], ref.qdot[k, rows] - qdot_meas[rows]])
        rec.add(
            q=true_q, q_meas=q_meas, qdot_meas=qdot_meas, tau=ctl.torque(),
            tau_applied=pieces[-1][1], gain=gain, s_norm=s_norm,
            u_discarded=ctl.read("u_discarded"),
            h1hat=[h1[i] for i in range(code.nq)] if h1 is not None else [0.0] * code.nq,
            error_norm=float(np.linalg.norm(err)),
            wheel_switching=_switching(ctl, info.switching,
                                       prev_gain if info.adaptive else gain, s_norm,
                                       exp.controller.eps, ref, k, q_meas, qdot_meas, act),
            payload=payload_mass(exp, t), status=status,
        )
        prev_gain = gain
        if k == n - 1:
            break
        ok, window_start = advance_pieces(plant, pieces, hk, nsub, window)
        if not ok:
            rec.stop = (t, None, NON_FINITE)
            break
    return rec.run(code, name, formulation, ref)


@dataclass
class _Record:
    """What :func:`run` records: one entry per sample in each list, named as :class:`Run`
    names its arrays; ``saturated``: samples whose torque was clipped; ``stop``: (t, the
    status < 0 or None, reason) of what stopped the run."""

    q: list[Array] = field(default_factory=list)
    q_meas: list[Array] = field(default_factory=list)
    qdot_meas: list[Array] = field(default_factory=list)
    tau: list[Array] = field(default_factory=list)
    tau_applied: list[list[float]] = field(default_factory=list)
    gain: list[float] = field(default_factory=list)
    s_norm: list[float] = field(default_factory=list)
    u_discarded: list[float] = field(default_factory=list)
    h1hat: list[list[float]] = field(default_factory=list)
    error_norm: list[float] = field(default_factory=list)
    wheel_switching: list[list[float]] = field(default_factory=list)
    payload: list[float] = field(default_factory=list)
    status: list[int] = field(default_factory=list)
    saturated: int = 0
    stop: tuple[float, int | None, str] | None = None

    def add(self, *, q: Array, q_meas: Array, qdot_meas: Array, tau: Array,
            tau_applied: list[float], gain: float, s_norm: float, u_discarded: float,
            h1hat: list[float], error_norm: float, wheel_switching: list[float],
            payload: float, status: int) -> None:
        """One sample's values, one per list."""
        self.q.append(q)
        self.q_meas.append(q_meas)
        self.qdot_meas.append(qdot_meas)
        self.tau.append(tau)
        self.tau_applied.append(tau_applied)
        self.gain.append(gain)
        self.s_norm.append(s_norm)
        self.u_discarded.append(u_discarded)
        self.h1hat.append(h1hat)
        self.error_norm.append(error_norm)
        self.wheel_switching.append(wheel_switching)
        self.payload.append(payload)
        self.status.append(status)

    def run(self, code: RobotCode, name: str, formulation: str, ref: Reference) -> Run:
        """The :class:`Run` of the samples recorded (N × nq, N × nu arrays)."""
        m = len(self.q)

        def rows(values: Sequence[Any], width: int) -> Array:
            return np.array(values).reshape(-1, width)

        failed_at, stop_status, stop_reason = self.stop or (None, None, None)
        return Run(
            controller=name, formulation=formulation, path=ref.name, t=ref.t[:m],
            q=rows(self.q, code.nq), q_meas=rows(self.q_meas, code.nq),
            qdot_meas=rows(self.qdot_meas, code.nq), q_des=ref.q[:m],
            tau=rows(self.tau, code.nu), tau_applied=rows(self.tau_applied, code.nu),
            gain=np.array(self.gain), s_norm=np.array(self.s_norm),
            u_discarded=np.array(self.u_discarded), h1hat=rows(self.h1hat, code.nq),
            error_norm=np.array(self.error_norm),
            wheel_switching=rows(self.wheel_switching, code.nu),
            payload=np.array(self.payload), status=np.array(self.status, dtype=np.int64),
            saturated=int(self.saturated), failed_at=failed_at, stop_status=stop_status,
            stop_reason=stop_reason,
        )


def advance_pieces(plant: Plant, pieces: list[tuple[float, list[float]]], h: float,
                   nsub: int, window: float) -> tuple[bool, Array | None]:
    """The plant over one sample under piecewise-constant torques ((start within the sample,
    τ) pieces), each piece in RK4 steps no longer than h / nsub (exactly h / nsub where the
    piece is a whole number of them); (finite, the driven wheels' angles at the window's
    start h − ``window`` if ``window``)."""
    dt = h / nsub
    marks = sorted({0.0, h, *(a for a, _ in pieces if 0 < a < h),
                    *([h - window] if window > 0 else [])})
    start: Array | None = None
    for a, b in itertools.pairwise(marks):
        if window > 0 and abs(a - (h - window)) < 1e-12:
            start = plant.wheels()[0]
        tau = [cmd for t0, cmd in pieces if t0 <= a + 1e-12][-1]
        steps = max(1, math.ceil((b - a) / dt - 1e-9))
        step = dt if abs(steps * dt - (b - a)) < 1e-12 else (b - a) / steps
        if not plant.advance(tau, step, steps):
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


def not_run(code: RobotCode, name: str, formulation: str, ref: Reference, reason: str,
            init_status: int = 0) -> Run:
    """The record of a run that did not start: no sample, ``reason`` as its stop reason;
    ``init_status``: what ``_init`` returned if it refused the configuration, else the run
    was refused before it (:attr:`Run.refused`, the caller's configuration checks)."""
    def empty(width: int) -> Array:
        return np.zeros((0, width))

    none = np.zeros(0)
    return Run(name, formulation, ref.name, ref.t[:0], empty(code.nq), empty(code.nq),
               empty(code.nq), ref.q[:0], empty(code.nu), empty(code.nu), none, none, none,
               empty(code.nq), none, empty(code.nu), none, np.zeros(0, dtype=np.int64), 0,
               0.0, init_status or None, reason, init_status,
               None if init_status else reason)
