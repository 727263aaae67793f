"""Everything in ``generated/`` for one robot, as a mapping path → bytes (written or diffed
by __main__). Paths are relative to ``generated/``: the default robot's files sit at its
root (``c/``, ``python/``, ``casadi/``, ``MODEL.md``), every other robot's under
``<output_dir>/``.

Pure: the same robot gives byte-identical output whatever the hash seed. Nothing here
knows a robot: the ``RobotModel`` says what to generate, the backends how.
"""

from __future__ import annotations

import importlib
from functools import cache
from pathlib import Path

from codegen import template_util
from codegen.backends import c as c_backend
from codegen.backends import casadi as casadi_backend
from codegen.backends import python as py_backend
from codegen.backends.c.config import CConfig
from codegen.backends.c.render import TEMPLATE_DIR as C_TEMPLATES
from codegen.backends.python.render import TEMPLATE_DIR as PY_TEMPLATES
from codegen.controller_api import CONTROLLERS, MAX_ABS_INPUT, defines, status_codes
from codegen.controller_layout import ControllerLayout
from codegen.cse import count_ops, cse_function
from codegen.robot_functions import (
    MAX_WINDOW,
    law_specs,
    minv_norm_needs_q,
    model_specs,
    plant_specs,
)
from codegen.spec import FunctionSpec
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
    )


@cache
def c_config(model: RobotModel) -> CConfig:
    """The C backend's names for ``model``: ``<prefix>_real_t``, ``<PREFIX>_LIT`` …"""
    layout = layout_for(model)
    p, big = model.prefix, model.prefix.upper()
    return CConfig(
        prefix=f"{p}_", types_header=f"{p}_types.h", real_type=f"{p}_real_t",
        status_type=f"{p}_status_t", params_ctype=f"{p}_params_t",
        float32_define=f"{big}_FLOAT32", literal_macro=f"{big}_LIT",
        status_codes=status_codes(layout), defines=defines(layout),
    )


def model_source(model: RobotModel) -> str:
    return model.docs.get("model_source", f"{model.source}, modeling/description/, "
                          "modeling/lagrange.py")


def plant_values(model: RobotModel, robot: Robot) -> dict[str, float]:
    """The simulated robot's parameters: the robot file's numbers, the model's defaults
    for plant-only parameters the file does not set."""
    given = robot.plant_values()
    return {p.key: float(given.get(p.key, model.values[p.key])) for p in model.plant_params}


def _modules(model: RobotModel) -> tuple[tuple[str, tuple[FunctionSpec, ...], str], ...]:
    p = model.prefix
    src = model_source(model)
    return (
        (f"{p}_model", model_specs(model), src),
        (f"{p}_laws", law_specs(model), LAW_SOURCE),
        (f"{p}_plant", plant_specs(model), src),
    )


def _c_files(model: RobotModel, robot: Robot) -> dict[str, str]:
    layout = layout_for(model)
    config = c_config(model)
    pre = layout.prefix
    files = c_backend.render_all(
        {name: specs for name, specs, _ in _modules(model)},
        config,
        source=f"{model_source(model)}, {LAW_SOURCE}",
    )
    param_fields = [config.c_field(p.key) for p in model.params]
    for suffix in ("h", "c"):
        template = f"controller_common.{suffix}.jinja"
        files[f"{pre}_controller.{suffix}"] = template_util.render(
            C_TEMPLATES,
            template,
            preamble=template_util.preamble_lines(LAW_SOURCE, C_TEMPLATES, template),
            layout=layout,
            param_fields=param_fields,
            max_abs_input=MAX_ABS_INPUT,
        )
    for info in CONTROLLERS:
        for suffix in ("h", "c"):
            template = f"controller.{suffix}.jinja"
            files[f"{pre}_{info.name}.{suffix}"] = template_util.render(
                C_TEMPLATES,
                template,
                preamble=template_util.preamble_lines(LAW_SOURCE, C_TEMPLATES, template),
                layout=layout,
                c=info,
                max_abs_input=MAX_ABS_INPUT,
            )
    fields = [(config.c_field(p.key), repr(robot.lumped[p.key])) for p in model.params]
    files[f"{pre}_robot.h"] = template_util.render(
        C_TEMPLATES,
        "robot.h.jinja",
        preamble=template_util.preamble_lines(robot.source, C_TEMPLATES, "robot.h.jinja"),
        layout=layout,
        robot_name=robot.name,
        fields=fields,
    )
    files["example_main.c"] = template_util.render(
        C_TEMPLATES,
        "example_main.c.jinja",
        preamble=template_util.preamble_lines(
            "codegen/generate.py", C_TEMPLATES, "example_main.c.jinja"
        ),
        layout=layout,
        param_fields=param_fields,
    )
    return files


