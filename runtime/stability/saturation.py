"""The saturation and wind-up verdict: beside the linear one, what the torque limit does.

The sampled-loop analysis (:mod:`runtime.stability.sampled_loop`) is linear: it cannot see
the torque limit τ_max, nor an adaptive gain that grows at start-up until the switching term
saturates the actuators (TDROC's k̂ of (25) on an independent plant at h = 0.25 s). This
module predicts both along the experiment's paths, without simulating:

* the torque demand: the minimal-form inverse dynamics τ_ff = M̄(q_d) η̇_d + H̄(q_d, η_d) of
  the reference with the experiment's heaviest robot (payload on), the torque any
  controller must deliver to follow the path;
* the switching torque: the switching term adds at most ‖M̂‖ k to it (k s / max(‖s‖, ε)
  has norm k at most, (24)/(25)); for TDROC, k̂ of (25) is computed along the reference as
  the controller computes it when it tracks perfectly: Ĥ1 of (17) from the generated
  kernel with u(t − h) = τ_ff(t − h) and the reference's rates (zero history before the
  first estimate, as the C state starts), the discounted window, ‖M̂⁻¹‖; ROC adds its ρ
  at zero error; TDC and the PI none; ASMC's gain integrates ‖s‖, zero on a tracked path.

Grip (μ: the experiment's ``[plant] friction``): each driven wheel can react at most
μ N r of torque on the floor, N its normal load from the one load model
(``modeling.contact_loads``, with the payload the schedule has on board and the load
transfer of the reference's acceleration; :class:`runtime.sim.slip_monitor.SlipMonitor`).
Along the reference, the torque a wheel's ground force needs is r |F| (F from the
constraint multipliers of (9) under τ_ff: the rolling and the axle's lateral force, a
friction circle); where it exceeds μ N r (and is under τ_max) the wheel is predicted to
slip: no controller follows the path on that floor. The switching torque's bound ‖M̂‖ k
is reached only while ‖s‖ ≥ ε, so where it would exceed the grip it is said as a risk;
the simulation (below) carries the switching term the loop really applies.

Verdict: ``saturates`` if the demand alone exceeds τ_max (no controller follows the path),
``slips`` if a wheel's torque exceeds its grip μ N r before τ_max (the time, wheel and
margin in the reason), ``winds up`` if demand plus switching torque exceeds τ_max (the
switching term drives the actuators into the limit; the error it leaves grows the adaptive
gains further), else ``ok``. With
``simulate``, the closed loop of :mod:`runtime.sim.loop` on the circle (the experiment's
plant: payload, friction, encoders) gives the simulated counterpart: the peak torque, the
samples clipped to τ_max and the peak switching gain, in the reason beside the prediction;
a run that saturates where ``ok`` was predicted turns the verdict into ``saturates
(simulated)`` (a loop the linear verdict calls unstable leaves the tracked path that the
prediction assumes: the small robot's ROC). The simulation carries the slip monitor: a run
whose wheel needs more than μ (|F| > μ N, TDROC's k̂ or ASMC's gain grown past the
tracked path's) turns ``ok`` or ``winds up`` into ``slips`` (simulated; a run that
saturates keeps that verdict and says where it slipped), with the first instant, the
wheel and its margin. Where a wheel slips, the same run with the traction
limit ``[controller] traction_mu`` = μ (τ_max → μ N r of the lightest driven wheel at
rest, :func:`runtime.setting.layout.traction_torque_limit`) is simulated too, and the
reason says whether that limit keeps grip.
"""

from __future__ import annotations

import hashlib
import inspect
import math
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from runtime.bindings.generated import RobotCode
from runtime.experiment.settings import Experiment
from runtime.plants import plant_for
from runtime.setting.layout import robot_layout, traction_torque_limit
from runtime.sim import loop, paths
from runtime.sim.memo import Memo, key_of
from runtime.sim.reference import Reference
from runtime.sim.slip_monitor import MonitoredPlant, SlipMonitor
from runtime.stability.sampled_loop import plant_parameters, roc_gain

