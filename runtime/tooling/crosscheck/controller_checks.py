"""The controller rows of the hand-written comparison (the paper's robot): every
implementation's per-step τ, switching gain, ‖s‖, Ĥ1 and ‖u₁₋₃‖ against the hand-written
controller's, the CasADi law kernels on the inputs the reference used, and how often each
branch of the step was exercised.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from runtime.tooling.crosscheck.bindings import casadi_call as call
from runtime.tooling.crosscheck.bindings import casadi_function, pvec
from runtime.tooling.crosscheck.controller_runs import c32_synced_run, c_run, hand_run, python_run
from runtime.tooling.crosscheck.deviation import IMPLS, Deviation, Params, Row, Trace, perturbed
from runtime.tooling.crosscheck.inputs import Sequence_
from runtime.tooling.crosscheck.targets import Target
from runtime.tooling.witness import controllers as hc


def compare_traces(dev: Deviation, got: Trace, ref: Trace, nc: int, check_status: bool) -> None:
    dev.add("tau", got.tau, ref.tau)
    dev.add("gain", got.gain, ref.gain)
    dev.add("|s|", got.s_norm, ref.s_norm)
    dev.add("H1hat", [h[:nc] for h in got.H1hat], [h[:nc] for h in ref.H1hat])
    dev.add("|u_1..3|", got.u_discarded, ref.u_discarded)
    if check_status and got.saturated != ref.saturated:
        dev.merge(math.inf, "saturation status")


def casadi_kernels(
    target: Target,
    seq: Sequence_,
    kind: hc.Kind,
    records: list[hc.StepRecord],
    nominal: Params,
) -> Deviation:
    """The CasADi law kernels on the inputs the reference used, step by step."""
    form = seq.settings.formulation
    pv = pvec(target, nominal)

    def casadi_call(name: str, *args: Any) -> list[Any]:
        return call(target, name, *args)

    dev = Deviation()
    got: dict[str, list[Any]] = {}
    want: dict[str, list[Any]] = {}

    def add(name: str, g: Any, w: Any) -> None:
        got.setdefault(name, []).append(g)
        want.setdefault(name, []).append(w)

    s = seq.settings
    for rec in records:
        if rec.tde_inputs is not None:
            q_prev, u_prev, now, then, span = rec.tde_inputs
            add(
                "tde",
                casadi_call(f"{form}_tde", pv, q_prev, u_prev, now, then, [span])[0],
                rec.H1hat,
            )
        if rec.window is not None:
            om, w, minv_norm = rec.window
            if casadi_function(target, f"{form}_tdroc_gain").name_in(0) == "minv_norm":
                add("minv_norm", casadi_call(f"{form}_minv_norm", pv)[0], [minv_norm])
                gain = casadi_call(f"{form}_tdroc_gain", [minv_norm], om.ravel(), w)[0]
            else:  # older signature: (p, q, omega, w)
                gain = casadi_call(f"{form}_tdroc_gain", pv, rec.q, om.ravel(), w)[0]
            add("tdroc_gain", gain, [rec.gain_in])
        common = (rec.e, rec.edot, rec.qdd_des, rec.k1, rec.k2, rec.p12, rec.p22)
        if kind == "tdc":
            out = casadi_call(f"{form}_tdc_law", pv, rec.q, *common, rec.H1hat)
            add("u", out[0], rec.u)
        elif kind == "tdroc":
            out = casadi_call(
                f"{form}_tdroc_law", pv, rec.q, *common, rec.H1hat, [rec.gain_in], [s.eps]
            )
            add("u", out[0], rec.u)
            add("s", out[1], rec.s)
            add("|s|", out[2], [rec.s_norm])
        elif kind == "roc":
            out = casadi_call(
                f"{form}_roc_law", pv, rec.q, rec.qdot, *common, [s.alpha, s.phi], [s.eps]
            )
            add("u", out[0], rec.u)
            add("|s|", out[2], [rec.s_norm])
            add("gain", out[3], [rec.gain_out])
        else:
            out = casadi_call(
                f"{form}_asmc_law",
                pv,
                rec.q,
                rec.qdot,
                *common,
                [rec.gain_in],
                [s.eps],
                [s.gamma, s.h],
            )
            add("u", out[0], rec.u)
            add("|s|", out[2], [rec.s_norm])
            add("gain", out[3], [rec.gain_out])
    # P of (20): the Lyapunov kernel for every coordinate.
    k1, k2 = np.asarray(s.k1), np.asarray(s.k2)
    for i in range(5):
        add("lyapunov_p", casadi_call("lyapunov_p", [k1[i], k2[i], s.q_pos, s.q_vel])[0][1:],
            hc.lyapunov_p(k1[i], k2[i], s.q_pos, s.q_vel)[1:])  # fmt: skip
    for name in got:
        dev.add(name, got[name], want[name])
    return dev


def check_controllers(
    target: Target,
    sequences: list[tuple[hc.Kind, Sequence_]],
    perturb: Mapping[str, Mapping[str, float]],
) -> tuple[list[Row], dict[str, int]]:
    """Rows of the controller table, and how often each branch of the step was exercised."""
    rows: dict[str, Row] = {}
    cover = dict.fromkeys(
        ("steps", "saturated", "inside boundary layer", "outside boundary layer",
         "TDE active", "central estimator", "matched estimator",
         "window full (n Ω differences)"), 0
    )  # fmt: skip
    for kind, seq in sequences:
        form = seq.settings.formulation
        nc = 5 if form == "paper" else 2
        row = rows.setdefault(f"{kind}/{form}", Row(f"{kind}/{form}"))
        nominal = dict(seq.settings.nominal)
        ref, records = hand_run(seq, kind)
        s = seq.settings
        for rec in records:
            cover["steps"] += 1
            cover["saturated"] += rec.saturated
            if kind != "tdc":
                cover["inside boundary layer"] += rec.s_norm < s.eps
                cover["outside boundary layer"] += rec.s_norm >= s.eps
            cover["TDE active"] += rec.tde_inputs is not None
            cover["central estimator"] += rec.tde_inputs is not None and s.accel == "central"
            cover["matched estimator"] += rec.tde_inputs is not None and s.accel == "matched"
            cover["window full (n Ω differences)"] += (
                rec.window is not None and int(np.count_nonzero(rec.window[1])) == s.n
            )
        cells = {impl: row.cells.setdefault(impl, Deviation()) for impl in IMPLS}
        compare_traces(
            cells["python"],
            python_run(target, seq, kind, perturbed(nominal, "python", perturb)),
            ref,
            nc,
            True,
        )
        compare_traces(
            cells["c64"], c_run(target, seq, kind, perturbed(nominal, "c64", perturb)), ref, nc,
            True,
        )
        kd = casadi_kernels(target, seq, kind, records, perturbed(nominal, "casadi", perturb))
        cells["casadi"].merge(kd.value, kd.worst)
        got32, want32 = c32_synced_run(target, seq, kind, perturb)
        compare_traces(cells["c32"], got32, want32, nc, False)
    return list(rows.values()), cover
