"""Robots from URDF (ROS) and MJCF (MuJoCo) files: ``wmr import``.

A file is read as published: a xacro template is expanded first (``expand``: the ROS
``xacro`` package, no ROS install), then read into a neutral 3D mechanism (``urdf``,
``mjcf``: standard library XML, no ROS or MuJoCo needed), checked for non-physical and
placeholder inertias (``checks``), wheels whose collision is a mesh given the cylinder of
its bounds (``meshes``, when the mesh file is found and is STL or OBJ), turned into a
planar bodies-and-wheels robot with a provenance note per value (``planar``: fixed joints
merged, 3D inertias composed and projected, wheels, casters and hitches
recognised), written as a robot file (``writer``), and read back through
``modeling.description.parse_description``, which runs the physics audit of
``modeling.audit`` on it: what ``wmr import`` writes is exactly what ``wmr model`` will
accept (``command``: the command line, which writes nothing on refusal).
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from modeling.description import RobotDescription, parse_description
from modeling.importers.expand import expand, uses_xacro, without_comments
from modeling.importers.mechanism import ImportFileError, Mechanism
from modeling.importers.meshes import add_wheel_cylinders
from modeling.importers.mjcf import read_mjcf
from modeling.importers.planar import Options, PlanarRobot, build
from modeling.importers.urdf import read_urdf
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


def read_mechanism(path: Path, package_path: Sequence[Path] = (),
                   xacro_args: Mapping[str, str] | None = None) -> Mechanism:
    """The mechanism of a URDF (xacro expanded, see ``expand``) or MJCF file, by its root
    element; ``package_path``: folders holding the ROS packages ``$(find PKG)`` names;
    ``xacro_args``: values of the file's ``xacro:arg``s."""
    text = read_robot_text(path)
    skipped: list[str] = []
    if uses_xacro(path, text):
        text, skipped = expand(path, dict(xacro_args or {}), package_path)
    first = re.search(r"<(robot|mujoco)[\s>/]", without_comments(text))
    if first and first.group(1) == "mujoco":
        return read_mjcf(path, text)
    if first:
        mech = read_urdf(path, text)
        add_wheel_cylinders(mech, path, package_path)
        if skipped:
            mech.notes.append("xacro includes skipped, their packages found nowhere (give "
                              "--package-path to read them): " + ", ".join(skipped))
        return mech
    raise ImportFileError(f"{path}: neither URDF (<robot>) nor MJCF (<mujoco>): cannot "
                          "import it")


def import_robot(path: Path, options: Options | None = None, where: str = "",
                 package_path: Sequence[Path] = (),
                 xacro_args: Mapping[str, str] | None = None) -> Imported:
    """Import ``path`` (see the module docstring); ``where`` names the output in the
    audit's messages; ``package_path`` and ``xacro_args`` as for :func:`read_mechanism`.
    Raises ``RobotFileError`` (one line) on anything it refuses."""
    robot = build(read_mechanism(Path(path), package_path, xacro_args), options)
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
