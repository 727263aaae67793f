"""The paper's robot's generated functions (``codegen.robot_functions`` bound to
``modeling.wmr.robot_model()``), for the runtime and tests written before robots were
generic. New code calls ``codegen.robot_functions`` with a ``RobotModel``."""

from __future__ import annotations

import sympy as sp

from codegen import robot_functions as rf
from codegen.robot_functions import MAX_WINDOW
from codegen.spec import FunctionSpec
from modeling import wmr

__all__ = ["MAX_WINDOW", "PARAM_FIELDS", "PARAM_KEYS", "law_specs", "model_specs",
           "plant_specs"]

PARAM_FIELDS: tuple[tuple[str, sp.Symbol, str], ...] = tuple(
    (p.key, p.symbol, p.doc) for p in wmr.robot_model().params
)
PARAM_KEYS = tuple(name for name, _, _ in PARAM_FIELDS)


def model_specs() -> tuple[FunctionSpec, ...]:
    return rf.model_specs(wmr.robot_model())


def law_specs() -> tuple[FunctionSpec, ...]:
    return rf.law_specs(wmr.robot_model())


def plant_specs() -> tuple[FunctionSpec, ...]:
    return rf.plant_specs(wmr.robot_model())
