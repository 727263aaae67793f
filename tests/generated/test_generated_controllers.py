"""The generated controllers step as documented: the four controllers, both formulations,
C step == Python class step (tau and state) on smooth multi-step sequences, and both ==
the SymPy laws of modeling.controllers with the step semantics re-implemented here.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from typing import Any

import numpy as np
import pytest
import sympy as sp
from generated_code_support import (
    CONTROLLER_CASES,
    CONTROLLER_IDS,
    FORMULATIONS,
    INFO,
    PARAM_SYMBOLS,
    PY_CLASSES,
    RTOL_CONTROLLER,
    STATUS,
    CBuild,
    CController,
    _close,
    _config,
    _smooth_sequence,
)

from codegen.robot_functions import MAX_WINDOW
from modeling import controllers as ctl
from modeling.controllers import ControllerSpec
from modeling.robots.drishti import model as wmr
from modeling.robots.drishti.model import PARAM_KEYS
from runtime.bindings.generated import controllers as pyctl

DRISHTI = wmr.robot_model()

RTOL_SYMPY_LAW = 1e-9  # steps vs the SymPy laws evaluated directly (other rounding)


# The history rows Drishti's minimal step keeps (issue 52): the controlled rows 4-5 of the
# rates and inputs, no q(t-h). The C step leaves the others as _init did (zero:
# tests/firmware/test_history_rows.py); the Python mirror keeps every row, which nothing reads.
MINIMAL_KEPT = {"qdot_prev": slice(3, 5), "qdot_prev2": slice(3, 5), "u_prev": slice(3, 5),
                "u_prev2": slice(3, 5), "q_prev": slice(0, 0)}


def _compare_states(
    c_fields: dict[str, Any], py_state: dict[str, Any], info: ControllerSpec, form: str
) -> None:
    required = {"steps", "gain", "s_norm", "H1hat", "tau"}
    required |= ({"omega_ring"} if info.window else set()) | ({"trig_prev"} if info.tde else set())
    common = {k for k in c_fields.keys() & py_state.keys() if not isinstance(c_fields[k], dict)}
    assert required <= common, sorted(required - common)
    for key in sorted(common):
        c_value, py_value = c_fields[key], py_state[key]
        if form == "minimal" and key in MINIMAL_KEPT:
            c_value = list(c_value)[MINIMAL_KEPT[key]]
            py_value = list(py_value)[MINIMAL_KEPT[key]]
        assert _close(c_value, py_value, RTOL_CONTROLLER), (
            f"{key}: C {c_fields[key]} vs Python {py_state[key]}"
        )


@pytest.mark.parametrize(("name", "form"), CONTROLLER_CASES, ids=CONTROLLER_IDS)
def test_controller_c_equals_python(c_builds: dict[str, CBuild], name: str, form: str) -> None:
    info = INFO[name]
    estimators = (pyctl.ACCEL_BACKWARD, pyctl.ACCEL_CENTRAL) if info.tde else (0,)
    for estimator in estimators:
        config = _config(name, FORMULATIONS[form], accel_estimator=estimator)
        c_ctl = CController(c_builds["double"], name, config)
        py_ctl = PY_CLASSES[name](config)
        _compare_states(c_ctl.fields(), py_ctl.state(), info, form)
        seq = _smooth_sequence(7 + estimator, 60, config.h)
        gains = []
        for k, inputs in enumerate(seq):
            status, tau_c = c_ctl.step(*inputs)
            tau_py = py_ctl.step(*inputs)
            assert status == STATUS[py_ctl.last_status], (k, status, py_ctl.last_status)
            assert _close(list(tau_c), tau_py, RTOL_CONTROLLER), (k, list(tau_c), tau_py)
            _compare_states(c_ctl.fields(), py_ctl.state(), info, form)
            gains.append(py_ctl.gain)
        assert py_ctl.steps == len(seq)
        if info.switching:  # the switching gain is exercised, not identically zero
            assert max(gains) > 0.0


@dataclass(frozen=True)
class SympyLaws:
    tde: Callable[..., Any]
    gain: Callable[..., Any]
    law: Callable[..., Any]
    lyapunov: Callable[..., Any]
    size: int


@cache
def _sympy_laws(name: str, form: str) -> SympyLaws:
    f: ctl.Formulation = "paper" if form == "paper" else "minimal"
    tde, ts = ctl.tde_estimate(f, DRISHTI)
    tde_fn = sp.lambdify(
        [*PARAM_SYMBOLS, *ts.q_prev, *ts.u_prev, *ts.qdot_now, *ts.qdot_then, ts.span], list(tde)
    )
    gain, omega, w = ctl.tdroc_gain(f, MAX_WINDOW, DRISHTI)
    # ||Mhat^-1||_F may be a separate input symbol of (25): substitute its expression.
    gain = gain.subs(sp.Symbol("minv_norm", positive=True), ctl.mass_inverse_norm(f, DRISHTI))
    gain_fn = sp.lambdify([*PARAM_SYMBOLS, *wmr.q, *omega, *w], gain)
    if name in ("tdc", "tdroc"):
        law, ls = ctl.tde_law(f, switching=name == "tdroc", model=DRISHTI)
    else:
        law, ls = {"roc": ctl.roc_law, "asmc": ctl.asmc_law}[name](f, DRISHTI)
    law_args = [
        *PARAM_SYMBOLS, *wmr.q, *wmr.qdot, *ls.e, *ls.edot, *ls.qddot_des, *ls.k1, *ls.k2,
        *ls.p12, *ls.p22, *ls.h1, ls.gain, ls.eps, ls.alpha, ls.phi,
    ]  # fmt: skip
    law_fn = sp.lambdify(law_args, [*law.u, law.s_norm, law.gain])
    k1, k2, q1, q2 = sp.symbols("k1 k2 q1 q2", positive=True)
    lyap_fn = sp.lambdify([k1, k2, q1, q2], list(ctl.lyapunov_p(k1, k2, q1, q2)))
    return SympyLaws(tde_fn, gain_fn, law_fn, lyap_fn, ctl.control_model(f, DRISHTI).size)


class SympyController:
    """The documented step semantics, independently: (17) from the previous applied input
    once two steps are stored (h backward / 2h central); Omega(1) = H1hat pushed newest
    first; (25) over the min(count - 1, n) newest differences with weights a^(i-1)
    normalised; tau = B^T u clipped to tau_max; ASMC's gain advanced after the law."""

    def __init__(self, name: str, form: str, config: Any) -> None:
        self.info, self.c = INFO[name], config
        self.laws = _sympy_laws(name, form)
        self.paper = form == "paper"
        self.p = [config.nominal[k] for k in PARAM_KEYS]
        pm = [
            self.laws.lyapunov(a, b, config.q_pos, config.q_vel)
            for a, b in zip(config.k1, config.k2, strict=True)
        ]
        self.p12 = np.array([x[1] for x in pm])
        self.p22 = np.array([x[2] for x in pm])
        self.steps = 0
        self.q_prev, self.qdot_prev, self.qdot_prev2 = np.zeros(5), np.zeros(5), np.zeros(5)
        self.u_prev = np.zeros(5)  # B tau of the previous step
        self.omegas: list[np.ndarray] = []
        self.gain = config.gain0 if self.info.adaptive else 0.0

    def step(self, q: np.ndarray, qdot: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
             qddd: np.ndarray) -> tuple[np.ndarray, float]:  # fmt: skip
        c, n = self.c, self.laws.size
        sl = slice(5 - n, 5)
        h1 = np.zeros(n)
        if self.info.tde and self.steps >= 2:
            central = c.accel_estimator == pyctl.ACCEL_CENTRAL
            then = self.qdot_prev2 if central else self.qdot_prev
            up = self.u_prev if self.paper else self.u_prev[3:]
            span = 2 * c.h if central else c.h
            h1 = np.array(self.laws.tde(*self.p, *self.q_prev, *up, *qdot[sl], *then[sl], span))
        gain = self.gain
        if self.info.window:
            if self.steps >= 2:
                self.omegas = [h1, *self.omegas][: MAX_WINDOW + 1]
            gain = 0.0
            if len(self.omegas) >= 2:
                active = min(len(self.omegas) - 1, c.n)
                w = np.array([c.a**i if i < active else 0.0 for i in range(MAX_WINDOW)])
                om = np.zeros((MAX_WINDOW + 1, n))
                om[: len(self.omegas)] = self.omegas
                gain = float(self.laws.gain(*self.p, *q, *om.reshape(-1), *(w / w.sum())))
        k1, k2 = np.asarray(c.k1)[sl], np.asarray(c.k2)[sl]
        out = self.laws.law(
            *self.p, *q, *qdot, *(qd - q)[sl], *(qdd - qdot)[sl], *qddd[sl], *k1, *k2,
            *self.p12[sl], *self.p22[sl], *h1, gain, c.eps, c.alpha, c.phi,
        )  # fmt: skip
        u, s_norm = np.array(out[:n], dtype=float), float(out[n])
        if self.info.bounds:
            gain = float(out[n + 1])
        tau = np.clip(u[3:] if self.paper else u, -c.tau_max, c.tau_max)
        if self.info.adaptive:
            self.gain = float(ctl.asmc_adaptation(gain, c.gamma, s_norm, c.h))
        self.qdot_prev2, self.qdot_prev, self.q_prev = self.qdot_prev, qdot.copy(), q.copy()
        self.u_prev = np.array([0.0, 0.0, 0.0, *tau])
        self.steps += 1
        return tau, (self.gain if self.info.adaptive else gain)