Array = NDArray[np.float64]
START_UP = 5.0  # s: the start-up the gain's growth is reported over


@dataclass(frozen=True)
class SaturationVerdict:
    """The verdict, its reason, and the predicted (and simulated) numbers behind it."""

    verdict: str  # ok, saturates, winds up
    reason: str
    demand: float  # N m: the largest |τ_ff| over the paths
    switching: float  # N m: the largest switching torque ‖M̂‖ k predicted with it
    tau_max: float
    gain_peak: float  # the predicted switching gain's peak (k̂, ρ; 0 without one)
    simulated_peak: float | None = None  # N m: largest |τ| commanded in the simulation
    simulated_saturated: int | None = None  # samples clipped to τ_max
    simulated_gain_peak: float | None = None
    friction: float = math.nan  # μ of the floor ([plant] friction)
    grip_margin: float = math.nan  # N m: smallest μ N r − torque over wheels and paths
    slip: Slip | None = None  # the first loss of grip (predicted, else simulated)
    friction_needed: float | None = None  # the simulation's largest |F|/N
    traction_mu: float | None = None  # the traction limit that keeps grip (simulated)


@dataclass(frozen=True)
class Slip:
    """Where a wheel first needs more than μ N: time (s), path, wheel, its margin there
    (μ N r − torque, N m, negative) and whether a simulation (not the tracked path) says so."""

    t: float
    path: str
    wheel: str
    margin: float
    simulated: bool

    def describe(self, mu: float) -> str:
        return (f"wheel '{self.wheel}' loses grip at t = {self.t:.2f} s on the {self.path} "
                f"({'simulated' if self.simulated else 'predicted'}: its torque exceeds "
                f"μ N r by {-self.margin:.3g} N m at μ = {mu:g})")


def torque_demand(code: RobotCode, params: dict[str, float], ref: Reference) -> Array:
    """τ_ff(t_k) = M̄(q_d) η̇_d + H̄(q_d, η_d) (minimal form, N × m)."""
    act = list(code.actuated)
    out = []
    for q, qd, qdd in zip(ref.q, ref.qdot, ref.qddot, strict=True):
        m_bar = np.asarray(code.model.minimal_mass_matrix(q, params), dtype=np.float64)
        h_bar = np.asarray(code.model.minimal_bias_forces(q, qd[act], params))
        out.append(m_bar @ qdd[act] + h_bar)
    return np.array(out)


def _minv_norm(code: RobotCode, formulation: str, q: Array, p: dict[str, float]) -> float:
    """‖M̂⁻¹‖ as the step computes it (a robot's kernel takes q where M̂ depends on it)."""
    fn = getattr(code.laws, f"{formulation}_minv_norm")
    args = (q, p) if len(inspect.signature(fn).parameters) == 2 else (p,)
    return float(fn(*args)[0])


def tdroc_gain_along(code: RobotCode, formulation: str, nominal: dict[str, float],
                     exp: Experiment, ref: Reference, tau_ff: Array) -> Array:
    """k̂ of (25) at each sample of ``ref`` for a controller that tracks it perfectly on the
    robot whose torques are ``tau_ff`` (see the module docstring)."""
    c = exp.controller
    act = list(code.actuated)
    rows = list(range(code.nq)) if formulation == "paper" else act
    nc = len(rows)
    window = int(code.controllers.MAX_WINDOW)
    tde = getattr(code.laws, f"{formulation}_tde")
    gain_fn = getattr(code.laws, f"{formulation}_tdroc_gain")
    omega = np.zeros((window + 1, nc))
    count = 0
    gains = np.zeros(len(ref.t))
    for k in range(2, len(ref.t)):
        u_prev = np.zeros(code.nq)
        u_prev[act] = tau_ff[k - 1]
        h1 = np.asarray(tde(ref.q[k - 1], u_prev[rows], ref.qdot[k, rows],
                            ref.qdot[k - 1, rows], [c.h], nominal))
        omega[1:] = omega[:-1].copy()
        omega[0] = h1[:nc]
        count = min(count + 1, window + 1)
        if count < 2:
            continue
        active = min(count - 1, c.n)
        w = np.array([c.a**i if i < active else 0.0 for i in range(window)])
        w = w / w.sum()
        gains[k] = float(gain_fn([_minv_norm(code, formulation, ref.q[k], nominal)], omega,
                                 w)[0])
    return gains


