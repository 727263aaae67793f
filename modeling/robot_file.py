"""Any robot file: its kind, and its model and numbers. Robot kinds are one table, :data:`KINDS`:

=========  ===============  ==========================================  ==================
kind       marked by        read and modelled by                        declares
=========  ===============  ==========================================  ==================
bodies     ``[[body]]``     ``modeling.description`` (audited before    ``PAPER_MODEL =
                            the derivation), then the derived model     False``, its LAYOUT
                            ``modeling.robot_model.described_model``
physical   ``[physical]``   ``modeling.robots.drishti.robot_file``      ``PAPER_MODEL =
                            (lumped relations: SymPy), the paper's      True``
                            model ``modeling.robots.drishti.model``
lumped     ``[lumped]``     the same reader, without SymPy; the         ``PAPER_MODEL =
                            paper's model                               True``
=========  ===============  ==========================================  ==================

Every kind declares ``KIND`` and ``PAPER_ROBOT`` too, in the generated ``robot.py``.
Whatever its kind, a robot file is named by itself: its ``name`` (else its stem), and its
prefix and output folder ``c_identifier(name)``, except the shipped robots of
``modeling.robot_io.SHIPPED_NAMING`` (Drishti's own file: prefix ``wmr``, the root of
``generated/``, the paper's robot). A copy of Drishti's file called ``mybot`` is the
paper's model with its own numbers, prefix ``mybot_`` and folder ``mybot/``.

A file is read and parsed once (``modeling.robot_io.read_robot_file``, a
:class:`RobotSource`); every reader here takes that. This dispatcher sits above both
formats and above ``modeling.robot_io``, whose names it re-exports: ``from
modeling.robot_file import load_robot, RobotFileError`` is the one import a caller needs.
Reading a ``[lumped]`` file imports no SymPy; the models are imported where they are built.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING

from modeling.robot_io import (
    DEFAULT_ROBOT,
    ROBOTS_DIR,
    Naming,
    Robot,
    RobotFileError,
    RobotSource,
    describes_bodies,
    is_description,
    read_robot_file,
    read_robot_text,
    shipped_robot_file,
    shipped_robot_files,
    source_label,
    text_digest,
)
from modeling.robots.drishti.parameters import tables_of
from modeling.robots.drishti.robot_file import parse_robot, robot_of

if TYPE_CHECKING:
    from modeling.robot_model import RobotModel

__all__ = [
    "DEFAULT_ROBOT",
    "KINDS",
    "ROBOTS_DIR",
    "Robot",
    "RobotFileError",
    "RobotKind",
    "RobotSource",
    "describes_bodies",
    "is_description",
    "kind_named",
    "kind_of",
    "load_robot",
    "load_robot_model",
    "model_of",
    "parse_robot",
    "read_robot_file",
    "read_robot_text",
    "robot_source",
    "shipped_robot_file",
    "shipped_robot_files",
    "source_label",
    "text_digest",
]


@dataclass(frozen=True)
class RobotKind:
    """One kind of robot file (a row of :data:`KINDS`): the top-level TOML key that marks
    it, how its numbers are read without a model (``robot``; None: they are its derived
    model's), how its model is built (``model``), and what its generated ``robot.py``
    declares (``paper_model``: the paper's differential drive, lumped parameters m, I, K,
    Iw, r, b, d at run time and an engine layout that follows from them)."""

    name: str
    marker: str
    robot: Callable[[RobotSource], Robot] | None
    model: Callable[[RobotSource], tuple[RobotModel, Robot]]
    paper_model: bool


def _paper_robot(source: RobotSource) -> Robot:
    """A ``[lumped]``/``[physical]`` file's numbers (checked and audited)."""
    return robot_of(tables_of(source.data, source.where), source.text, source.where)


@cache
def _paper_model(name: str, naming: Naming) -> RobotModel:
    """The paper's model named ``name`` with ``naming`` (the same object for Drishti's own
    naming: every derivation cached on the model is shared)."""
    from modeling.robots.drishti import model as wmr

    model = wmr.robot_model()
    if (name, naming.prefix, naming.output_dir, naming.paper_robot) == (
            model.name, model.prefix, model.output_dir, model.paper_robot):
        return model
    return replace(model, name=name, prefix=naming.prefix, output_dir=naming.output_dir,
                   paper_robot=naming.paper_robot)


def _paper(source: RobotSource) -> tuple[RobotModel, Robot]:
    robot = _paper_robot(source)
    return _paper_model(robot.name, source.naming), robot


def _described(source: RobotSource) -> tuple[RobotModel, Robot]:
    """A ``[[body]]`` file: read and audited before the (slow) derivation, then derived."""
    from modeling import robot_model
    from modeling.description.files import description_of

    audited = description_of(source.data, source.where)
    label = source_label(source.path) if source.path is not None else source.where
    model = robot_model.described_model(audited, label, source.naming)
    return model, Robot(model.name, model.param_values(), source=model.source,
                        digest=source.digest, warnings=audited.warnings, kind="bodies",
                        supports=audited.supports)


# Robot kinds, looked up by marker in this order: a file with both [lumped] and [physical]
# goes to the physical row, whose reader says to give exactly one; a file with none of the
# markers to the lumped row, whose reader names what is missing.
KINDS: tuple[RobotKind, ...] = (
    RobotKind("bodies", "body", None, _described, paper_model=False),
    RobotKind("physical", "physical", _paper_robot, _paper, paper_model=True),
    RobotKind("lumped", "lumped", _paper_robot, _paper, paper_model=True),
)


def kind_of(source: RobotSource) -> RobotKind:
    """The kind of a robot file read (see :data:`KINDS`)."""
    return next((k for k in KINDS if k.marker in source.data), KINDS[-1])


def kind_named(name: str) -> RobotKind:
    """The row of :data:`KINDS` called ``name``; ``KeyError`` otherwise."""
    for kind in KINDS:
        if kind.name == name:
            return kind
    raise KeyError(name)


def robot_source(path: str | Path | RobotSource | None) -> RobotSource:
    """A robot file read once (a :class:`RobotSource` as it is); Drishti's own file, by
    any path, is named as in the package (its generated preambles do not depend on the
    path given)."""
    if isinstance(path, RobotSource):
        return path
    if path is not None and Path(path).resolve() == shipped_robot_file(DEFAULT_ROBOT):
        path = None  # the packaged default: its source reads modeling/robots/drishti/...
    return read_robot_file(path)


def load_robot(path: str | Path | RobotSource | None = None) -> Robot:
    """The numbers of a ``[lumped]``/``[physical]`` robot file (``None``: Drishti's own; a
    :class:`RobotSource` already read is not read again). ``RobotFileError`` names the file
    and the field; a ``[[body]]`` file's numbers are its derived model's
    (:func:`load_robot_model`)."""
    source = read_robot_file(path) if not isinstance(path, RobotSource) else path
    kind = kind_of(source)
    if kind.robot is None:
        raise RobotFileError(f"{source.where}: a [[{kind.marker}]] robot file: its "
                             "parameters are its derived model's (load_robot_model)")
    return kind.robot(source)


def model_of(source: RobotSource) -> tuple[RobotModel, Robot]:
    """The model of a robot file read and its parameter values (see
    :func:`load_robot_model`)."""
    return kind_of(source).model(source)


def load_robot_model(path: str | Path | RobotSource | None = None
                     ) -> tuple[RobotModel, Robot]:
    """The generic model of a robot file and its parameter values, by its kind
    (:data:`KINDS`).

    A file with ``[[body]]`` tables is derived by ``modeling.description`` (run-time
    parameters: base inertial parameters and wheel radii); a ``[lumped]``/``[physical]``
    file is the paper's differential drive with those numbers. ``Robot.lumped`` holds the
    values of the model's ``params``; ``Robot.warnings`` the physics audit's findings. Raises
    ``RobotFileError`` naming the problem; the audit (``modeling.audit``) refuses an
    implausible file before any derivation. The file is read once.
    """
    return model_of(robot_source(path))
