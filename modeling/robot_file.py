"""Any robot file: which format it is, and its model and numbers.

Two formats, each with its own reader:

* ``[[body]]``/``[[joint]]``/``[[wheel]]`` tables describe any wheeled robot
  (``modeling.description``); its model is derived (``modeling.robot_model.described_model``);
* a ``[lumped]`` or ``[physical]`` table is the paper's robot, Drishti, with other numbers
  (``modeling.robots.drishti.robot_file``, the format in
  ``modeling.robots.drishti.parameters``).

This dispatcher sits above both and above ``modeling.robot_io`` (the error type, reading,
digests, the shipped robots), whose names it re-exports: ``from modeling.robot_file import
load_robot, RobotFileError`` is the one import a caller needs. Reading a ``[lumped]`` file
imports no SymPy; the models are imported inside :func:`load_robot_model`.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from modeling.robot_io import (
    DEFAULT_ROBOT,
    ROBOTS_DIR,
    Robot,
    RobotFileError,
    describes_bodies,
    is_description,
    read_robot_text,
    shipped_robot_file,
    shipped_robot_files,
    source_label,
    text_digest,
)
from modeling.robots.drishti.robot_file import load_robot, parse_robot

if TYPE_CHECKING:
    from modeling.robot_model import RobotModel

__all__ = [
    "DEFAULT_ROBOT",
    "ROBOTS_DIR",
    "Robot",
    "RobotFileError",
    "describes_bodies",
    "is_description",
    "load_robot",
    "load_robot_model",
    "parse_robot",
    "read_robot_text",
    "shipped_robot_file",
    "shipped_robot_files",
    "source_label",
    "text_digest",
]


def load_robot_model(path: str | Path | None = None) -> tuple[RobotModel, Robot]:
    """The generic model of a robot file and its parameter values.

    A file with ``[[body]]`` tables is derived by ``modeling.description`` (run-time
    parameters: base inertial parameters and wheel radii); a ``[lumped]``/``[physical]``
    file is the paper's differential drive with those numbers. ``Robot.lumped`` holds the
    values of the model's ``params``; ``Robot.warnings`` the physics audit's findings. Raises
    ``RobotFileError`` naming the problem; the audit (``modeling.audit``) refuses an
    implausible file before any derivation.
    """
    from modeling.description import load_description
    from modeling.robot_model import described_model

    if path is not None and Path(path).resolve() == shipped_robot_file(DEFAULT_ROBOT):
        path = None  # the packaged default: its source reads modeling/robots/drishti/...
    if path is not None and is_description(path):
        audited = load_description(path)  # read and audited before the (slow) derivation
        model = described_model(str(Path(path).resolve()), source_label(path))
        digest = text_digest(Path(path).read_text(encoding="utf-8"))
        return model, Robot(model.name, model.param_values(), source=model.source,
                            digest=digest, warnings=audited.warnings)
    from modeling.robots.drishti import model as wmr

    robot = load_robot(path)
    return wmr.robot_model(), robot