def mass_norm(code: RobotCode, formulation: str, q: Array, p: dict[str, float]) -> float:
    """‖M̂‖₂ on the driven wheels (minimal form: M̄̂), the torque per unit acceleration."""
    m_bar = np.asarray(code.model.minimal_mass_matrix(q, p), dtype=np.float64)
    return float(np.linalg.norm(m_bar, 2))


def slip_monitor(code: RobotCode, exp: Experiment, nominal: dict[str, float]
                 ) -> SlipMonitor | None:
    """The slip monitor of the robot (None where its layout cannot be had at these
    parameters: a bodies-and-wheels robot with drawn parameters, or generated before the
    contact forces)."""
    try:
        return SlipMonitor(code, robot_layout(code, {**code.plant_defaults, **nominal}), exp)
    except ValueError:
        return None


# grip_along's results in this process, by what they depend on (the robot's code, its
# layout at ``nominal``, the experiment and the reference's samples), not by controller:
# saturation_verdict asks for the same paths once per controller and formulation.
_grip_memo: Memo[tuple[Array, Array]] = Memo(16)


def grip_along(monitor: SlipMonitor, nominal: dict[str, float], exp: Experiment,
               ref: Reference) -> tuple[Array, Array]:
    """(torque each driven wheel's ground force needs, r |F|; its grip μ N r) at each
    sample of ``ref`` (samples × driven wheels, N m) for a robot that tracks it, with the
    payload the schedule has on board (see the module docstring)."""
    digest = hashlib.sha256()
    for a in (ref.t, ref.q, ref.qdot, ref.qddot):
        digest.update(np.ascontiguousarray(a, dtype=np.float64).tobytes())
    key = key_of(monitor.code, nominal, monitor.robot, exp, digest.digest())

    def grip() -> tuple[Array, Array]:
        radius = {w.name: w.radius for w in monitor.robot.wheels}
        r = np.array([radius[w] for w in monitor.driven])
        fx, fy, n = monitor.along(ref, nominal, exp)
        return r * np.hypot(fx, fy), exp.plant.friction * n * r

    needed, limit = _grip_memo.get(key, grip)
    return needed.copy(), limit.copy()


# Verdicts already reached in this process, by everything they read (the robot's generated
# code by its folder and prefix, as the references' and the grip's memos): `wmr freeze` asks
# for the same simulated verdict on every run with the same configuration, at seconds each.
# The experiment's ``source`` (the file's name as typed) is left out of the key: nothing
# in a verdict reads it. A verdict is a frozen dataclass: handed out as it is.
_verdict_memo: Memo[SaturationVerdict] = Memo(32)


def saturation_verdict(code: RobotCode, controller: str, formulation: str,
                       nominal: dict[str, float], exp: Experiment, plant: str = "payload",
                       simulate: bool = False) -> SaturationVerdict:
    """The verdict for one controller and formulation (see the module docstring); the
    demand with the heaviest robot unless ``plant="nominal"`` (the same arguments in one
    process: the same verdict, reached once)."""
    key = key_of(code, nominal, controller, formulation, replace(exp, source=""), plant,
                 simulate)
    return _verdict_memo.get(key, lambda: _saturation_verdict(
        code, controller, formulation, nominal, exp, plant, simulate))


