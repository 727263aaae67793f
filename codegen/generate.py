"""Everything in ``generated/`` for one robot, as a mapping path → bytes (written or diffed
by __main__). Paths are relative to ``generated/``: the default robot's files sit at its
root (``c/``, ``python/``, ``casadi/``, ``MODEL.md``), every other robot's under
``<output_dir>/``.

The driver derives the robot's functions once, in their shared form
(:class:`codegen.backend.RobotTarget`), and hands the same target to every backend the
registry (:mod:`codegen.backends`) lists; each writes its own folder. It names none of
them: the report (``MODEL.md``) and the package ``__init__.py`` are its own.

Pure: the same robot gives byte-identical output whatever the hash seed. Nothing here
knows a robot: the ``RobotModel`` says what to generate, the backends how.
"""

from __future__ import annotations

import importlib
from functools import cache
from pathlib import Path

from codegen import backends
from codegen.backend import Module, RobotTarget, function_ir
from codegen.controller_layout import ControllerLayout
from codegen.robot_functions import (
    law_specs,
    minv_norm_needs_q,
    model_specs,
    plant_specs,
    trig_angles,
)
from codegen.template_util import generated_by
from modeling.robot_file import Robot
from modeling.robot_model import RobotModel

GENERATED_DIR = Path(__file__).resolve().parent.parent / "generated"
LAW_SOURCE = "modeling/controllers.py"


@cache
def layout_for(model: RobotModel) -> ControllerLayout:
    """What the controller templates need to know about ``model``."""
    return ControllerLayout(
        model.prefix, model.nq, model.nu, model.actuated, model.paper,
        minv_norm_needs_q(model), model.coordinate_names, model.input_names,
        trig_angles(model, "paper") if model.paper else (), trig_angles(model, "minimal"),
    )


def model_source(model: RobotModel) -> str:
    return model.docs.get("model_source", f"{model.source}, modeling/description/, "
                          "modeling/lagrange.py")


def robot_target(model: RobotModel, robot: Robot) -> RobotTarget:
    """What every backend is given for ``robot``: its functions (CSE'd once each here),
    grouped in modules ``<prefix>_model``, ``<prefix>_laws``, ``<prefix>_plant``."""
    p = model.prefix
    src = model_source(model)
    groups = (
        (f"{p}_model", model_specs(model), src),
        (f"{p}_laws", law_specs(model), LAW_SOURCE),
        (f"{p}_plant", plant_specs(model), src),
    )
    modules = tuple(
        Module(name, tuple(function_ir(s) for s in specs), source)
        for name, specs, source in groups
    )
    return RobotTarget(model, robot, layout_for(model), modules, src, LAW_SOURCE)


def op_counts(target: RobotTarget) -> dict[str, str]:
    """``function -> "operations after CSE: ..."`` for every generated function."""
    return {f.name: f.ops.comment() for f in target.functions()}


def generate_files(
    robot: Robot, model: RobotModel | None = None, *, report: bool = True
) -> dict[str, bytes]:
    """All generated files for ``robot`` (paths relative to ``generated/``). ``model``
    defaults to the paper's robot (a ``[lumped]``/``[physical]`` robot file)."""
    if model is None:
        from modeling.robot_file import load_robot_model

        model = load_robot_model(None)[0]
    root = f"{model.output_dir}/" if model.output_dir else ""
    target = robot_target(model, robot)
    out: dict[str, bytes] = {}
    for backend in backends.registered():
        for name, data in backend.render(target).items():
            out[f"{root}{backend.folder}/{name}"] = (
                data.encode() if isinstance(data, str) else data
            )
    out[f"{root}__init__.py"] = f'"""{generated_by()} DO NOT EDIT."""\n'.encode()
    if report:
        renderer = importlib.import_module(model.docs.get("report", "codegen.robot_report"))
        out[f"{root}MODEL.md"] = renderer.render(model, robot, op_counts(target)).encode()
    return out
