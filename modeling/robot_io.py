"""Robot files as files: the error every reader raises, the text and its digest, which
format a file is, and where the shipped robots are. Standard library only.

This is the leaf every robot-file module imports: ``modeling.description`` (bodies, joints
and wheels), Drishti's ``[lumped]``/``[physical]`` schema
(``modeling.robots.drishti.robot_file``) and the dispatcher between them,
``modeling.robot_file``; the runtime reads robot files through it without SymPy.
"""

from __future__ import annotations

import hashlib
import re
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

from modeling.planar_robot import PlanarSupport

DEFAULT_ROBOT = "drishti"
ROBOTS_DIR = Path(__file__).resolve().parent / "robots"


class RobotFileError(ValueError):
    """A robot file that cannot describe a robot; the message names the field."""


@dataclass(frozen=True)
class Robot:
    """A robot's lumped parameters (keys m, I, K, Iw, r, b, d) and, when the file gave
    them, its physical parameters and the lateral first moment K_lat they imply.
    ``warnings``: the physics audit's findings on the file (``modeling.audit``), which the
    generated MODEL.md lists."""

    name: str
    lumped: dict[str, float]
    physical: dict[str, float] | None = None
    K_lat: float = 0.0
    source: str = "<built-in>"
    digest: str = ""  # text_digest of the file it was read from ("" if none)
    warnings: tuple[str, ...] = ()
    kind: str = "lumped"  # the robot file's kind (modeling.robot_file.KINDS)
    # its [[support]] (modeling.supports; None: not stated, the default)
    supports: tuple[PlanarSupport, ...] | None = None

    def plant_values(self) -> dict[str, float]:
        """The numbers the file gives the simulated robot: the lumped parameters and the
        lateral first moment its physical parameters imply (the plant-only K_lat)."""
        return {**self.lumped, "K_lat": self.K_lat}


@dataclass(frozen=True)
class Naming:
    """What a robot's generated code is called and where it goes, beside its name: the C
    and Python ``prefix`` (``<prefix>_model.c``), the ``output_dir`` relative to the output
    folder ("" = its root) and whether it is the paper's own robot (``paper_robot``,
    declared in the generated ``robot.py`` as ``PAPER_ROBOT``; the runtime reads it, never
    the prefix)."""

    prefix: str
    output_dir: str
    paper_robot: bool = False


# The shipped robots whose code is not named after them (every other robot file, shipped
# or not, whatever its kind: prefix and folder ``c_identifier(name)``). Drishti, the
# paper's robot, keeps the prefix ``wmr`` and the root of ``generated/`` it has always
# had; a copy of its file elsewhere is another robot and gets the default.
SHIPPED_NAMING: dict[str, Naming] = {
    DEFAULT_ROBOT: Naming(prefix="wmr", output_dir="", paper_robot=True),
}


def c_identifier(name: str) -> str:
    """A C/Python identifier prefix from a robot name: ``my-robot`` → ``my_robot``."""
    ident = re.sub(r"\W+", "_", name.strip()).strip("_").lower()
    if not ident or ident[0].isdigit():
        ident = f"robot_{ident}"
    return ident


def naming_of(name: str, path: str | Path | None) -> Naming:
    """The naming of robot ``name`` read from ``path`` (``None``: Drishti's packaged file):
    the shipped-robot table's for a shipped robot's own file, else prefix and folder
    ``c_identifier(name)``."""
    for shipped, naming in SHIPPED_NAMING.items():
        if path is None and shipped == DEFAULT_ROBOT:
            return naming
        if path is not None and Path(path).resolve() == shipped_robot_file(shipped):
            return naming
    ident = c_identifier(name)
    return Naming(prefix=ident, output_dir=ident)


def text_digest(text: str) -> str:
    """SHA-256 of a robot file's text (as read, UTF-8): generated ``robot.py`` records it,
    and the runtime refuses code generated from another version of the file."""
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def read_robot_text(path: str | Path) -> str:
    """A robot file's text; ``RobotFileError`` naming the file if it cannot be read."""
    p = Path(path)
    try:
        return p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise RobotFileError(f"{p}: robot file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise RobotFileError(f"{p}: cannot read robot file: {exc}") from None


@dataclass(frozen=True)
class RobotSource:
    """A robot file read once: its text and TOML (every reader of a command takes this,
    none reads the file again), and the name errors give it (``where``). ``path``: None for
    Drishti's packaged file."""

    path: Path | None
    where: str
    text: str
    data: dict[str, Any]

    @property
    def digest(self) -> str:
        return text_digest(self.text)

    @property
    def name(self) -> str:
        """The robot's name: the file's ``name``, else the file's stem."""
        name = self.data.get("name", Path(self.where).stem)
        if not isinstance(name, str) or not name:
            raise RobotFileError(f"{self.where}: field 'name' must be a non-empty string")
        return name

    @property
    def naming(self) -> Naming:
        """Its prefix and output folder (:func:`naming_of`)."""
        return naming_of(self.name, self.path)


def read_robot_file(path: str | Path | None = None) -> RobotSource:
    """Read and parse a robot file once (``None``: Drishti's, :func:`packaged_source`);
    ``RobotFileError`` naming the file if it cannot be read or is not TOML."""
    if path is None:
        return packaged_source()
    return _parsed(Path(path), str(path), read_robot_text(path))


@cache
def packaged_source() -> RobotSource:
    """Drishti's own robot file, named as in the package, read once per process: the robot
    file of ``wmr model`` and the defaults of Drishti's model are one reading (package data
    does not change under a running command)."""
    file = shipped_robot_file(DEFAULT_ROBOT)
    source = _parsed(file, source_label(file), read_robot_text(file))
    return RobotSource(None, source.where, source.text, source.data)


def _parsed(path: Path, where: str, text: str) -> RobotSource:
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise RobotFileError(f"{where}: not valid TOML: {exc}") from None
    return RobotSource(path, where, text, data)


def describes_bodies(data: Mapping[str, Any]) -> bool:
    """Whether a parsed robot file describes bodies, joints and wheels (``[[body]]``)."""
    return "body" in data


def is_description(path: str | Path) -> bool:
    """Whether a robot file describes bodies, joints and wheels (``[[body]]`` tables)."""
    try:
        data = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return False  # load_robot reports the error with the file's name
    return describes_bodies(data)


def shipped_robot_file(name: str) -> Path:
    """The robot file of a shipped robot: ``modeling/robots/<name>/<name>.toml``."""
    return ROBOTS_DIR / name / f"{name}.toml"


def shipped_robot_files() -> list[Path]:
    """The robots ``make model`` generates: every ``modeling/robots/<name>/<name>.toml``,
    the default (Drishti) first."""
    files = [shipped_robot_file(d.name) for d in ROBOTS_DIR.iterdir() if d.is_dir()]
    return sorted((f for f in files if f.is_file()),
                  key=lambda p: (p.stem != DEFAULT_ROBOT, p.stem))


def source_label(path: str | Path) -> str:
    """A robot file's name for generated preambles: relative to the repository when it is
    inside it (generated output must not depend on where the clone lives)."""
    p = Path(path).resolve()
    try:
        return p.relative_to(ROBOTS_DIR.parent.parent).as_posix()
    except ValueError:
        return Path(path).as_posix()
