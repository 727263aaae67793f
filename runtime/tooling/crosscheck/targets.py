"""Which robot's generated code the crosscheck reads: a :class:`Target` is one folder with
``python/`` (the NumPy reference and controller classes, described by its ``robot.py``),
``c/`` and ``casadi/``.

Robots found under ``generated/``: the root (the default robot) and every
``generated/<name>/`` with a ``python/robot.py``. ``--robot`` is resolved as every command
resolves it (:func:`runtime.bindings.robots.resolve`): a robot's name (its ``robot.py``
NAME, or the folder name), a generated folder, or a robot file (its generated code); a
folder outside ``generated/`` (e.g. a modified copy) is imported as a package of its own.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

from runtime.bindings.generated import GENERATED, RobotCode
from runtime.bindings.robots import RobotSourceError, code_in, generated_robots
from runtime.bindings.robots import resolve as resolve_robot


@dataclass(frozen=True)
class Target:
    """One robot's generated code: its Python (``code``) and where its C and CasADi are;
    ``warnings``: the physics audit's on the robot file (a robot file's own, else those its
    generated ``robot.py`` records)."""

    code: RobotCode
    folder: Path
    c_dir: Path
    casadi_dir: Path
    warnings: tuple[str, ...] = ()

    @property
    def name(self) -> str:
        return self.code.name

    @property
    def prefix(self) -> str:
        return self.code.prefix

    @property
    def label(self) -> str:
        """``name (folder, C prefix prefix_)`` for the report."""
        try:
            where = str(self.folder.resolve().relative_to(GENERATED.parent))
        except ValueError:
            where = str(self.folder)
        return f"{self.name} ({where}/, C prefix {self.prefix}_)"


def discover() -> list[Path]:
    """Every generated robot folder: the root of generated/, then generated/<name>/."""
    return generated_robots(GENERATED)


def target_of(folder: Path) -> Target:
    """The target of a robot folder (``python/``, ``c/``, ``casadi/`` inside)."""
    code = code_in(folder)
    folder = folder.resolve()
    return Target(code, folder, folder / "c", folder / "casadi", code.audit_warnings)


def resolve(robot: str, generated: Path | None = None) -> Target:
    """``--robot`` (and ``--generated``) as every command resolves them; exits with its
    sentence otherwise."""
    try:
        setup = resolve_robot(robot, generated)
    except RobotSourceError as exc:
        raise SystemExit(str(exc)) from None
    return replace(target_of(setup.code.folder), warnings=setup.warnings)


def all_targets() -> list[Target]:
    return [target_of(folder) for folder in discover()]
