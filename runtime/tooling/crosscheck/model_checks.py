"""The hand-written comparison (the paper's robot): the model functions of every
implementation against the hand-written (14), (31) and minimal forms, and the hand-written
equations' consistency with each other and with (9).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from runtime.tooling.crosscheck.bindings import CModel, casadi_call, pvec
from runtime.tooling.crosscheck.deviation import (
    IMPLS,
    Arr,
    Deviation,
    Params,
    Row,
    f32,
    f32_params,
    perturbed,
)
from runtime.tooling.crosscheck.inputs import model_args
from runtime.tooling.crosscheck.targets import Target
from runtime.tooling.witness import controllers as hc
from runtime.tooling.witness import model as hw

ModelFn = Callable[[str, Params, tuple[Arr, ...]], Arr]
# name, hand-written function, generated function (argument layout, NumPy and CasADi name),
# output size, C name (the generated name unless given)
MODEL_FUNCTIONS: tuple[tuple[str, Callable[..., Arr], str, int, str], ...] = (
    ("M (14)", hw.mass_matrix_14, "mass_matrix", 25, ""),
    ("H (14)", hw.bias_14, "bias_forces", 5, ""),
    ("forward dynamics (14)", hw.forward_dynamics_14, "forward_dynamics", 5, ""),
    # C: wmr_model_prepare once per sample, then wmr_forward_dynamics_prepared
    ("forward dynamics, prepared", hw.forward_dynamics_14, "forward_dynamics", 5,
     "forward_dynamics_prepared"),
    ("kinematics (31)", hw.kinematics_31, "kinematics", 3, ""),
    ("Mbar = S'MS", hw.minimal_mass_matrix, "minimal_mass_matrix", 4, ""),
    ("Hbar = S'(M Sdot eta + H)", hw.minimal_bias, "minimal_bias_forces", 2, ""),
    ("minimal forward dynamics", hw.minimal_forward_dynamics, "minimal_forward_dynamics", 2,
     ""),
)


def check_models(
    target: Target,
    samples: list[tuple[Params, Arr, Arr, Arr]],
    perturb: Mapping[str, Mapping[str, float]],
) -> list[Row]:
    model = target.code.model
    cm = {"c64": CModel(target, False), "c32": CModel(target, True)}
    rows = []
    for title, ref_fn, gen, n_out, c_name in MODEL_FUNCTIONS:
        c_fn = c_name or gen
        row = Row(title)
        results: dict[str, list[Arr]] = {k: [] for k in (*IMPLS, "ref", "ref32")}
        for p, q, eta, tau in samples:
            args = model_args(gen, q, eta, tau, p)
            results["ref"].append(np.ravel(ref_fn(*args, p)))
            results["python"].append(
                np.ravel(getattr(model, gen)(*args, perturbed(p, "python", perturb)))
            )
            results["c64"].append(cm["c64"].call(c_fn, perturbed(p, "c64", perturb), args, n_out))
            results["casadi"].append(
                casadi_call(target, gen, pvec(target, perturbed(p, "casadi", perturb)), *args)[0]
            )
            # float32: rounded inputs; the reference sees exactly those rounded values.
            p32 = f32_params(p)
            args32 = tuple(f32(a) for a in model_args(gen, f32(q), f32(eta), f32(tau), p32))
            results["ref32"].append(np.ravel(ref_fn(*args32, p32)))
            results["c32"].append(
                cm["c32"].call(c_fn, perturbed(p32, "c32", perturb), args32, n_out)
            )
        for impl in IMPLS:
            dev = Deviation()
            dev.add(title, results[impl], results["ref32" if impl == "c32" else "ref"])
            row.cells[impl] = dev
        rows.append(row)
    return rows


def self_checks(samples: list[tuple[Params, Arr, Arr, Arr]]) -> list[tuple[str, float, bool]]:
    """Consistency of the hand-written equations with each other and with (9):
    (name, max relative deviation, gated)."""
    import scipy.linalg

    checks: dict[str, Deviation] = {}

    def add(name: str, got: Any, ref: Any) -> None:
        checks.setdefault(name, Deviation()).add(name, [got], [ref])

    for p, q, eta, tau in samples:
        S, A = hw.null_space(q, p), hw.constraint_matrix(q, p)
        M9, qdot = hw.mass_matrix_9(q, p), hw.qdot_on_manifold(q, eta, p)
        Ma, Sa = M9[:3, :3], S[:3]
        block = np.block([[Ma, -Ma @ Sa], [Sa.T @ Ma, p["Iw"] * np.eye(2)]])
        add(
            "A(q) S(q) = 0, (31) corrected vs (6)-(8) [abs. residual]", A @ S + 1.0, np.ones((3, 2))
        )
        add("M (14) printed = [[Ma, -Ma Sa], [Sa' Ma, Iw]] derived", hw.mass_matrix_14(q, p), block)
        h_block = np.concatenate(
            [-Ma @ hw.null_space_rate_times_eta(q, eta, p)[:3], Sa.T @ hw.bias_9(q, qdot, p)[:3]]
        )
        add("H (14) printed = [-Ma Sdot_a eta; Sa' Ha] derived", hw.bias_14(q, qdot, p), h_block)
        mbar = hw.minimal_mass_matrix(q, p)
        q0 = np.array([q[0], q[1], 0.0, q[3], q[4]])
        add(
            "||M (14)^-1||_F independent of heading (TDROC gain of (25))",
            np.linalg.norm(np.linalg.inv(hw.mass_matrix_14(q, p))),
            np.linalg.norm(np.linalg.inv(hw.mass_matrix_14(q0, p))),
        )
        add(
            "M (14) S = [0; Mbar]", hw.mass_matrix_14(q, p) @ S, np.vstack([np.zeros((3, 2)), mbar])
        )
        # (14) against the constrained Lagrange equations (9) + (6)-(8), solved as KKT system.
        th, thd = q[2], qdot[2]
        adot = np.array(
            [
                [-math.cos(th) * thd, -math.sin(th) * thd, 0.0, 0.0, 0.0],
                [math.sin(th) * thd, -math.cos(th) * thd, 0.0, 0.0, 0.0],
                [math.sin(th) * thd, -math.cos(th) * thd, 0.0, 0.0, 0.0],
            ]
        )
        kkt = np.block([[M9, A.T], [A, np.zeros((3, 3))]])
        rhs = np.concatenate([hw.input_matrix_9() @ tau - hw.bias_9(q, qdot, p), -adot @ qdot])
        add(
            "forward dynamics (14) = KKT solve of (9) with (6)-(8)",
            hw.forward_dynamics_14(q, qdot, tau, p),
            np.linalg.solve(kkt, rhs)[:5],
        )
        add(
            "forward dynamics (14) = S etadot + Sdot eta (minimal)",
            hw.forward_dynamics_14(q, qdot, tau, p),
            hw.pose_acceleration(q, eta, hw.minimal_forward_dynamics(q, eta, tau, p), p),
        )
        k1, k2, qp, qv = (float(x) for x in np.abs(tau[:1].tolist() + eta.tolist() + [p["m"]]))
        k1, k2 = 1.0 + k1 % 7, 1.0 + k2 % 7
        qp, qv = 0.5 + qp % 2, 0.5 + qv % 2
        a_mat = np.array([[0.0, 1.0], [-k1, -k2]])
        pm = scipy.linalg.solve_continuous_lyapunov(a_mat.T, -np.diag([qp, qv]))
        p11, p12, p22 = hc.lyapunov_p(k1, k2, qp, qv)
        add(
            "lyapunov_p = scipy solve_continuous_lyapunov",
            [p11, p12, p22],
            [pm[0, 0], pm[0, 1], pm[1, 1]],
        )
    gated = [(name, d.value, True) for name, d in checks.items()]
    # Information only: how far the printed (31) (b where b/2 belongs) is from (6)-(8).
    printed = Deviation()
    for p, q, eta, _ in samples:
        printed.add(
            "printed", [hw.kinematics_31_as_printed(q, eta, p)], [hw.kinematics_31(q, eta, p)]
        )
    gated.append(
        ("(31) as printed (b, not b/2) vs corrected [erratum, info]", printed.value, False)
    )
    return gated