PAPER_LAW_CASES = [(c, f) for c, f in CONTROLLER_CASES if INFO[c].error_dynamics]


@pytest.mark.parametrize(("name", "form"), PAPER_LAW_CASES,
                         ids=[f"{c}-{f}" for c, f in PAPER_LAW_CASES])
def test_controller_steps_match_sympy_laws(
    c_builds: dict[str, CBuild], name: str, form: str
) -> None:
    config = _config(name, FORMULATIONS[form])
    ref = SympyController(name, form, config)
    c_ctl = CController(c_builds["double"], name, config)
    py_ctl = PY_CLASSES[name](config)
    for k, inputs in enumerate(_smooth_sequence(11, 8, config.h)):
        tau_ref, gain_ref = ref.step(*inputs)
        _, tau_c = c_ctl.step(*inputs)
        tau_py = py_ctl.step(*inputs)
        assert _close(tau_py, tau_ref, RTOL_SYMPY_LAW), (k, tau_py, tau_ref)
        assert _close(list(tau_c), tau_ref, RTOL_SYMPY_LAW), (k, list(tau_c), tau_ref)
        assert _close(py_ctl.gain, gain_ref, RTOL_SYMPY_LAW), (k, py_ctl.gain, gain_ref)
    if INFO[name].window:
        assert ref.omegas and ref.steps == 8 and py_ctl.gain > 0.0


