"""The controllers codegen generates, in order: each declared once, in its own file.

codegen builds the kernels and the C and Python step functions from these entries, the
generated robot.py exports them, and the runtime and the reports iterate them. A new law
is one file beside the others and one entry here.
"""

from __future__ import annotations

from dataclasses import replace
from functools import cache

from modeling.controllers.asmc import ASMC
from modeling.controllers.declaration import ControllerSpec, Kernel
from modeling.controllers.model import Formulation, control_model
from modeling.controllers.pi import PI
from modeling.controllers.roc import ROC
from modeling.controllers.tdc import TDC
from modeling.controllers.tdroc import TDROC
from modeling.robot_model import RobotModel

REGISTRY: tuple[ControllerSpec, ...] = (TDC, TDROC, ROC, ASMC, PI)
CONTROLLERS = tuple(c.name for c in REGISTRY)


@cache
def kernel(spec: ControllerSpec, formulation: Formulation, model: RobotModel) -> Kernel:
    """``spec``'s law kernel for one formulation of ``model`` (derived once), with the
    staged quantities its outputs read (a staged robot's)."""
    k = spec.kernel(formulation, model)
    if formulation not in model.formulations or not model.staged:
        return k
    exprs = [e for a in k.outputs for e in a.values]
    return replace(k, definitions=control_model(formulation, model).definitions(exprs))


def controller(name: str) -> ControllerSpec:
    """The registry entry of ``name``."""
    for c in REGISTRY:
        if c.name == name:
            return c
    raise ValueError(f"no controller {name!r} (known: {', '.join(CONTROLLERS)})")
