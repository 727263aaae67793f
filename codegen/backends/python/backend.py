"""The NumPy-only Python backend as the driver sees it: every Python file of a robot.

``python/``: one ``<module>.py`` per module, ``controllers.py`` (the controllers' step
functions, from the layout), ``robot.py`` (the robot file's numbers, sizes and names) and
``__init__.py``.
"""

from __future__ import annotations

import json
from typing import Any

from codegen import template_util
from codegen.backend import RobotTarget
from codegen.backends.python.config import PythonConfig
from codegen.backends.python.printer import PyPrinter
from codegen.backends.python.render import TEMPLATE_DIR, render_module
from codegen.certify.runtime_check import gate_context
from codegen.contact_forces import contact_rows
from codegen.controller_api import (
    MAX_ABS_INPUT,
    law_signature,
    nominal_range,
    python_context,
    status_codes,
)
from codegen.robot_functions import MAX_WINDOW
from codegen.template_util import generated_by
from modeling.controllers import BASE_CHECKS, ControllerSpec
from modeling.robot_file import kind_named
from modeling.version import VERSION


def robot_py(target: RobotTarget) -> str:
    """``robot.py``: the robot file's default parameters, the plant's, sizes and names."""
    model, robot = target.model, target.robot
    rows = contact_rows(model)
    params = ", ".join(f'"{p.key}": {robot.lumped[p.key]!r}' for p in model.params)
    name = json.dumps(robot.name)  # a quote in a name cannot end the string
    supports = (None if robot.supports is None
                else [s.to_data() for s in robot.supports])
    text = (
        f'"""Default parameters of robot {name} (from {robot.source}).\n\n'
        f'{generated_by()} DO NOT EDIT.\n"""\n\n'
        "from typing import Any\n\n"
        f"NAME = {name}\n"
        f'TOOLCHAIN_VERSION = "{VERSION}"  # the wmr-toolchain that generated this code\n'
        f'SOURCE_SHA256 = "{robot.digest}"  # of the robot file\'s text\n'
        f"PARAMS: dict[str, float] = {{{params}}}\n"
    )
    plant = ", ".join(f'"{k}": {v!r}' for k, v in target.plant_values().items())
    names = ", ".join(f'"{n}"' for n in model.coordinate_names)
    inputs = ", ".join(f'"{n}"' for n in model.input_names)
    return text + (
        f'PLANT_PARAMS: dict[str, float] = {{{plant}}}\n'
        f'PREFIX = "{model.prefix}"\n'
        "# What the robot is (modeling.robot_file.KINDS), declared for the runtime, which reads\n"
        "# these and never the prefix: its robot file's kind; whether it is the paper's\n"
        "# differential drive (parameters m, I, K, Iw, r, b, d, the layout following from\n"
        "# them); whether it is the paper's own robot (modeling.robot_io.SHIPPED_NAMING).\n"
        f'KIND = "{robot.kind}"\n'
        f"PAPER_MODEL = {kind_named(robot.kind).paper_model}\n"
        f"PAPER_ROBOT = {model.paper_robot}\n"
        f"NQ = {model.nq}  # generalised coordinates\n"
        f"NU = {model.nu}  # inputs (driven wheels)\n"
        f"ACTUATED = {model.actuated!r}  # index in q of each input's wheel angle\n"
        f"COORDINATES = ({names},)\n"
        f"INPUTS = ({inputs},)\n"
        f"FORMULATIONS = {tuple(model.formulations)!r}\n"
        "# The robot's bodies, hitches and wheels in numbers (modeling.planar_robot), for an\n"
        "# engine's model of it (runtime.mujoco); None: a [lumped]/[physical] robot, whose\n"
        "# layout follows from its parameters.\n"
        f"LAYOUT: dict[str, Any] | None = {model.layout!r}\n"
        "# Its supports as the robot file states them ([[support]], modeling.supports: name,\n"
        "# body, position in the body frame, radius); None: not stated, the default rule.\n"
        f"SUPPORTS: list[Any] | None = {supports!r}\n"
        "# The wheels of <prefix>_wheel_contact_forces' outputs (codegen.contact_forces):\n"
        "# the driven wheels of 'longitudinal', the wheels of each row of 'lateral'.\n"
        f"DRIVEN_WHEELS = {rows.driven!r}\n"
        f"LATERAL_WHEELS = {rows.lateral_wheels!r}\n"
        + physical_py(model)
        + audit_py(robot.warnings)
        + controllers_py(target.controllers)
    )


