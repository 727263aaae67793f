"""TDROC, time-delayed robust optimal control (16), (17), (22), (25):
u = M̂(q) u_a + Ĥ1 with the gain

        k̂ = ‖M̂⁻¹‖_F · Σ_{i=1..n} w_i ‖Ω(i) − Ω(i+1)‖ / Σ w_i,
        Ω(i) = u(t − ih) − M̂(q(t − ih)) q̈(t − ih)   (Ω(1) is Ĥ1 of (17)).

Weights w_i = a^(i−1) (i = 1 is the most recent difference), normalised: the printed (25)
is unreadable here; Remark 3 asks that recent data weigh most, which a^(i−1) does for
0 < a < 1 (a = 1: equal weights). ‖·‖_F bounds the spectral norm from above, so the
robustness argument of (23) still holds (docs/PAPER.md item 10).
"""

from __future__ import annotations

import sympy as sp

from modeling.controllers.common import norm, vec
from modeling.controllers.declaration import (
    ERROR_DYNAMICS_ARGS,
    ControllerSpec,
    Estimate,
    Gain,
    Kernel,
    KernelArg,
    law_args,
)
from modeling.controllers.model import Formulation, control_model
from modeling.controllers.tde import tde_law
from modeling.robot_model import RobotModel


def heading_rotation(formulation: Formulation, model: RobotModel) -> sp.Matrix:
    """T(θ): rotates the root's (x, y) rows by its yaw θ in the paper form (q starts with
    them); the identity for the minimal form's wheel angles."""
    rm = model
    size = control_model(formulation, rm).size
    t = sp.eye(size)
    if formulation == "paper":
        c, s = sp.cos(rm.heading), sp.sin(rm.heading)
        t[0, 0], t[0, 1], t[1, 0], t[1, 1] = c, -s, s, c
    return t


def rotation_residual(formulation: Formulation, model: RobotModel) -> sp.Matrix:
    """M̂(θ) − T(θ) M̂(0) T(θ)ᵀ, which is zero: the model is invariant under heading.

    So M̂(θ)⁻¹ = T M̂(0)⁻¹ Tᵀ with T orthogonal, and every unitarily invariant norm of
    M̂⁻¹ (Frobenius, spectral) is independent of θ — (25) needs it for the parameters
    only. Tests assert the residual simplifies to zero.
    """
    rm = model
    cm = control_model(formulation, rm)
    t = heading_rotation(formulation, rm)
    at_zero = cm.mass.subs(rm.heading, 0)
    return (cm.mass - t * at_zero * t.T).applyfunc(rm.system.simplify)


# Up to this size ‖M̂⁻¹‖_F is built from M̂'s entries as ‖adj M̂‖_F / |det M̂|: the expanded
# inverse costs ~2.4x the operations (Drishti's minimal form 75 -> 31, the trailer's 994 -> 425).
ADJUGATE_NORM_MAX_SIZE = 3


def mass_inverse_norm(formulation: Formulation, model: RobotModel) -> sp.Expr:
    """‖M̂⁻¹‖_F of (25). The paper form is evaluated at θ = 0 (exact for every θ, see
    rotation_residual); the minimal form as it is — a constant for a single body, a
    function of the hitch angles for a robot with trailers (then an input of the kernel).
    A small M̂ (``ADJUGATE_NORM_MAX_SIZE``) goes through its entries: M̂⁻¹ = adj M̂ / det M̂
    over entry symbols, the entries substituted after (the same value, fewer operations)."""
    rm = model
    cm = control_model(formulation, rm)
    if cm.stage is not None:  # M-hat's entries are quantities of the stage
        n = cm.mass.rows
        if n > ADJUGATE_NORM_MAX_SIZE:
            return norm(sp.Matrix(list(cm.stage.solve(cm.mass, sp.eye(n)))))
        return norm(sp.Matrix(list(cm.mass.adjugate()))) / sp.Abs(cm.mass.det())
    if formulation == "paper":
        mass, inverse = cm.mass.subs(rm.heading, 0), cm.mass_inverse.subs(rm.heading, 0)
    else:
        mass, inverse = cm.mass, cm.mass_inverse
    n = mass.rows
    if n > ADJUGATE_NORM_MAX_SIZE:
        return norm(sp.Matrix(list(inverse)))
    entries = sp.Matrix(n, n, lambda i, j: sp.Symbol(f"_mhat_{i}_{j}", real=True))
    by_entries = norm(sp.Matrix(list(entries.adjugate()))) / sp.Abs(entries.det())
    return by_entries.subs(dict(zip(list(entries), list(mass), strict=True)), simultaneous=True)


