"""Closed-loop simulation: the generated C controllers against the simulated robot.

Plant: the constrained dynamics derived with a lateral first moment (``wmr_plant``),
true parameters = robot + payload schedule, wheel friction (viscous + Coulomb) unknown to
the controllers, fixed-step RK4 in C (``runtime/paper/csrc/wmr_sim.c``) at ``substeps / h``.
Controllers: sampled every h with zero-order hold, fed what the experiment's ``[sensing]``
says is measured — wheel angles from quadrature encoders (4 × ppr counts per revolution,
times the gear ratio for a motor-side encoder), wheel rates at the sample instant, or
differenced over the sample or over a short window, and the pose by integrating (31) from
the encoder angles (odometry).
Faults (``runtime.faults``): encoder miscounts, dropped or repeated samples, wheel slip and
actuator torque limits, injected when ``run`` is given them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from runtime import cbuild
from runtime.experiment import Experiment
from runtime.faults import Fault, schedule
from runtime.generated_modules import robot as generated_robot
from runtime.generated_modules import wmr_model
from runtime.paper.controller_config import (
    ACCEL_CODES,
    FORMULATIONS,
    checked_controller_config,
    controller_config,
    roc_bounds,
)
from runtime.paper.payload_schedule import plant_params
from runtime.paper.references import Reference
from runtime.paper.sim_library import build_sim_library

__all__ = [
    "ACCEL_CODES",
    "CONTROLLERS",
    "FORMULATIONS",
    "Run",
    "Sensors",
    "build_sim_library",
    "controller_config",
    "plant_params",
    "roc_bounds",
    "run",
    "sim_library",
]

CONTROLLERS = ("tdc", "tdroc", "roc", "asmc")


sim_library = cache(build_sim_library)


@dataclass(frozen=True)
class Run:
    """One closed-loop run, sampled at the control instants."""

    controller: str
    formulation: str
    path: str
    t: NDArray[np.float64]
    q: NDArray[np.float64]  # true state (N, 5)
    q_meas: NDArray[np.float64]
    q_des: NDArray[np.float64]
    tau: NDArray[np.float64]  # (N, 2)
    gain: NDArray[np.float64]
    s_norm: NDArray[np.float64]
    u_discarded: NDArray[np.float64]
    payload: NDArray[np.float64]  # true total mass
    saturated: int
    failed_at: float | None
    h1hat: NDArray[np.float64]  # the controller's Ĥ1 (TDC/TDROC) per step, (N, 5)
    error_norm: NDArray[np.float64]  # ‖(e, ė)‖ as the controller measures it
    wheel_switching: NDArray[np.float64]  # (N, 2): Δu_a of (24)/(25) on the right, left wheel
    # What step returned per sample (NOT_CALLED: a dropped sample), the (q̇) the controller
    # was given, and the torque the actuators delivered (differs from tau under a torque
    # limit fault).
    status: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    qdot_meas: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 5)))
    tau_applied: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 2)))
    stop_status: int | None = None  # the status < 0 that stopped the run at failed_at, if one did

    @property
    def position_error(self) -> NDArray[np.float64]:
        return np.linalg.norm(self.q[:, :2] - self.q_des[:, :2], axis=1)


NOT_CALLED = -(2**31)  # Run.status of a sample whose step was not called (dropped)


class Sensors:
    """Encoders (quantised wheel angles), wheel rates by the experiment's sensing model, and
    the pose by integrating (31) from the encoder angles (odometry). ``offset`` and
    ``window_offset`` are counts added to the encoder readings at the sample instant and at
    the motor-encoder window's start (an encoder fault)."""

    def __init__(self, q0: NDArray[np.float64], exp: Experiment, params: dict[str, float]):
        self.sensing = exp.sensing
        self.counts_per_rad = self.sensing.counts_per_wheel_rev() / (2 * math.pi)
        self.h = exp.controller.h
        self.window = self.sensing.rate_window(self.h)
        self.params = params
        self.pose = q0[:3].copy()
        self.offset = np.zeros(2)
        self.window_offset = np.zeros(2)
        self.angles = self.quantise(q0[3:5])

    def quantise(
        self, angles: NDArray[np.float64], offset: NDArray[np.float64] | None = None
    ) -> NDArray[np.float64]:
        """The encoder angles: whole counts, plus ``offset`` counts."""
        counts = np.floor(angles * self.counts_per_rad)
        if offset is not None:
            counts = counts + offset
        return counts / self.counts_per_rad

    def rates(
        self,
        angles: NDArray[np.float64],
        true_rates: NDArray[np.float64],
        window_start: NDArray[np.float64] | None,
    ) -> NDArray[np.float64]:
        """Wheel rates as measured: at the instant, over the sample, or over the window."""
        v = self.sensing.velocity
        if v == "sample-instant":
            return true_rates.copy()
        if v == "encoder-average":
            return (angles - self.angles) / self.h
        assert window_start is not None, "motor-encoder needs the angles at t - window"
        return (angles - self.quantise(window_start, self.window_offset)) / self.window

    def measure(
        self,
        true_angles: NDArray[np.float64],
        true_rates: NDArray[np.float64],
        window_start: NDArray[np.float64] | None = None,
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(q, q̇) as the controller sees them at a sample instant."""
        angles = self.quantise(true_angles, self.offset)
        delta = angles - self.angles
        p = self.params
        dtheta = p["r"] * (delta[0] - delta[1]) / p["b"]
        mid = np.array([*self.pose[:2], self.pose[2] + dtheta / 2, 0.0, 0.0])
        self.pose = self.pose + wmr_model.kinematics(mid, delta, p)
        rates = self.rates(angles, true_rates, window_start)
        self.angles = angles
        q = np.concatenate([self.pose, angles])
        qdot = np.concatenate([wmr_model.kinematics(q, rates, p), rates])
        return q, qdot


def advance(
    clib: Any,
    pp: Any,
    friction: Any,
    x: Any,
    tau: Any,
    dt: float,
    nsub: int,
    slip: Any = None,
    loss: Any = None,
) -> bool:
    """RK4 over ``nsub`` steps under zero-order hold; False if the state became non-finite.
    With ``slip`` and ``loss`` (a traction fault), the slip proxy of ``wmr_sim.c``."""
    if nsub == 0:
        return True
    if slip is not None:
        return bool(clib.sim_plant_advance_slip(pp, friction, x, slip, tau, loss, dt, nsub) == 0)
    return bool(clib.sim_plant_advance(pp, friction, x, tau, dt, nsub) == 0)


def run(
    name: str,
    formulation: str,
    ref: Reference,
    robot: dict[str, float],
    exp: Experiment,
    float32: bool = False,
    held_gain: float | None = None,
    check: bool = True,
    faults: Sequence[Fault] = (),
    plant: dict[str, float] | None = None,
) -> Run:
    """Simulate one controller on one reference (``held_gain``: TDROC with k̂ held;
    ``check=False`` skips the configuration checks, to show what they prevent; ``faults``:
    injected as ``runtime.faults`` describes; ``plant``: the simulated robot's parameters
    before payload when they differ from the controllers' model ``robot``, as a campaign's
    parameter error)."""
    lib = sim_library(float32)
    ffi, clib = lib.ffi, lib.lib
    # The toolchain checks the TDE condition ||M^-1 Mhat - I|| < 1 over the uncertainty box
    # and the sampled loop's stability when it builds a configuration (ValueError naming
    # the reason otherwise).
    cfg = (
        checked_controller_config(lib, name, formulation, robot, exp, held_gain=held_gain)
        if check
        else controller_config(lib, name, formulation, robot, exp, held_gain)
    )
    state = ffi.new(f"wmr_{name}_state_t *")
    status = getattr(clib, f"wmr_{name}_init")(state, cfg)
    if status != 0:
        raise RuntimeError(f"{name}/{formulation}: init failed with status {status}")
    step = getattr(clib, f"wmr_{name}_step")
    h, nsub = exp.controller.h, exp.plant.substeps
    friction = ffi.new("sim_friction_t *", [exp.plant.viscous, exp.plant.coulomb, 0.05])
    x = ffi.new("wmr_real_t[7]", [*ref.q[0], 0.0, 0.0])
    buf = {k: ffi.new("wmr_real_t[5]") for k in ("q", "qdot", "qd", "qdd", "qddd")}
    tau = ffi.new("wmr_real_t[2]")
    tau_plant = ffi.new("wmr_real_t[2]")  # what the actuators deliver
    slip = ffi.new("wmr_real_t[4]")  # wheel angles and rates relative to rolling (slip)
    loss = ffi.new("wmr_real_t[2]")
    pp = ffi.new("wmr_plant_params_t *")
    sensors = Sensors(np.array(ref.q[0]), exp, robot)
    # Substeps before the motor-encoder window opens (all of them for the other models).
    n_window = round(sensors.window / (h / nsub)) if exp.sensing.velocity == "motor-encoder" else 0
    window_start: NDArray[np.float64] | None = None
    n = len(ref.t)
    sched = schedule(faults, h, n)
    keys_rec = ("q", "qm", "tau", "gain", "s", "ud", "mass", "h1", "en", "sw", "st", "qdm", "ta")
    rec: dict[str, list[Any]] = {k: [] for k in keys_rec}
    sl = slice(0, 5) if formulation == "paper" else slice(3, 5)
    delivered = (ref.q[0].copy(), np.zeros(5))
    saturated, failed_at = 0, None
    stop_status: int | None = None
    prev_gain = float(state.gain)  # ASMC: the gain before each step's adaptation
    payload_on: bool | None = None  # the payload state the plant's parameters were set for
    keys = tuple(generated_robot.PLANT_PARAMS)
    for k in range(n):
        t = ref.t[k]
        true_q = np.array([x[i] for i in range(5)])
        # The wheels as their encoders see them: rolling plus slip.
        wheel_angles = true_q[3:5] + np.array([slip[0], slip[1]])
        true_rates = np.array([x[5] + slip[2], x[6] + slip[3]])
        sensors.offset = sched.encoder_offset[k]
        sensors.window_offset = sched.encoder_offset[k - 1] if k else np.zeros(2)
        sensed = (
            sensors.measure(wheel_angles, true_rates, window_start)
            if k
            else (ref.q[0].copy(), np.zeros(5))
        )
        # A repeated sample delivers the previous delivery again.
        q_meas, qdot_meas = delivered if sched.repeated[k] else sensed
        delivered = (q_meas, qdot_meas)
        buf["q"][0:5] = list(q_meas)
        buf["qdot"][0:5] = list(qdot_meas)
        buf["qd"][0:5] = list(ref.q[k])
        buf["qdd"][0:5] = list(ref.qdot[k])
        buf["qddd"][0:5] = list(ref.qddot[k])
        if sched.dropped[k]:  # the step is not called; the drive holds the last torque
            status = NOT_CALLED
        else:
            status = step(
                state, cfg, buf["q"], buf["qdot"], buf["qd"], buf["qdd"], buf["qddd"], tau
            )
            if status < 0:
                failed_at, stop_status = float(t), int(status)
                break
            saturated += status == 1
        if exp.plant.extra_on(float(t)) != payload_on:  # the payload changes at its switches
            payload_on = exp.plant.extra_on(float(t))
            true_p = plant_params(robot if plant is None else plant, exp, float(t))
            cbuild.fill_params(pp, dict(zip(keys, true_p, strict=True)))
        rec["q"].append(true_q)
        rec["qm"].append(q_meas)
        rec["tau"].append([tau[0], tau[1]])
        rec["gain"].append(state.gain)
        rec["s"].append(state.s_norm)
        rec["ud"].append(state.u_discarded)
        rec["mass"].append(true_p[0])
        rec["h1"].append([state.H1hat[i] for i in range(5)])
        err = np.concatenate([ref.q[k, sl] - q_meas[sl], ref.qdot[k, sl] - qdot_meas[sl]])
        rec["en"].append(float(np.linalg.norm(err)))
        # Δu_a = k s/max(‖s‖, ε) on the wheel rows, s_j = p12_j e_j + p22_j ė_j (from the
        # state's P), with the gain and ‖s‖ the C step used (ASMC: the gain before adaptation).
        used_gain = prev_gain if name == "asmc" else state.gain
        s_w = [
            state.p12[i] * (ref.q[k, i] - q_meas[i])
            + state.p22[i] * (ref.qdot[k, i] - qdot_meas[i])
            for i in (3, 4)
        ]
        denom = max(state.s_norm, exp.controller.eps)
        rec["sw"].append([used_gain * v / denom for v in s_w] if name != "tdc" else [0.0, 0.0])
        prev_gain = state.gain
        lim = sched.torque_limit[k]
        applied = [float(np.clip(tau[i], -lim[i], lim[i])) for i in range(2)]
        tau_plant[0:2] = applied
        rec["st"].append(status)
        rec["qdm"].append(qdot_meas)
        rec["ta"].append(applied)
        if k == n - 1:
            break
        slipping = None
        if sched.any_loss[k]:
            loss[0:2] = list(sched.traction_loss[k])
            slipping = slip
        for i in range(2):  # traction back: the contact stops the wheel's spin at once
            if sched.traction_loss[k, i] == 0:
                slip[2 + i] = 0.0
        ok = advance(clib, pp, friction, x, tau_plant, h / nsub, nsub - n_window, slipping, loss)
        if ok and n_window:  # the motor encoder's window opens n_window substeps before t + h
            window_start = np.array([x[3] + slip[0], x[4] + slip[1]])
            ok = advance(clib, pp, friction, x, tau_plant, h / nsub, n_window, slipping, loss)
        if not ok:
            failed_at = float(t)
            break
    m = len(rec["q"])
    return Run(
        name,
        formulation,
        ref.name,
        ref.t[:m],
        np.array(rec["q"]),
        np.array(rec["qm"]),
        ref.q[:m],
        np.array(rec["tau"]),
        np.array(rec["gain"]),
        np.array(rec["s"]),
        np.array(rec["ud"]),
        np.array(rec["mass"]),
        int(saturated),
        failed_at,
        np.array(rec["h1"]),
        np.array(rec["en"]),
        np.array(rec["sw"]),
        np.array(rec["st"], dtype=np.int64),
        np.array(rec["qdm"]).reshape(-1, 5),
        np.array(rec["ta"]).reshape(-1, 2),
        stop_status,
    )
