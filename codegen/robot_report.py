"""The model report (``MODEL.md``) of a robot described as bodies, joints and wheels.

What the toolchain derived and generated for it: coordinates, the wheel constraints kept
and dropped, the run-time (base) parameters with their physical meaning and defaults, the
formulations generated, the dependence of M̄ on q, and the operation counts. There is no
printed paper to compare with (the paper's robot has its own report,
``modeling.robots.drishti.report``, which its ``RobotModel.docs["report"]`` names).
Deterministic: no timestamps, no absolute paths.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import sympy as sp

from codegen import template_util
from codegen.robot_functions import staged_forms
from modeling.robot_file import Robot
from modeling.robot_model import RobotModel
from modeling.staged import CLOSED_FORM_MAX

TEMPLATE_DIR = Path(__file__).resolve().parent / "templates"
TEMPLATE = "robot_report.md.jinja"


def _cell(text: str) -> str:
    return " ".join(str(text).split()).replace("|", "\\|")


def render(model: RobotModel, robot: Robot, op_counts: dict[str, str]) -> str:
    """MODEL.md for ``model`` with the robot file's parameter values."""
    values = robot.lumped
    s = model.system
    labels = s.constraint_labels
    dropped = s.dropped_constraints
    if model.staged:  # the closed form is what a staged robot never builds
        mbar = staged_forms(model)
        mbar_q = sorted(str(v) for v in model.q if mbar.depends_on(mbar.mbar, (v,)))
    else:
        mbar_q = sorted(str(v) for v in s.minimal_mass_matrix.free_symbols & set(model.q))
    context: dict[str, Any] = {
        "preamble": list(template_util.preamble_lines(model.source, TEMPLATE_DIR, TEMPLATE)),
        "robot_name": model.name,
        "prefix": model.prefix,
        "nq": model.nq,
        "nu": model.nu,
        "coordinates": [
            {"index": i, "name": n, "role": "driven wheel" if i in model.actuated else ""}
            for i, n in enumerate(model.coordinate_names)
        ],
        "inputs": list(model.input_names),
        "constraints": [_cell(x) for x in labels],
        "dropped": [_cell(x) for x in dropped],
        "parameters": [
            {"key": p.key, "value": repr(values[p.key]), "doc": _cell(p.comment)}
            for p in model.params
        ],
        "formulations": list(model.formulations),
        "staged": model.staged,
        "closed_form_max": CLOSED_FORM_MAX,
        "mbar_depends_on": mbar_q,
        "kinetic_energy": sp.latex(s.kinetic_energy),
        "op_counts": [{"function": k, "count": _cell(v)} for k, v in op_counts.items()],
        "warnings": [" ".join(w.split()) for w in robot.warnings],
    }
    return template_util.render(TEMPLATE_DIR, TEMPLATE, **context)
