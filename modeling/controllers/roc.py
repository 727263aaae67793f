"""ROC, robust control with predefined bounds (Ryu & Agarwal's robust control in its
standard Lyapunov-redesign form; ROC and ASMC are only cited by the paper, docs/PAPER.md
item 11): u = M̂(q) u_a + Ĥ(q, q̇) (full nominal model), gain

        ρ = (α (‖q̈_d‖ + ‖K1 e + K2 ė‖) + φ) / (1 − α),

α ≥ ‖M⁻¹ M̂ − I‖ and φ ≥ ‖M⁻¹ (H − Ĥ)‖ over the predefined uncertainty box (30 % above
nominal), computed when the configuration is built.
"""

from __future__ import annotations

import sympy as sp

from modeling.controllers.common import Law, LawSymbols, norm
from modeling.controllers.declaration import (
    ERROR_DYNAMICS_ARGS,
    ControllerSpec,
    Estimate,
    Gain,
    Kernel,
    KernelArg,
    law_args,
)
from modeling.controllers.model import Formulation
from modeling.controllers.model_based import model_law
from modeling.robot_model import RobotModel


def roc_gain(ls: LawSymbols, feedback: sp.Matrix) -> sp.Expr:
    """ρ = (α(‖q̈_d‖ + ‖K1 e + K2 ė‖) + φ)/(1 − α)."""
    return (ls.alpha * (norm(ls.qddot_des) + norm(feedback)) + ls.phi) / (1 - ls.alpha)


def roc_law(formulation: Formulation, model: RobotModel) -> tuple[Law, LawSymbols]:
    return model_law(formulation, model, roc_gain)


def roc_kernel(formulation: Formulation, model: RobotModel) -> Kernel:
    law, ls = roc_law(formulation, model)
    return Kernel(
        "ROC:\nu = Mhat(q)(ua_hat + rho s/max(|s|, eps)) + Hhat(q, qdot),\n"
        "rho = (alpha(|qddot_des| + |K1 e + K2 edot|) + phi)/(1 - alpha).", ("(22)", "(24)"),
        (KernelArg("q", "q", tuple(model.q)), KernelArg("qdot", "qdot", tuple(model.qdot)),
         *law_args(ls, *ERROR_DYNAMICS_ARGS),
         KernelArg("bounds", "config", (ls.alpha, ls.phi), "alpha, phi"),
         KernelArg("eps", "config", (ls.eps,))),
        (KernelArg("u", "u", tuple(law.u)), KernelArg("s", "s", tuple(law.s)),
         KernelArg("s_norm", "s_norm", (law.s_norm,)),
         KernelArg("gain", "gain", (law.gain,))),
    )


ROC = ControllerSpec(
    "roc", "ROC", "robust control with predefined bounds", "(22), (24)",
    roc_kernel, Estimate.MODEL, Gain.BOUNDS,
)