def test_wheel_pi_matches_the_hand_written_witness(c_builds: dict[str, CBuild]) -> None:
    """The generated wheel-velocity PI (C and Python) against the one typed by hand for the
    differential drive (runtime.tooling.witness.wheel_pi): the same torques and integral
    along a smooth tracking sequence, saturation included (a tight torque limit)."""
    from runtime.tooling.witness.wheel_pi import WheelPI, WheelPIGains

    for tau_max in (200.0, 0.5):
        config = _config("pi", FORMULATIONS["minimal"], kx=1.5, ky=6.0, ktheta=3.0, kp=2.5,
                         ki=4.0, tau_max=tau_max)
        c_ctl = CController(c_builds["double"], "pi", config)
        py_ctl = PY_CLASSES["pi"](config)
        ref = WheelPI(WheelPIGains(1.5, 6.0, 3.0, 2.5, 4.0), config.nominal["r"],
                      config.nominal["b"], config.h, tau_max)
        saturated = 0
        for k, (q, qdot, qd, qdd, _) in enumerate(_smooth_sequence(5, 40, config.h)):
            tau_ref = ref.step(q, qdot, qd, qdd)
            status, tau_c = c_ctl.step(q, qdot, qd, qdd, np.zeros(5))
            tau_py = py_ctl.step(q, qdot, qd, qdd, np.zeros(5))
            saturated += status == STATUS["WMR_WARN_SATURATED"]
            assert _close(list(tau_c), tau_ref, RTOL_SYMPY_LAW), (k, list(tau_c), tau_ref)
            assert _close(tau_py, tau_ref, RTOL_SYMPY_LAW), (k, tau_py, tau_ref)
            assert _close(list(c_ctl.fields()["integral"]), ref.integral, RTOL_SYMPY_LAW)
        assert (saturated > 0) == (tau_max < 1.0)
