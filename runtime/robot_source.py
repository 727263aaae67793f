"""From a robot file to the generated code and numbers a simulation of it needs.

* A ``[lumped]``/``[physical]`` file is the paper's differential drive with other numbers:
  the default generated code (``wmr_``) with the file's parameters.
* A ``[[body]]``/``[[wheel]]`` file has code of its own: the generated folder whose
  ``robot.py`` names the robot (``generated/<name>/`` after ``python -m codegen --robot
  FILE``, or under ``--generated DIR``), refused when it was generated from another version
  of the file (``SOURCE_SHA256``) — its parameters are then the file's.

No SymPy for described robots: their numbers are read from the generated ``robot.py``.
(Physical parameters of a ``[physical]`` file go through the lumped relations:
``modeling.robot_file.load_robot``, which imports SymPy for that file only.)
"""

from __future__ import annotations

import ast
import tomllib
from dataclasses import dataclass
from pathlib import Path

from modeling.robot_file import load_robot
from modeling.robot_io import RobotFileError, describes_bodies, read_robot_text, text_digest
from runtime.generated_modules import GENERATED, RobotCode, load_robot_code


class RobotSourceError(ValueError):
    """A robot file that cannot be simulated; the message says why and what to run."""


@dataclass(frozen=True)
class RobotSetup:
    """A robot to simulate: its generated code, the controllers' nominal parameters and the
    simulated robot's (before any payload)."""

    name: str
    source: str
    code: RobotCode
    nominal: dict[str, float]
    plant: dict[str, float]


def _read(path: Path) -> tuple[str, dict[str, object]]:
    try:
        text = read_robot_text(path)
    except RobotFileError as exc:
        raise RobotSourceError(str(exc)) from None
    try:
        return text, tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise RobotSourceError(f"{path}: not valid TOML: {exc}") from None


def generated_robots(root: Path) -> list[Path]:
    """Folders under ``root`` (itself included) that hold a generated robot."""
    found = [root] if (root / "python" / "robot.py").is_file() else []
    if root.is_dir():
        found += sorted(p.parent.parent for p in root.glob("*/python/robot.py"))
    return found


def code_in(folder: Path) -> RobotCode:
    """The generated code in a robot folder (``python/``, ``c/``, ``casadi/`` inside):
    ``generated/`` itself is the default robot, ``generated/<name>/`` a shipped one, any
    other folder is imported as a package of its own. ``FileNotFoundError`` if none."""
    folder = folder.resolve()
    if not (folder / "python" / "robot.py").is_file():
        raise FileNotFoundError(f"{folder}: no generated robot here (python/robot.py missing)")
    if folder == GENERATED.resolve():
        return load_robot_code("")
    if folder.parent == GENERATED.resolve():
        return load_robot_code(folder.name)
    return load_robot_code(folder)


def generated_folder(name_or_dir: str) -> Path:
    """``--robot`` of a command that reads generated code: a folder, or the name of a robot
    generated under ``generated/`` (its ``robot.py`` NAME, or its folder's name).
    ``RobotSourceError`` naming the robots found otherwise."""
    path = Path(name_or_dir)
    if path.is_dir():
        return path
    names: dict[str, Path] = {}
    for folder in generated_robots(GENERATED):
        names.setdefault(folder.name, folder)
        names[code_in(folder).name] = folder
    if name_or_dir in names:
        return names[name_or_dir]
    raise RobotSourceError(
        f"--robot {name_or_dir!r}: not a folder and not a generated robot "
        f"(found: {', '.join(sorted(n for n in names if n != GENERATED.name))})"
    )


def resolve(path: Path, generated: Path | None = None) -> RobotSetup:
    """The setup of robot file ``path``; ``generated`` is the folder to look for its code in
    (default: the repository's ``generated/``)."""
    text, data = _read(path)
    if describes_bodies(data):
        return _described(path, text, data, generated or GENERATED)
    return _lumped(path, generated)


def _described(path: Path, text: str, data: dict[str, object], root: Path) -> RobotSetup:
    name = data.get("name")
    if not isinstance(name, str) or not name:
        raise RobotSourceError(f"{path}: field 'name' must be a non-empty string")
    matches = [d for d in generated_robots(root)
               if _robot_name(d / "python" / "robot.py") == name]
    hint = (f"run `python -m codegen --robot {path}` (writes generated/<name>/) or "
            f"`python -m codegen --robot {path} --out DIR` and pass --generated DIR")
    if not matches:
        raise RobotSourceError(f"{path}: no generated code for robot '{name}' under {root}; "
                               f"{hint}")
    code = load_robot_code(matches[0].resolve())
    recorded = getattr(code.robot, "SOURCE_SHA256", None)
    if recorded != text_digest(text):
        raise RobotSourceError(
            f"{path}: {matches[0]} was generated from "
            f"{'another version of this file' if recorded else 'an unrecorded source'} "
            f"(robot.py SOURCE_SHA256); regenerate: {hint}"
        )
    return RobotSetup(name, str(path), code, code.params, code.plant_defaults)


def _robot_name(robot_py: Path) -> str | None:
    """``NAME`` of a generated ``robot.py``, read without importing it."""
    for line in robot_py.read_text(encoding="utf-8").splitlines():
        if line.startswith("NAME = "):
            value = ast.literal_eval(line.split("=", 1)[1].strip())
            return value if isinstance(value, str) else None
    return None


def _lumped(path: Path, generated: Path | None) -> RobotSetup:
    try:
        robot = load_robot(path)
    except RobotFileError as exc:
        raise RobotSourceError(str(exc)) from None
    code = load_robot_code(generated.resolve() if generated else "")
    if code.prefix != "wmr" or set(code.params) != set(robot.lumped):
        raise RobotSourceError(
            f"{path}: a lumped robot file runs on the paper robot's generated code (wmr_, "
            f"parameters {', '.join(robot.lumped)}), but {code.folder} holds robot "
            f"'{code.name}' ({code.prefix}_); regenerate it with `make model`"
        )
    values = robot.plant_values()
    plant = {k: float(values.get(k, 0.0)) for k in code.plant_defaults}
    return RobotSetup(robot.name, str(path), code, dict(robot.lumped), plant)