def _saturation_verdict(code: RobotCode, controller: str, formulation: str,
                        nominal: dict[str, float], exp: Experiment, plant: str,
                        simulate: bool) -> SaturationVerdict:
    info = code.controller(controller)
    heavy = plant_parameters(code, nominal, exp, "payload" if plant == "payload" else plant)
    heavy = {k: v for k, v in heavy.items() if k in nominal}
    tau_max = exp.controller.tau_max
    mu = exp.plant.friction
    monitor = slip_monitor(code, exp, nominal)
    demand, switching, gain_peak, when, path_of = 0.0, 0.0, 0.0, 0.0, ""
    grip_margin, risk, slip = math.inf, math.inf, None
    for name in paths.PATHS:
        ref = paths.reference(code, nominal, exp, name)
        tau_ff = torque_demand(code, heavy, ref)
        peak = np.abs(tau_ff).max(axis=1)
        if info.window:
            gains = tdroc_gain_along(code, formulation, nominal, exp, ref, tau_ff)
        elif info.bounds:
            try:
                gains = np.full(len(ref.t), roc_gain(code, formulation, nominal, exp)
                                * exp.controller.eps)
            except ValueError:  # no ROC configuration exists: nothing to saturate
                gains = np.zeros(len(ref.t))
        else:
            gains = np.zeros(len(ref.t))
        norms = np.array([mass_norm(code, formulation, q, nominal) for q in ref.q])
        total = peak + norms * gains
        k = int(np.argmax(total))
        if float(peak.max()) > demand:
            demand = float(peak.max())
        if total[k] - peak[k] > switching or (gain_peak == 0 and gains.max() > 0):
            switching, gain_peak = float(total[k] - peak[k]), float(gains.max())
            when, path_of = float(ref.t[int(np.argmax(gains))]), name
        if monitor is not None:
            need, grip = grip_along(monitor, nominal, exp, ref)
            margins = grip - need
            grip_margin = min(grip_margin, float(margins.min()))
            # the switching torque's bound ‖M̂‖ k is reached only while ‖s‖ ≥ ε: a risk
            # (said in the reason), not a slip; the simulation carries the real one
            risk = min(risk, float((margins - (norms * gains)[:, None]).min()))
            # a slip where the grip binds before τ_max (beyond it: saturation, wind-up)
            lost = np.nonzero(((margins < 0) & (grip < tau_max)).any(axis=1))[0]
            if len(lost) and (slip is None or ref.t[lost[0]] < slip.t):
                i = int(lost[0])
                w = int(np.argmin(np.where(grip[i] < tau_max, margins[i], np.inf)))
                slip = Slip(float(ref.t[i]), name, monitor.driven[w], float(margins[i, w]),
                            False)
    if demand > tau_max:
        verdict = "saturates"
        why = (f"the paths need {demand:.3g} N m (inverse dynamics with the payload on) "
               f"> τ_max = {tau_max:.3g} N m")
    elif slip is not None:
        verdict = "slips"
        why = (f"{slip.describe(mu)}; predicted peak {demand + switching:.3g} N m (demand "
               f"{demand:.3g} + switching {switching:.3g}) of τ_max = {tau_max:.3g} N m")
    elif demand + switching > tau_max:
        verdict = "winds up"
        why = (f"the switching gain reaches {gain_peak:.3g} (t = {when:.2f} s, {path_of}): "
               f"‖M̂‖ k = {switching:.3g} N m on top of the demand {demand:.3g} N m "
               f"> τ_max = {tau_max:.3g} N m")
    else:
        verdict = "ok"
        why = (f"predicted peak {demand + switching:.3g} N m (demand {demand:.3g} + "
               f"switching {switching:.3g}) of τ_max = {tau_max:.3g} N m")
    if monitor is not None and math.isfinite(grip_margin):
        why += f"; grip margin {grip_margin:.3g} N m at μ = {mu:g}"
        if risk < 0 <= grip_margin:
            why += (f" (with the switching torque at its bound ‖M̂‖ k it would be "
                    f"{risk:.3g} N m: grip then rests on the loop's error staying under ε)")
    out = SaturationVerdict(verdict, why, demand, switching, tau_max, gain_peak,
                            friction=mu, grip_margin=grip_margin, slip=slip)
    if not simulate:
        return out
    ref = paths.circle(code, nominal, exp)
    r, needed = _monitored_run(code, controller, formulation, ref, nominal, exp, monitor)
    if r.init_status != 0:
        return replace(out, reason=f"{why}; not simulated: {r.stop_reason}")
    early = r.t <= START_UP
    sim_peak = float(np.abs(r.tau).max()) if len(r.tau) else math.nan
    sim_gain = float(r.gain[early].max()) if early.any() else math.nan
    sim = (f"; simulated on the circle (and, for grip, every path): peak {sim_peak:.3g} N m, "
           f"{r.saturated} samples at "
           f"τ_max, switching gain up to {sim_gain:.3g} in the first {START_UP:g} s"
           + (f", stopped at t = {r.failed_at:g} s ({r.stop_reason})" if r.failed_at is not None
              else ""))
    sim_slip, mu_needed = _first_slip(monitor, needed, r, mu)
    if mu_needed is not None:
        sim += f", μ needed {mu_needed:.3g} on the circle"
    refs = {ref.name: ref}
    if monitor is not None:
        # grip on the other paths too: ASMC's gain, integrating ‖s‖, grows over the lawn
        # mower's long run until its chattering torque spins a wheel (h = 0.25 s: at 31 s)
        for name in paths.PATHS:
            if name in refs:
                continue
            refs[name] = paths.reference(code, nominal, exp, name)
            other, plant_other = _monitored_run(code, controller, formulation, refs[name],
                                                nominal, exp, monitor)
            slip_other, need_other = _first_slip(monitor, plant_other, other, mu)
            if need_other is not None:
                sim += f", μ needed {need_other:.3g} on the {name}"
                mu_needed = max(mu_needed or 0.0, need_other)
            if sim_slip is None:
                sim_slip = slip_other
    if r.saturated and verdict == "ok":  # the prediction missed it: say so, the run decides
        verdict = "saturates (simulated)"
        sim += (" — not predicted from the tracked path: the loop left it (see the linear "
                "verdict)")
    traction_mu = None
    if sim_slip is not None and slip is None:
        # a run that left the path into τ_max keeps that verdict; its slip is said too
        verdict = verdict if verdict.startswith("saturates") else "slips"
        sim += f"; {sim_slip.describe(mu)}"
        slip = sim_slip
    if verdict == "slips" and monitor is not None:
        advice, traction_mu = _traction_advice(code, controller, formulation,
                                               refs.get(slip.path if slip else "", ref),
                                               nominal, exp, monitor)
        sim += f"; {advice}"
    return replace(out, verdict=verdict, reason=why + sim, simulated_peak=sim_peak,
                   simulated_saturated=r.saturated, simulated_gain_peak=sim_gain, slip=slip,
                   friction_needed=mu_needed, traction_mu=traction_mu)


