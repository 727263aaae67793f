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

Verdict: ``saturates`` if the demand alone exceeds τ_max (no controller follows the path),
``winds up`` if demand plus switching torque does (the switching term drives the actuators
into the limit; the error it leaves grows the adaptive gains further), else ``ok``. With
``simulate``, the closed loop of :mod:`runtime.sim.loop` on the circle (the experiment's
plant: payload, friction, encoders) gives the simulated counterpart: the peak torque, the
samples clipped to τ_max and the peak switching gain, in the reason beside the prediction;
a run that saturates where ``ok`` was predicted turns the verdict into ``saturates
(simulated)`` (a loop the linear verdict calls unstable leaves the tracked path that the
prediction assumes: the small robot's ROC).
"""

from __future__ import annotations

import inspect
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from runtime.bindings.generated import RobotCode
from runtime.experiment.settings import Experiment
from runtime.plants import plant_for
from runtime.sim import loop, paths
from runtime.sim.reference import Reference
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


def saturation_verdict(code: RobotCode, controller: str, formulation: str,
                       nominal: dict[str, float], exp: Experiment, plant: str = "payload",
                       simulate: bool = False) -> SaturationVerdict:
    """The verdict for one controller and formulation (see the module docstring); the
    demand with the heaviest robot unless ``plant="nominal"``."""
    info = code.controller(controller)
    heavy = plant_parameters(code, nominal, exp, "payload" if plant == "payload" else plant)
    heavy = {k: v for k, v in heavy.items() if k in nominal}
    tau_max = exp.controller.tau_max
    demand, switching, gain_peak, when, path_of = 0.0, 0.0, 0.0, 0.0, ""
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
    if demand > tau_max:
        verdict = "saturates"
        why = (f"the paths need {demand:.3g} N m (inverse dynamics with the payload on) "
               f"> τ_max = {tau_max:.3g} N m")
    elif demand + switching > tau_max:
        verdict = "winds up"
        why = (f"the switching gain reaches {gain_peak:.3g} (t = {when:.2f} s, {path_of}): "
               f"‖M̂‖ k = {switching:.3g} N m on top of the demand {demand:.3g} N m "
               f"> τ_max = {tau_max:.3g} N m")
    else:
        verdict = "ok"
        why = (f"predicted peak {demand + switching:.3g} N m (demand {demand:.3g} + "
               f"switching {switching:.3g}) of τ_max = {tau_max:.3g} N m")
    out = SaturationVerdict(verdict, why, demand, switching, tau_max, gain_peak)
    if not simulate:
        return out
    ref = paths.circle(code, nominal, exp)
    r = loop.run(code, controller, formulation, ref, nominal, exp,
                 plant=plant_for(code, exp, nominal))
    if r.init_status != 0:
        return SaturationVerdict(verdict, f"{why}; not simulated: {r.stop_reason}", demand,
                                 switching, tau_max, gain_peak)
    early = r.t <= START_UP
    sim_peak = float(np.abs(r.tau).max()) if len(r.tau) else math.nan
    sim_gain = float(r.gain[early].max()) if early.any() else math.nan
    sim = (f"; simulated on the circle: peak {sim_peak:.3g} N m, {r.saturated} samples at "
           f"τ_max, switching gain up to {sim_gain:.3g} in the first {START_UP:g} s"
           + (f", stopped at t = {r.failed_at:g} s ({r.stop_reason})" if r.failed_at is not None
              else ""))
    if r.saturated and verdict == "ok":  # the prediction missed it: say so, the run decides
        verdict = "saturates (simulated)"
        sim += (" — not predicted from the tracked path: the loop left it (see the linear "
                "verdict)")
    return SaturationVerdict(verdict, why + sim, demand, switching, tau_max, gain_peak,
                             sim_peak, r.saturated, sim_gain)
