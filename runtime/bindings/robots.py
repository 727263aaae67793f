"""``--robot`` of every command: what it names, resolved to generated code and parameters.

It may name

* a robot file: ``[lumped]``/``[physical]`` (the paper's differential drive with other
  numbers: generated code that declares the paper's model, ``PAPER_MODEL``, with the
  file's parameters: the default robot's, or with ``--generated DIR`` the folder DIR or
  DIR/<name>/ that ``wmr model --robot FILE --out DIR`` wrote) or
  ``[[body]]``/``[[wheel]]`` (code of its own: the generated folder whose ``robot.py``
  names the robot, refused when it was generated from another version of the file,
  ``SOURCE_SHA256``; its parameters are then the file's);
* a generated folder (``python/``, ``c/``, ``casadi/`` inside, as ``wmr model --out DIR``
  writes it): that code with the parameters it was generated with;
* the name of a robot generated under ``generated/`` (its ``robot.py`` NAME, or its
  folder's name).

``--generated DIR`` says where a robot file's code is (default: the repository's
``generated/``, searched for the robot's name). No SymPy for generated code and
bodies-and-wheels files: their numbers come from the generated ``robot.py``. (Physical
parameters of a ``[physical]`` file go through the lumped relations:
``modeling.robot_file.load_robot``, which imports SymPy for that file only.)
"""

from __future__ import annotations

import ast
import tomllib
from dataclasses import dataclass
from pathlib import Path

from modeling.robot_file import load_robot
from modeling.robot_io import (
    RobotFileError,
    RobotSource,
    describes_bodies,
    read_robot_text,
    text_digest,
)
from runtime.bindings.generated import GENERATED, RobotCode, load_robot_code


class RobotSourceError(ValueError):
    """A robot that cannot be run; the message says why and what to run."""


@dataclass(frozen=True)
class RobotSetup:
    """A robot to run: its generated code, the controllers' nominal parameters and the
    simulated robot's (before any payload); ``source`` is what ``--robot`` named, ``sha256``
    the robot file's text digest (for generated code: the one it was generated from),
    ``warnings`` the physics audit's on the robot file (``modeling.audit``: a lumped file's
    own, else those its generated ``robot.py`` declares)."""

    name: str
    source: str
    code: RobotCode
    nominal: dict[str, float]
    plant: dict[str, float]
    sha256: str | None = None
    warnings: tuple[str, ...] = ()


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


def generated_folder(name_or_dir: str, root: Path = GENERATED) -> Path:
    """A generated folder, or the folder of the robot generated under ``root`` with that
    name (its ``robot.py`` NAME, or its folder's name). ``RobotSourceError`` naming the
    robots found otherwise."""
    path = Path(name_or_dir)
    if _holds_robot(path):
        return path
    names: dict[str, Path] = {}
    for folder in generated_robots(root):
        names.setdefault(folder.name, folder)
        name = _robot_name(folder / "python" / "robot.py")
        if name is not None:
            names[name] = folder
    if name_or_dir in names:
        return names[name_or_dir]
    if path.is_dir():
        return path  # a folder without a robot: _folder says so
    raise RobotSourceError(
        f"--robot {name_or_dir!r}: not a robot file, not a folder and not a generated robot "
        f"(found: {', '.join(sorted(n for n in names if n != root.name))})"
    )


def resolve(robot: str | Path | None = None, generated: Path | None = None) -> RobotSetup:
    """The robot ``--robot`` names (see the module docstring; None: the default robot, the
    paper's Drishti, or the one in ``generated``), with its code looked for under
    ``generated`` (default: the repository's ``generated/``)."""
    root = GENERATED if generated is None else generated
    if generated is not None and not generated.is_dir():
        raise RobotSourceError(f"--generated {generated}: not a folder")
    if robot is None:
        return _folder(root if generated is not None else GENERATED, "--generated")
    path = Path(robot)
    if _holds_robot(path):
        return _folder(path, "--robot")
    if path.is_file() or path.suffix == ".toml":
        text, data = _read(path)
        if describes_bodies(data):
            return _described(path, text, data, root)
        return _lumped(RobotSource(path, str(path), text, data), generated)
    return _folder(generated_folder(str(robot), root), "--robot")