def tdroc_gain(
    formulation: Formulation, window: int, model: RobotModel
) -> tuple[sp.Expr, sp.Matrix, sp.Matrix]:
    """(25): k̂ = ‖M̂⁻¹‖_F Σ_{i=1..window} w_i ‖Ω(i) − Ω(i+1)‖ with the weights w_i
    given normalised (Σ w_i = 1 over the active window, 0 beyond it) by the caller.
    ‖M̂⁻¹‖_F depends on the nominal parameters only (``mass_inverse_norm``): it is an
    input here (symbol ``minv_norm``), computed when the nominal parameters change.

    Returns (k̂, Ω window symbols ((window + 1) × n, row i = Ω(i + 1)), weight symbols).
    """
    cm = control_model(formulation, model)
    n = cm.size
    omega = sp.Matrix(window + 1, n, lambda i, j: sp.Symbol(f"Om{i}_{j}", real=True))
    w = vec("w", window)
    total = sp.S.Zero
    for i in range(window):
        total += w[i] * norm((omega[i, :] - omega[i + 1, :]).T)
    return sp.Symbol("minv_norm", positive=True) * total, omega, w


def omega_difference_norm(
    formulation: Formulation, model: RobotModel
) -> tuple[sp.Expr, sp.Matrix, sp.Matrix]:
    """One term of (25): ‖Ω(i) − Ω(i+1)‖ for two consecutive rows of the window.

    Each difference is computed once, when its newer row joins the window, and then only
    moves down the window: a step evaluates one norm instead of ``window``. Returns (norm,
    newer row symbols, older row symbols).
    """
    n = control_model(formulation, model).size
    newer, older = vec("Om_new", n), vec("Om_old", n)
    return norm(newer - older), newer, older


def tdroc_weighted_gain(window: int) -> tuple[sp.Expr, sp.Matrix, sp.Matrix]:
    """(25) from the window's difference norms d_i = ‖Ω(i) − Ω(i+1)‖ (``omega_difference_norm``):
    k̂ = ‖M̂⁻¹‖_F Σ_{i=1..window} w_i d_i — ``tdroc_gain`` with its norms given.

    Returns (k̂, difference-norm symbols, weight symbols); ``minv_norm`` as in ``tdroc_gain``.
    """
    d = vec("dn", window)
    w = vec("w", window)
    total = sum((w[i] * d[i] for i in range(window)), sp.S.Zero)
    return sp.Symbol("minv_norm", positive=True) * total, d, w


def tdroc_kernel(formulation: Formulation, model: RobotModel) -> Kernel:
    law, ls = tde_law(formulation, switching=True, model=model)
    return Kernel(
        "TDROC (16), (22), (25):\nu = Mhat(q)(ua_hat + gain s/max(|s|, eps))\n"
        "+ H1hat, s = B^T P e.", ("(16)", "(22)", "(24)", "(25)"),
        (KernelArg("q", "q", tuple(model.q)), *law_args(ls, *ERROR_DYNAMICS_ARGS, "H1hat"),
         KernelArg("gain", "khat", (ls.gain,), "khat of (25)"),
         KernelArg("eps", "config", (ls.eps,), "boundary layer")),
        (KernelArg("u", "u", tuple(law.u)), KernelArg("s", "s", tuple(law.s)),
         KernelArg("s_norm", "s_norm", (law.s_norm,))),
    )


TDROC = ControllerSpec(
    "tdroc", "TDROC", "time-delayed robust optimal control", "(16)-(18), (22)-(25)",
    tdroc_kernel, Estimate.TDE, Gain.WINDOW,
)
