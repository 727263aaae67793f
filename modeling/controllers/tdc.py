"""TDC, time-delay control (16)–(18): u = M̂(q) û_a + Ĥ1, no switching term."""

from __future__ import annotations

from modeling.controllers.declaration import (
    ERROR_DYNAMICS_ARGS,
    ControllerSpec,
    Estimate,
    Kernel,
    KernelArg,
    law_args,
)
from modeling.controllers.model import Formulation
from modeling.controllers.tde import tde_law
from modeling.robot_model import RobotModel


def tdc_kernel(formulation: Formulation, model: RobotModel) -> Kernel:
    law, ls = tde_law(formulation, switching=False, model=model)
    return Kernel(
        "TDC (16), (18): u = Mhat(q) ua_hat + H1hat.", ("(16)", "(18)"),
        (KernelArg("q", "q", tuple(model.q)), *law_args(ls, *ERROR_DYNAMICS_ARGS, "H1hat")),
        (KernelArg("u", "u", tuple(law.u)),),
    )


TDC = ControllerSpec(
    "tdc", "TDC", "time-delay control", "(16)-(18)", tdc_kernel, Estimate.TDE,
)
