"""ASMC, adaptive sliding-mode control (Chen et al.): u = M̂(q) u_a + Ĥ(q, q̇), gain adapted
by dk̂/dt = γ ‖s‖ (explicit Euler over one sample h): k̂ never decreases."""

from __future__ import annotations

import sympy as sp

from modeling.controllers.common import Law, LawSymbols
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


def asmc_adaptation(gain: sp.Symbol, gamma: sp.Symbol, s_norm: sp.Symbol, h: sp.Symbol) -> sp.Expr:
    """ASMC: k̂(t + h) = k̂(t) + h γ ‖s(t)‖ (explicit Euler of dk̂/dt = γ‖s‖)."""
    return gain + h * gamma * s_norm


def asmc_law(formulation: Formulation, model: RobotModel) -> tuple[Law, LawSymbols]:
    """The law with the adapted gain k̂ an input (``ls.gain``)."""
    return model_law(formulation, model, lambda ls, _: ls.gain)


def asmc_kernel(formulation: Formulation, model: RobotModel) -> Kernel:
    law, ls = asmc_law(formulation, model)
    gamma, h = sp.symbols("gamma h", positive=True)
    return Kernel(
        "ASMC:\nu = Mhat(q)(ua_hat + khat s/max(|s|, eps)) + Hhat(q, qdot);\n"
        "gain_next = khat + h gamma |s|.", ("(22)", "(24)"),
        (KernelArg("q", "q", tuple(model.q)), KernelArg("qdot", "qdot", tuple(model.qdot)),
         *law_args(ls, *ERROR_DYNAMICS_ARGS),
         KernelArg("gain", "adapted_gain", (ls.gain,), "khat"),
         KernelArg("eps", "config", (ls.eps,)),
         KernelArg("adapt", "config", (gamma, h), "gamma, h")),
        (KernelArg("u", "u", tuple(law.u)), KernelArg("s", "s", tuple(law.s)),
         KernelArg("s_norm", "s_norm", (law.s_norm,)),
         KernelArg("gain_next", "gain",
                   (asmc_adaptation(ls.gain, gamma, law.s_norm, h),))),
    )


ASMC = ControllerSpec(
    "asmc", "ASMC", "adaptive sliding-mode control", "(22), (24)",
    asmc_kernel, Estimate.MODEL, Gain.ADAPTIVE,
)
