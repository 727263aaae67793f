"""Robots from URDF (ROS) and MJCF (MuJoCo) files: ``wmr import``.

A file is read into a neutral 3D mechanism (``urdf``, ``mjcf``: standard library XML, no
ROS or MuJoCo needed), checked for non-physical and placeholder inertias (``checks``),
turned into a planar bodies-and-wheels robot with a provenance note per value (``planar``:
fixed joints merged, 3D inertias composed and projected, wheels, casters and hitches
recognised), written as a robot file (``writer``), and read back through
``modeling.description.parse_description``, which runs the physics audit of
``modeling.audit`` on it: what ``wmr import`` writes is exactly what ``wmr model`` will
accept (``command``: the command line, which writes nothing on refusal).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from modeling.description import RobotDescription, parse_description
from modeling.importers.mechanism import ImportFileError, Mechanism
from modeling.importers.planar import Options, PlanarRobot, build
from modeling.importers.writer import robot_file_text
from modeling.robot_io import RobotFileError, read_robot_text

__all__ = ["ImportFileError", "Imported", "Options", "import_robot", "read_mechanism"]


@dataclass(frozen=True)
class Imported:
    """An import: the planar robot, the robot file's text and its description as the
    toolchain reads it (with the audit's warnings)."""

    robot: PlanarRobot
    text: str
    description: RobotDescription


def read_mechanism(path: Path) -> Mechanism:
    """The mechanism of a URDF or MJCF file (by its root element); xacro refused."""
    from modeling.importers.mjcf import read_mjcf
    from modeling.importers.urdf import read_urdf, xacro_refusal

    text = read_robot_text(path)
    refusal = xacro_refusal(path, text)
    if refusal:
        raise ImportFileError(refusal)
    first = re.search(r"<(robot|mujoco)[\s>/]", text)
    if first and first.group(1) == "mujoco":
        return read_mjcf(path, text)
    if first:
        return read_urdf(path, text)
    raise ImportFileError(f"{path}: neither URDF (<robot>) nor MJCF (<mujoco>): cannot "
                          "import it")


def import_robot(path: Path, options: Options | None = None, where: str = "") -> Imported:
    """Import ``path`` (see the module docstring); ``where`` names the output in the
    audit's messages. Raises ``RobotFileError`` (one line) on anything it refuses."""
    robot = build(read_mechanism(Path(path)), options)
    text = robot_file_text(robot)
    where = where or f"{Path(path).stem}.toml"
    try:
        description = parse_description(text, where)
    except RobotFileError as exc:
        # The audit names the robot file's fields (body[0], wheel[1]: the imported bodies
        # and wheels, named after their links); the file to fix is the imported one.
        message = str(exc).removeprefix(f"{where}: ")
        raise ImportFileError(f"{path}: {message}") from None
    return Imported(robot, text, description)
