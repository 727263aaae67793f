"""Which robot's generated code the crosscheck reads: a :class:`Target` is one folder with
``python/`` (the NumPy reference and controller classes, described by its ``robot.py``),
``c/`` and ``casadi/``.

Robots found under ``generated/``: the root (the default robot) and every
``generated/<name>/`` with a ``python/robot.py``. ``--robot`` takes a robot's name (its
``robot.py`` NAME, or the folder name) or a folder path; a folder outside ``generated/``
(e.g. a modified copy) is imported as a package of its own (``load_robot_code(Path)``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from runtime.generated_modules import GENERATED, RobotCode, load_robot_code
from runtime.robot_source import generated_robots


@dataclass(frozen=True)
class Target:
    """One robot's generated code: its Python (``code``) and where its C and CasADi are."""

    code: RobotCode
    folder: Path
    c_dir: Path
    casadi_dir: Path

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


def _is_robot(folder: Path) -> bool:
    return (folder / "python" / "robot.py").is_file()


def discover() -> list[Path]:
    """Every generated robot folder: the root of generated/, then generated/<name>/."""
    return generated_robots(GENERATED)


def target_of(folder: Path) -> Target:
    """The target of a robot folder (``python/``, ``c/``, ``casadi/`` inside)."""
    folder = folder.resolve()
    if not _is_robot(folder):
        raise FileNotFoundError(f"{folder}: no generated robot here (python/robot.py missing)")
    if folder == GENERATED.resolve():
        code = load_robot_code("")
    elif folder.parent == GENERATED.resolve():
        code = load_robot_code(folder.name)
    else:
        code = load_robot_code(folder)  # a package of its own
    return Target(code, folder, folder / "c", folder / "casadi")


def resolve(name_or_dir: str) -> Target:
    """``--robot``: a folder path, or the name of a robot found under generated/."""
    path = Path(name_or_dir)
    if path.is_dir():
        return target_of(path)
    names: dict[str, Path] = {}
    for folder in discover():
        names.setdefault(folder.name, folder)
        names[target_of(folder).name] = folder
    if name_or_dir in names:
        return target_of(names[name_or_dir])
    raise SystemExit(
        f"--robot {name_or_dir!r}: not a folder and not a generated robot "
        f"(found: {', '.join(sorted(n for n in names if n != GENERATED.name))})"
    )


def all_targets() -> list[Target]:
    return [target_of(folder) for folder in discover()]
