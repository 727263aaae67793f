"""Robot files as files: the error every reader raises, the text and its digest, which
format a file is, and where the shipped robots are. Standard library only.

This is the leaf every robot-file module imports: ``modeling.description`` (bodies, joints
and wheels), Drishti's ``[lumped]``/``[physical]`` schema
(``modeling.robots.drishti.robot_file``) and the dispatcher between them,
``modeling.robot_file``; the runtime reads robot files through it without SymPy.
"""

from __future__ import annotations

import hashlib
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

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

    def plant_values(self) -> dict[str, float]:
        """The numbers the file gives the simulated robot: the lumped parameters and the
        lateral first moment its physical parameters imply (the plant-only K_lat)."""
        return {**self.lumped, "K_lat": self.K_lat}


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
