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
from collections.abc import Callable
from functools import cache
from pathlib import Path

from codegen import backends
from codegen.backend import Module, RobotTarget, function_ir, with_shared
from codegen.certify.stored import model_section
from codegen.controller_layout import ControllerLayout
from codegen.progress import Progress, quiet
from codegen.robot_functions import (
    law_specs,
    mhat_kernels,
    minv_norm_needs_q,
    model_specs,
    plant_specs,
    trig_angles,
)
from codegen.spec import FunctionSpec
from codegen.template_util import generated_by
from modeling import controllers as ctl
from modeling.controllers import ControllerSpec
from modeling.robot_file import Robot
from modeling.robot_model import RobotModel

GENERATED_DIR = Path(__file__).resolve().parent.parent / "generated"
# Named in the generated files' preambles; kept as the laws' former single file so that
# generated/ stays byte-identical (the laws are now the package modeling/controllers/).
LAW_SOURCE = "modeling/controllers.py"


@cache
def layout_for(model: RobotModel) -> ControllerLayout:
    """What the controller templates need to know about ``model``."""
    return ControllerLayout(
        model.prefix, model.nq, model.nu, model.actuated, model.paper,
        minv_norm_needs_q(model), model.coordinate_names, model.input_names,
        trig_angles(model, "paper") if model.paper else (), trig_angles(model, "minimal"),
        len(ctl.control_model("minimal", model).mass) if mhat_kernels(model, "minimal") else 0,
    )


def model_source(model: RobotModel) -> str:
    return model.docs.get("model_source", f"{model.source}, modeling/description/, "
                          "modeling/lagrange.py")


# The steps of one robot's generation as progress names them: what is derived (lazily: a
# step includes the derivation it is the first to need) and what is generated.
MODULE_STEPS = {
    "model": "deriving the model (S, M, H; minimal form, forward dynamics, linearization)",
    "laws": "deriving the control laws",
    "plant": "deriving the plant",
}


def robot_target(model: RobotModel, robot: Robot, progress: Progress | None = None,
                 controllers: tuple[ControllerSpec, ...] = ctl.REGISTRY) -> RobotTarget:
    """What every backend is given for ``robot``: its functions (CSE'd once each here),
    grouped in modules ``<prefix>_model``, ``<prefix>_laws`` (with the kernels of
    ``controllers``), ``<prefix>_plant``."""
    progress = progress or quiet(robot.name)
    p = model.prefix
    src = model_source(model)
    groups: tuple[tuple[str, Callable[[], tuple[FunctionSpec, ...]], str], ...] = (
        ("model", lambda: model_specs(model), src),
        ("laws", lambda: law_specs(model, controllers), LAW_SOURCE),
        ("plant", lambda: plant_specs(model), src),
    )
    modules = []
    for name, specs, source in groups:
        with progress.step(MODULE_STEPS[name]):
            functions = with_shared(tuple(function_ir(s) for s in specs()))
        modules.append(Module(f"{p}_{name}", functions, source))
    return RobotTarget(model, robot, layout_for(model), tuple(modules), src, LAW_SOURCE,
                       controllers)


def op_counts(target: RobotTarget) -> dict[str, str]:
    """``function -> "operations after CSE: ..."`` for every generated function."""
    return {f.name: f.ops.comment() for f in target.functions()}


def generate_files(
    robot: Robot, model: RobotModel | None = None, *, report: bool = True,
    progress: Progress | None = None, controllers: tuple[ControllerSpec, ...] = ctl.REGISTRY,
) -> dict[str, bytes]:
    """All generated files for ``robot`` (paths relative to ``generated/``). ``model``
    defaults to the paper's robot (a ``[lumped]``/``[physical]`` robot file); ``progress``
    announces and times each step (derivations, then one step per backend);
    ``controllers``: those generated (the registry's)."""
    if model is None:
        from modeling.robot_file import load_robot_model

        model = load_robot_model(None)[0]
    progress = progress or quiet(robot.name)
    root = f"{model.output_dir}/" if model.output_dir else ""
    target = robot_target(model, robot, progress, controllers)
    out: dict[str, bytes] = {}
    for backend in backends.registered():
        with progress.step(f"generating {backend.folder}/"):
            for name, data in backend.render(target).items():
                out[f"{root}{backend.folder}/{name}"] = (
                    data.encode() if isinstance(data, str) else data
                )
    out[f"{root}__init__.py"] = f'"""{generated_by()} DO NOT EDIT."""\n'.encode()
    if report:
        with progress.step("writing the report (MODEL.md)"):
            renderer = importlib.import_module(model.docs.get("report",
                                                              "codegen.robot_report"))
            report_text = renderer.render(model, robot, op_counts(target))
            out[f"{root}MODEL.md"] = (report_text + model_section(model.prefix)).encode()
    return out