def physical_py(model: Any) -> str:
    """``PHYSICAL`` and ``PHYSICAL_TERMS`` of robot.py: the inputs of
    ``plant_params_from_physical`` (key -> (nominal, unit, what), in input order) and each
    output's polynomial as (coefficient, ((input index, power), ...)) terms
    (``modeling.physical_map``), for the runtime's interval enclosures of its range; None
    for a [lumped]/[physical] robot."""
    pm = model.physical
    head = ("# The physical quantities of plant_params_from_physical (modeling.physical_map):\n"
            "# key -> (nominal, unit, what), in input order; each output's polynomial terms\n"
            "# (coefficient, ((input index, power), ...)). None: a [lumped]/[physical] robot.\n")
    if pm is None:
        return head + ("PHYSICAL: dict[str, tuple[float, str, str]] | None = None\n"
                       "PHYSICAL_TERMS: dict[str, Any] | None = None\n")
    inputs = ", ".join(f"{q.key!r}: ({q.nominal!r}, {q.unit!r}, {q.doc!r})" for q in pm.inputs)
    terms = ",\n".join(f"    {k!r}: {v!r}" for k, v in pm.terms().items())
    return head + (f"PHYSICAL: dict[str, tuple[float, str, str]] | None = {{{inputs}}}\n"
                   f"PHYSICAL_TERMS: dict[str, Any] | None = {{\n{terms},\n}}\n")


def audit_py(warnings: tuple[str, ...]) -> str:
    """``AUDIT_WARNINGS`` of robot.py: the physics audit's warnings on the robot file
    (``modeling.audit``; MODEL.md lists them too), one line each, so that every command
    that runs the robot prints them and its reports carry them without re-reading or
    re-auditing the file."""
    lines = ["# The physics audit's warnings on the robot file (modeling.audit), as MODEL.md",
             "# lists them: every command that runs this robot prints them.",
             "AUDIT_WARNINGS: tuple[str, ...] = ("]
    lines += [f"    {' '.join(w.split())!r}," for w in warnings]
    return "\n".join([*lines, ")", ""])


def controllers_py(controllers: tuple[ControllerSpec, ...]) -> str:
    """``CONTROLLERS`` of robot.py: the controllers generated (the registry,
    ``modeling.controllers.REGISTRY``) as data, so that the runtime iterates them without
    importing SymPy or retyping them: name, label, title, equations, the step features
    derived from each declaration and configuration fields (name, kind, unit, where the
    runtime takes the value)."""
    lines = ["# The controllers generated for this robot (modeling.controllers.REGISTRY): name,",
             "# labels, step features, configuration fields (name, kind, unit, value source).",
             "CONTROLLERS: tuple[dict[str, Any], ...] = ("]
    for c in controllers:
        fields = ", ".join(f"({f.name!r}, {f.kind!r}, {f.unit!r}, {f.source!r})"
                           for f in c.fields)
        lines += [
            "    {",
            f"        \"name\": {c.name!r}, \"label\": {c.label!r}, \"title\": {c.title!r},",
            f"        \"equations\": {c.equations!r}, \"tde\": {c.tde}, "
            f"\"switching\": {c.switching},",
            f"        \"window\": {c.window}, \"bounds\": {c.bounds}, "
            f"\"adaptive\": {c.adaptive},",
            f"        \"error_dynamics\": {c.error_dynamics}, \"integrator\": {c.integrator}, "
            f"\"formulations\": {c.formulations!r},",
            f"        \"fields\": ({fields},),",
            "    },",
        ]
    return "\n".join([*lines, ")", ""])


def nominal_conditions(target: RobotTarget) -> list[tuple[str, str]]:
    """The robot's conditions on nominal parameters as (Python expression over
    ``values[key]``, doc)."""
    names = {p.symbol: f'values["{p.key}"]' for p in target.model.params}
    printer = PyPrinter(PythonConfig(), names)
    return [(printer.expr_code(c.expr), repr(c.doc)) for c in target.model.nominal_conditions]


class PythonBackend:
    """Plain functions over Python floats (``math``), NumPy arrays in and out."""

    name = "python"
    folder = "python"

    def render(self, target: RobotTarget) -> dict[str, str]:
        layout = target.layout
        files: dict[str, str] = {}
        for module in target.modules:
            files.update(render_module(module.functions, module.name, source=module.source))
        template = "controllers.py.jinja"
        files["controllers.py"] = template_util.render(
            TEMPLATE_DIR,
            template,
            preamble=template_util.preamble_lines(target.law_source, TEMPLATE_DIR, template),
            layout=layout,
            status_codes=status_codes(layout),
            controllers=target.controllers,
            gates={c.name: gate_context(c, layout.prefix) for c in target.controllers},
            law_signatures={c.name: law_signature(c, target.model)
                            for c in target.controllers},
            base_checks=BASE_CHECKS,
            formulation_paper=0,
            formulation_minimal=1,
            max_window=MAX_WINDOW,
            max_abs_input=MAX_ABS_INPUT,
            # the controllers accept C structs (cffi) as parameters: C's field spellings
            c_field_names=target.model.c_field_names(),
            param_keys=[p.key for p in target.model.params],
            nominal_conditions=nominal_conditions(target),
            nominal_ranges={p.key: nominal_range(target.robot.lumped[p.key],
                                                 p.key in target.model.positive)
                            for p in target.model.params},
            **python_context(target.controllers),
        )
        files["robot.py"] = robot_py(target)
        files["__init__.py"] = (
            f'"""NumPy-only model and controllers. {generated_by()} DO NOT EDIT."""\n'
        )
        return files


BACKEND = PythonBackend()
