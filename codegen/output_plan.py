"""Which robot writes where, checked before anything is written: two robots that would
write the same path are refused with one line naming both and the path.

A robot writes only under its folder (``RobotModel.output_dir``; "" is the output's root),
and there only :data:`ROBOT_ENTRIES`: the backends' folders, ``MODEL.md`` and
``__init__.py`` (``codegen.generate``). Its generated ``python/robot.py`` is its manifest:
the robots already in an output folder are read from there (``NAME``, parsed, not
imported). Two robots of the same name are one robot regenerated. The folder check needs
no derivation, so a refused command costs no time; :func:`shared_path` checks the rendered
paths themselves before they are written.
"""

from __future__ import annotations

import ast
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

from codegen import backends

ROBOT_ENTRIES = frozenset({*(b.folder for b in backends.registered()), "MODEL.md",
                           "__init__.py"})
MANIFEST = "python/robot.py"  # every robot writes it; it declares the robot's NAME


@dataclass(frozen=True)
class Placed:
    """A robot and its folder in the output; ``origin`` says where it comes from (its
    robot file, or the output folder it is already generated in)."""

    name: str
    folder: str
    origin: str

    def label(self) -> str:
        return f"'{self.name}' ({self.origin})"


def _declared_name(manifest: Path) -> str | None:
    """``NAME`` of a generated ``robot.py``, read without importing it."""
    try:
        tree = ast.parse(manifest.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, SyntaxError):
        return None
    for node in tree.body:
        if (isinstance(node, ast.Assign) and len(node.targets) == 1
                and isinstance(node.targets[0], ast.Name) and node.targets[0].id == "NAME"
                and isinstance(node.value, ast.Constant) and isinstance(node.value.value, str)):
            return node.value.value
    return None


def robots_in(out: Path) -> list[Placed]:
    """The robots already generated in ``out``: its root and each folder one level down
    that holds a ``python/robot.py`` (robot folders are ``c_identifier``s: one level)."""
    if not out.is_dir():
        return []
    manifests = [out / MANIFEST, *sorted(out.glob(f"*/{MANIFEST}"))]
    found = []
    for manifest in manifests:
        name = _declared_name(manifest) if manifest.is_file() else None
        if name is not None:
            folder = manifest.parent.parent.relative_to(out).as_posix()
            found.append(Placed(name, "" if folder == "." else folder, f"already in {out}"))
    return found


def _within(folder: str, other: str) -> bool:
    """Whether ``folder`` lies in one of the entries robot folder ``other`` writes."""
    if other == "":
        rest = PurePosixPath(folder).parts
    elif folder.startswith(f"{other}/"):
        rest = PurePosixPath(folder[len(other) + 1:]).parts
    else:
        return False
    return bool(rest) and rest[0] in ROBOT_ENTRIES


def _clash(a: Placed, b: Placed) -> str | None:
    """The path (relative to the output) both would write, if they are two robots."""
    if a.name == b.name:
        return None
    if a.folder == b.folder or _within(a.folder, b.folder):
        return (PurePosixPath(a.folder) / MANIFEST).as_posix()
    if _within(b.folder, a.folder):
        return (PurePosixPath(b.folder) / MANIFEST).as_posix()
    return None


def _refusal(a: Placed, b: Placed, path: str, out: Path) -> str:
    return (f"robots {a.label()} and {b.label()} would both write {out / path}: give one "
            "of them another name (its prefix and folder follow from it) or another --out")


def folder_collision(planned: Sequence[Placed], out: Path) -> str | None:
    """The refusal (one line) if two robots of ``planned``, or one of them and a robot
    already in ``out``, would write the same path; None if every robot has its own place."""
    existing = robots_in(out)
    for i, a in enumerate(planned):
        for b in (*planned[:i], *existing):
            path = _clash(a, b)
            if path is not None:
                return _refusal(b, a, path, out) if b in planned else _refusal(a, b, path, out)
    return None


def shared_path(produced: Sequence[tuple[Placed, Iterable[str]]], out: Path) -> str | None:
    """The refusal (one line) if two robots rendered the same path (relative to ``out``)."""
    owner: dict[str, Placed] = {}
    for robot, paths in produced:
        for path in paths:
            first = owner.setdefault(path, robot)
            if first is not robot and first.name != robot.name:
                return _refusal(first, robot, path, out)
    return None
