"""The laws with the nominal model's Ĥ (ROC, ASMC): shared pieces.

u = M̂(q) (u_a + k s / max(‖s‖, ε)) + Ĥ(q, q̇), (22), (24), with the gain k of the law.
"""

from __future__ import annotations

from collections.abc import Callable

import sympy as sp

from modeling.controllers.common import (
    Law,
    LawSymbols,
    law_symbols,
    nominal_acceleration,
    sliding_variable,
    switching_direction,
    with_switching,
)
from modeling.controllers.model import Formulation, control_model
from modeling.robot_model import RobotModel


def model_law(
    formulation: Formulation, model: RobotModel,
    gain: Callable[[LawSymbols, sp.Matrix], sp.Expr],
) -> tuple[Law, LawSymbols]:
    """u = M̂ u_a + Ĥ(q, q̇) with the nominal model's Ĥ and the switching gain
    ``gain(ls, feedback)`` (``feedback`` = K1 e + K2 ė)."""
    cm = control_model(formulation, model)
    ls = law_symbols(cm.size)
    ua_hat = nominal_acceleration(ls)
    k = gain(ls, ua_hat - ls.qddot_des)
    direction, s_norm = switching_direction(ls)
    u = with_switching(cm.mass, ua_hat, cm.bias, k, direction)
    return Law(u, sliding_variable(ls), s_norm, k), ls
