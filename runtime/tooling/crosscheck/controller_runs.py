"""The hand-written comparison (the paper's robot): each implementation of a controller
stepped over a recorded sequence, open loop — the hand-written reference, the generated
Python classes, the C double build, and the C float32 build restarted every step from the
reference's (rounded) state.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from runtime.bindings.controller import Controller
from runtime.bindings.generated import controllers as pyctl
from runtime.tooling.crosscheck.bindings import CModel
from runtime.tooling.crosscheck.deviation import Arr, Params, Trace, f32, f32_params, perturbed
from runtime.tooling.crosscheck.inputs import Sequence_, accel_code
from runtime.tooling.crosscheck.targets import Target
from runtime.tooling.witness import controllers as hc
from runtime.tooling.witness import model as hw


def hand_run(seq: Sequence_, kind: hc.Kind) -> tuple[Trace, list[hc.StepRecord]]:
    ctrl = hc.Controller(kind, seq.settings)
    trace, records = Trace(), []
    for k in range(len(seq.q)):
        ctrl.step(seq.q[k], seq.qdot[k], seq.q_des[k], seq.qdot_des[k], seq.qddot_des[k])
        hs = ctrl.history
        trace.record(hs.tau, hs.gain, hs.s_norm, hs.H1hat, hs.u_discarded, ctrl.saturated)
        assert ctrl.last is not None
        records.append(ctrl.last)
    return trace, records


def python_run(target: Target, seq: Sequence_, kind: hc.Kind, nominal: Params) -> Trace:
    gc = target.code.controllers
    s = seq.settings
    cfg = gc.Config(
        nominal=nominal,
        formulation=gc.FORMULATION_PAPER if s.formulation == "paper" else gc.FORMULATION_MINIMAL,
        k1=np.asarray(s.k1, dtype=np.float64).tolist(),
        k2=np.asarray(s.k2, dtype=np.float64).tolist(),
        q_pos=s.q_pos,
        q_vel=s.q_vel,
        h=s.h,
        tau_max=s.tau_max,
        accel_estimator=accel_code(target, s.accel),
        rate_window=s.rate_window,
        eps=s.eps,
        n=s.n,
        a=s.a,
        alpha=s.alpha,
        phi=s.phi,
        gamma=s.gamma,
        gain0=s.gain0,
    )
    ctrl = getattr(gc, kind.upper())(cfg)
    trace = Trace()
    for k in range(len(seq.q)):
        ctrl.step(seq.q[k], seq.qdot[k], seq.q_des[k], seq.qdot_des[k], seq.qddot_des[k])
        trace.record(
            ctrl.tau,
            ctrl.gain,
            ctrl.s_norm,
            ctrl.H1hat,
            ctrl.u_discarded,
            ctrl.last_status.endswith("_WARN_SATURATED"),
        )
    return trace


class CController:
    """A generated C controller through the bindings' wrapper
    (:class:`runtime.bindings.controller.Controller`), configured from the hand-written
    equations' settings (the crosscheck's own test configurations)."""

    def __init__(
        self, target: Target, float32: bool, kind: hc.Kind, s: hc.Settings, nominal: Params
    ) -> None:
        self.m = CModel(target, float32)
        ffi, pre = self.m.ffi, self.m.prefix
        self.kind = kind
        self.cfg = ffi.new(f"{pre}_{kind}_config_t *")
        fields = {name for name, _ in ffi.typeof(f"{pre}_{kind}_config_t").fields}
        from runtime.bindings import cbuild

        cbuild.fill_params(
            self.cfg.nominal, {k: nominal[k] for k in hw.PARAM_KEYS}, self.m.field_names
        )
        self.cfg.formulation = 0 if s.formulation == "paper" else 1
        for i in range(5):
            self.cfg.k1[i] = float(np.asarray(s.k1)[i])
            self.cfg.k2[i] = float(np.asarray(s.k2)[i])
        values: dict[str, float | int] = {
            "q_pos": s.q_pos, "q_vel": s.q_vel, "h": s.h, "tau_max": s.tau_max,
            "accel_estimator": accel_code(target, s.accel), "rate_window": s.rate_window,
            "eps": s.eps, "n": s.n,
            "a": s.a, "alpha": s.alpha, "phi": s.phi, "gamma": s.gamma, "gain0": s.gain0,
        }  # fmt: skip
        for key, value in values.items():
            if key in fields:
                setattr(self.cfg, key, value)
        self.ctl = Controller(self.m.lib, pre, kind, self.cfg, 5, 2)
        self.state, self.state_fields = self.ctl.state, self.ctl.state_fields
        status = self.ctl.init()
        if status != 0:
            raise RuntimeError(f"{pre}_{kind}_init returned {status}")
        self.tau = self.ctl.tau

    def step(self, q: Arr, qdot: Arr, qd: Arr, qdd: Arr, qddd: Arr) -> int:
        status = self.ctl.step([q, qdot, qd, qdd, qddd])
        if status < 0:
            raise RuntimeError(f"{self.m.prefix}_{self.kind}_step returned {status}")
        return status

    def record(self, trace: Trace, status: int) -> None:
        st, rd = self.state, self.m.read
        trace.record(
            rd(st.tau, 2), st.gain, st.s_norm, rd(st.H1hat, 5), st.u_discarded, status == 1
        )

    def load(self, hist: hc.History, p12: Arr, p22: Arr) -> None:
        """Overwrite the C state with a (float32-representable) reference history."""
        st = self.state
        st.steps = hist.steps
        for i in range(5):
            st.p12[i], st.p22[i] = float(p12[i]), float(p22[i])
            st.q_prev[i], st.qdot_prev[i] = float(hist.q_prev[i]), float(hist.qdot_prev[i])
            st.qdot_prev2[i], st.u_prev[i] = float(hist.qdot_prev2[i]), float(hist.u_prev[i])
            st.u_prev2[i] = float(hist.u_prev2[i])
            st.H1hat[i] = float(hist.H1hat[i])
        if "omega_ring" in self.state_fields:  # C keeps the window's difference norms
            # in a ring written twice (at i and i + MAX_WINDOW), the newest at omega_head
            dnorm = np.linalg.norm(hist.omega[:-1] - hist.omega[1:], axis=1)
            for i in range(hc.MAX_WINDOW):
                st.omega_ring[i] = st.omega_ring[i + hc.MAX_WINDOW] = float(dnorm[i])
            st.omega_head = 0
            st.omega_count = hist.omega_count
        if "trig_prev" in self.state_fields:  # sin, cos of q(t-h)'s angles, as the step keeps
            angles = pyctl.TRIG[int(self.cfg.formulation)] if hist.steps else ()
            trig = [f(float(hist.q_prev[a])) for a in angles for f in (math.sin, math.cos)]
            for i in range(len(st.trig_prev)):
                st.trig_prev[i] = trig[i] if i < len(trig) else 0.0
        st.gain, st.s_norm, st.u_discarded = hist.gain, hist.s_norm, hist.u_discarded
        st.tau[0], st.tau[1] = float(hist.tau[0]), float(hist.tau[1])


def c_run(target: Target, seq: Sequence_, kind: hc.Kind, nominal: Params) -> Trace:
    ctrl = CController(target, False, kind, seq.settings, nominal)
    trace = Trace()
    for k in range(len(seq.q)):
        status = ctrl.step(seq.q[k], seq.qdot[k], seq.q_des[k], seq.qdot_des[k], seq.qddot_des[k])
        ctrl.record(trace, status)
    return trace


def rounded_history(h: hc.History) -> hc.History:
    return hc.History(
        steps=h.steps, q_prev=f32(h.q_prev), qdot_prev=f32(h.qdot_prev),
        qdot_prev2=f32(h.qdot_prev2), u_prev=f32(h.u_prev), u_prev2=f32(h.u_prev2),
        omega=f32(h.omega),
        omega_count=h.omega_count, H1hat=f32(h.H1hat), gain=f32(h.gain),
        s_norm=f32(h.s_norm), u_discarded=f32(h.u_discarded), tau=f32(h.tau),
    )  # fmt: skip


def rounded_settings(s: hc.Settings, nominal: Params) -> hc.Settings:
    return hc.Settings(
        nominal=f32_params(nominal), formulation=s.formulation, k1=f32(s.k1), k2=f32(s.k2),
        q_pos=f32(s.q_pos), q_vel=f32(s.q_vel), h=f32(s.h), tau_max=f32(s.tau_max),
        accel=s.accel, rate_window=f32(s.rate_window), eps=f32(s.eps), n=s.n, a=f32(s.a),
        alpha=f32(s.alpha), phi=f32(s.phi),
        gamma=f32(s.gamma), gain0=f32(s.gain0),
    )  # fmt: skip


def c32_synced_run(
    target: Target, seq: Sequence_, kind: hc.Kind, perturb: Mapping[str, Mapping[str, float]]
) -> tuple[Trace, Trace]:
    """float32 C per step from the reference's state, on identical (float32) inputs.

    Returns (float32 trace, reference trace on the same rounded inputs and states)."""
    s32 = rounded_settings(seq.settings, dict(seq.settings.nominal))
    ref = hc.Controller(kind, s32)
    ref.p12, ref.p22 = f32(ref.p12), f32(ref.p22)
    c32 = CController(target, True, kind, s32, perturbed(dict(s32.nominal), "c32", perturb))
    got, want = Trace(), Trace()
    for k in range(len(seq.q)):
        ref.history = rounded_history(ref.history)
        c32.load(ref.history, ref.p12, ref.p22)
        args = [f32(x[k]) for x in (seq.q, seq.qdot, seq.q_des, seq.qdot_des, seq.qddot_des)]
        status = c32.step(*args)
        c32.record(got, status)
        ref.step(*args)
        hs = ref.history
        want.record(hs.tau, hs.gain, hs.s_norm, hs.H1hat, hs.u_discarded, ref.saturated)
    return got, want