def _monitored_run(code: RobotCode, controller: str, formulation: str, ref: Reference,
                   nominal: dict[str, float], exp: Experiment, monitor: SlipMonitor | None
                   ) -> tuple[loop.Run, MonitoredPlant | None]:
    """The closed loop on the experiment's plant, with the slip monitor on it if any."""
    plant = plant_for(code, exp, nominal)
    if monitor is None:
        return loop.run(code, controller, formulation, ref, nominal, exp, plant=plant), None
    monitored = MonitoredPlant(plant, monitor)
    return (loop.run(code, controller, formulation, ref, nominal, exp, plant=monitored),
            monitored)


def _first_slip(monitor: SlipMonitor | None, plant: MonitoredPlant | None, r: loop.Run,
                mu: float) -> tuple[Slip | None, float | None]:
    """(The first sample whose wheel needs more than μ, the run's largest need)."""
    if monitor is None or plant is None or not plant.needed:
        return None, None
    needed = np.array(plant.needed)
    radius = {w.name: w.radius for w in monitor.robot.wheels}
    lost = np.nonzero(needed > mu)[0]
    slip = None
    if len(lost):
        i = int(lost[0])
        margins = mu * plant.loads[i] - plant.forces[i]
        w = int(np.argmin(margins))
        slip = Slip(float(r.t[i]), r.path or "circle", monitor.driven[w],
                    float(margins[w] * radius[monitor.driven[w]]), True)
    return slip, float(needed.max())