def _holds_robot(path: Path) -> bool:
    """A generated folder (``python/robot.py`` inside)."""
    return (path / "python" / "robot.py").is_file()


def _folder(folder: Path, option: str) -> RobotSetup:
    try:
        code = code_in(folder)
    except FileNotFoundError:
        raise RobotSourceError(f"{option} {folder}: no generated robot there (python/robot.py "
                               "missing); `wmr model --robot FILE --out DIR` writes one"
                               ) from None
    return RobotSetup(code.name, str(folder), code, code.params, code.plant_defaults,
                      getattr(code.robot, "SOURCE_SHA256", None), code.audit_warnings)


def _described(path: Path, text: str, data: dict[str, object], root: Path) -> RobotSetup:
    name = data.get("name")
    if not isinstance(name, str) or not name:
        raise RobotSourceError(f"{path}: field 'name' must be a non-empty string")
    matches = [d for d in generated_robots(root)
               if _robot_name(d / "python" / "robot.py") == name]
    hint = (f"run `wmr model --robot {path}` (writes generated/<name>/ in a source checkout) "
            f"or `wmr model --robot {path} --out DIR` and pass --generated DIR (or --robot "
            "DIR)")
    if not matches:
        raise RobotSourceError(f"{path}: no generated code for robot '{name}' under {root}; "
                               f"{hint}")
    code = load_robot_code(matches[0].resolve())
    recorded = getattr(code.robot, "SOURCE_SHA256", None)
    digest = text_digest(text)
    if recorded != digest:
        raise RobotSourceError(
            f"{path}: {matches[0]} was generated from "
            f"{'another version of this file' if recorded else 'an unrecorded source'} "
            f"(robot.py SOURCE_SHA256); regenerate: {hint}"
        )
    return RobotSetup(name, str(path), code, code.params, code.plant_defaults, digest,
                      code.audit_warnings)


def _robot_name(robot_py: Path) -> str | None:
    """``NAME`` of a generated ``robot.py``, read without importing it."""
    for line in robot_py.read_text(encoding="utf-8").splitlines():
        if line.startswith("NAME = "):
            value = ast.literal_eval(line.split("=", 1)[1].strip())
            return value if isinstance(value, str) else None
    return None


def _lumped(source: RobotSource, generated: Path | None) -> RobotSetup:
    path = source.path  # read once, by resolve: not read again here
    try:
        robot = load_robot(source)
    except RobotFileError as exc:
        raise RobotSourceError(str(exc)) from None
    if generated is not None and not _holds_robot(generated):
        # the folder `wmr model --robot FILE --out DIR` wrote this robot in: DIR/<name>/
        generated = next((d for d in generated_robots(generated)
                          if _robot_name(d / "python" / "robot.py") == robot.name), generated)
    try:
        code = code_in(generated) if generated is not None else load_robot_code("")
    except FileNotFoundError:
        raise RobotSourceError(f"--generated {generated}: no generated robot there "
                               "(python/robot.py missing)") from None
    if not code.paper_model or set(code.params) != set(robot.lumped):
        raise RobotSourceError(
            f"{path}: a lumped robot file runs on generated code of the paper's model "
            f"(parameters {', '.join(robot.lumped)}), but {code.folder} holds robot "
            f"'{code.name}' ({code.prefix}_); regenerate it with `wmr model`"
        )
    values = robot.plant_values()
    plant = {k: float(values.get(k, 0.0)) for k in code.plant_defaults}
    return RobotSetup(robot.name, str(path), code, dict(robot.lumped), plant,
                      source.digest, robot.warnings)