def _robot_py(model: RobotModel, robot: Robot) -> str:
    params = ", ".join(f'"{p.key}": {robot.lumped[p.key]!r}' for p in model.params)
    text = (
        f'"""Default parameters of robot "{robot.name}" (from {robot.source}).\n\n'
        'Generated by `python -m codegen`. DO NOT EDIT.\n"""\n\n'
        f'NAME = "{robot.name}"\nPARAMS: dict[str, float] = {{{params}}}\n'
    )
    plant = ", ".join(f'"{k}": {v!r}' for k, v in plant_values(model, robot).items())
    names = ", ".join(f'"{n}"' for n in model.coordinate_names)
    inputs = ", ".join(f'"{n}"' for n in model.input_names)
    return text + (
        f'PLANT_PARAMS: dict[str, float] = {{{plant}}}\n'
        f'PREFIX = "{model.prefix}"\n'
        f"NQ = {model.nq}  # generalised coordinates\n"
        f"NU = {model.nu}  # inputs (driven wheels)\n"
        f"ACTUATED = {model.actuated!r}  # index in q of each input's wheel angle\n"
        f"COORDINATES = ({names},)\n"
        f"INPUTS = ({inputs},)\n"
        f"FORMULATIONS = {tuple(model.formulations)!r}\n"
    )


def _python_files(model: RobotModel, robot: Robot) -> dict[str, str]:
    layout = layout_for(model)
    config = c_config(model)
    files: dict[str, str] = {}
    for name, specs, source in _modules(model):
        files.update(py_backend.render(specs, name, source=source))
    template = "controllers.py.jinja"
    files["controllers.py"] = template_util.render(
        PY_TEMPLATES,
        template,
        preamble=template_util.preamble_lines(LAW_SOURCE, PY_TEMPLATES, template),
        layout=layout,
        status_codes=status_codes(layout),
        controllers=CONTROLLERS,
        formulation_paper=0,
        formulation_minimal=1,
        max_window=MAX_WINDOW,
        max_abs_input=MAX_ABS_INPUT,
        c_field_names=dict(config.field_renames),
        param_keys=[p.key for p in model.params],
    )
    files["robot.py"] = _robot_py(model, robot)
    files["__init__.py"] = (
        '"""Generated NumPy-only model and controllers. DO NOT EDIT (python -m codegen)."""\n'
    )
    return files


def op_counts(model: RobotModel) -> dict[str, str]:
    """``function -> "operations after CSE: ..."`` for every generated function."""
    return {
        s.name: count_ops(cse_function(s.checked_spec())).comment()
        for _, specs, _ in _modules(model)
        for s in specs
    }


def generate_files(
    robot: Robot, model: RobotModel | None = None, *, report: bool = True
) -> dict[str, bytes]:
    """All generated files for ``robot`` (paths relative to ``generated/``). ``model``
    defaults to the paper's robot (a ``[lumped]``/``[physical]`` robot file)."""
    if model is None:
        from modeling.robot_file import load_robot_model

        model = load_robot_model(None)[0]
    root = f"{model.output_dir}/" if model.output_dir else ""
    out: dict[str, bytes] = {}
    out.update({f"{root}c/{k}": v.encode() for k, v in _c_files(model, robot).items()})
    out.update({f"{root}python/{k}": v.encode() for k, v in _python_files(model, robot).items()})
    for module, specs, _ in _modules(model):
        # (the CasADi files name the model's source for all three modules)
        for k, data in casadi_backend.render(specs, module, source=model_source(model)).items():
            out[f"{root}casadi/{k}"] = data
    out[f"{root}__init__.py"] = b'"""Generated code (python -m codegen). DO NOT EDIT."""\n'
    if report:
        renderer = importlib.import_module(model.docs.get("report", "codegen.robot_report"))
        out[f"{root}MODEL.md"] = renderer.render(model, robot, op_counts(model)).encode()
    return out


def default_c_config() -> CConfig:
    """The default robot's C config (``wmr_`` names), for tools built around it."""
    from modeling.robot_file import load_robot_model

    return c_config(load_robot_model(None)[0])