def _traction_advice(code: RobotCode, controller: str, formulation: str, ref: Reference,
                     nominal: dict[str, float], exp: Experiment, monitor: SlipMonitor
                     ) -> tuple[str, float | None]:
    """Whether ``traction_mu`` = μ keeps grip on ``ref`` (simulated), in a sentence, and
    that μ if it does."""
    mu = exp.plant.friction
    c = exp.controller
    limit = traction_torque_limit(code, {**code.plant_defaults, **nominal}, exp, mu)
    if limit >= c.tau_max:
        return (f"a traction limit cannot help: μ N r = {limit:.3g} N m is not under "
                f"τ_max", None)
    limited = replace(exp, controller=replace(c, tau_max=limit))
    r, plant = _monitored_run(code, controller, formulation, ref, nominal, limited, monitor)
    slip, needed = _first_slip(monitor, plant, r, mu)
    held = (f"[controller] traction_mu = {mu:g} (τ_max → {limit:.3g} N m): simulated, "
            f"μ needed {needed:.3g}" if needed is not None else "")
    if r.init_status == 0 and r.failed_at is None and slip is None:
        return f"set {held}, it keeps grip", mu
    return (f"{held or 'traction_mu'} does not keep grip either"
            + (f" (stopped at t = {r.failed_at:g} s)" if r.failed_at is not None else "")
            + ": slow the path down, or make the loop stable first", None)


def grip_line(v: SaturationVerdict) -> str:
    """The grip part of a verdict in one line, as ``wmr freeze``'s header and the campaign
    summary carry it (the verdict is :func:`saturation_verdict`'s, not recomputed): the
    verdict at the floor's μ, the first slip (time, path, wheel, margin) and the
    ``traction_mu`` that keeps grip, if the simulation found one."""
    mu = v.friction
    head = f"{v.verdict} at μ = {mu:g} ([plant] friction)"
    needed = ("" if v.friction_needed is None
              else f", μ needed {v.friction_needed:.3g} (simulated)")
    if v.slip is None:
        margin = (f"grip margin {v.grip_margin:.3g} N m" if math.isfinite(v.grip_margin)
                  else "grip not checked (no slip monitor for this robot)")
        return f"{head}: {margin}{needed}"
    advice = (f"set [controller] traction_mu = {v.traction_mu:g}: it keeps grip (simulated)"
              if v.traction_mu is not None else
              "no traction_mu keeps grip (simulated): slow the path down or make the loop "
              "stable first")
    return f"{head}: {v.slip.describe(mu)}{needed}; {advice}"


def grip_data(v: SaturationVerdict) -> dict[str, object]:
    """The grip part of a verdict as JSON-able data (the campaign's ``summary.json``)."""
    slip = v.slip
    return {
        "verdict": v.verdict, "friction": v.friction,
        "grip_margin_Nm": v.grip_margin if math.isfinite(v.grip_margin) else None,
        "friction_needed": v.friction_needed, "traction_mu": v.traction_mu,
        "slip": None if slip is None else {
            "t": slip.t, "path": slip.path, "wheel": slip.wheel, "margin_Nm": slip.margin,
            "simulated": slip.simulated},
        "line": grip_line(v),
    }
