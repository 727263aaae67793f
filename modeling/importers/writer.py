"""A :class:`~modeling.importers.planar.PlanarRobot` as a bodies-and-wheels robot file.

The format is ``modeling.description``'s, so the rest of the toolchain reads the file
unchanged. Every value carries a comment saying where it came from; the header lists what
was merged, dropped, frozen and projected; the importer's findings go into the
``[import]`` table, which the description reader turns into warnings (printed, and written
into MODEL.md). Numbers are written with 12 significant digits: more than any description
file carries, and a composition that should give 0.05 writes 0.05.
"""

from __future__ import annotations

import json
import textwrap
from pathlib import Path

from modeling.importers.planar import PlanarRobot
from modeling.version import VERSION

WIDTH = 92
COLUMN = 32  # where value comments start


def number(x: float) -> str:
    """A TOML float with 12 significant digits (always with a point or an exponent)."""
    if x == 0:
        return "0.0"
    text = f"{x:.12g}"
    return text if any(c in text for c in ".en") else f"{text}.0"


def _string(s: str) -> str:
    return json.dumps(s, ensure_ascii=False)  # a valid TOML basic string


def _line(assignment: str, comment: str) -> str:
    if not comment:
        return assignment
    return f"{assignment.ljust(COLUMN - 1)} # {comment}"


def _point(p: tuple[float, float]) -> str:
    return f"[{number(p[0])}, {number(p[1])}]"


def _bullets(lines: list[str]) -> list[str]:
    out = []
    for line in lines:
        out += textwrap.wrap(line, WIDTH - 4, initial_indent="# - ",
                             subsequent_indent="#   ", break_on_hyphens=False)
    return out


def robot_file_text(robot: PlanarRobot) -> str:
    """The robot file's text (see the module docstring)."""
    source = Path(robot.source).name
    out = [
        f"# Imported by `wmr import` (wmr-toolchain {VERSION}) from {source} ({robot.fmt}).",
        "# A bodies-and-wheels robot file (format: modeling/description/__init__.py); each",
        "# value's comment says where it came from. Lengths in m, masses in kg, inertias in",
        "# kg m^2. `wmr model --robot THIS_FILE --out DIR` derives it.",
        "#",
        *_bullets(robot.header),
    ]
    if robot.findings:
        out += ["#", "# Findings of the import (also in [import] below, printed by every command",
                "# that reads this file, and written into MODEL.md):", *_bullets(robot.findings)]
    out += ["", f"name = {_string(robot.name)}", "", "[import]",
            f"source = {_string(source)}"]
    if robot.findings:
        out.append("findings = [")
        out += [f"    {_string(f)}," for f in robot.findings]
        out.append("]")
    else:
        out.append("findings = []")
    for b in robot.bodies:
        out += ["", "[[body]]",
                _line(f"name = {_string(b.name)}", b.notes.get("name", "")),
                _line(f"mass = {number(b.mass)}", b.notes.get("mass", "")),
                _line(f"yaw_inertia = {number(b.yaw_inertia)}", b.notes.get("yaw_inertia", "")),
                _line(f"com = {_point(b.com)}", b.notes.get("com", ""))]
    for j in robot.joints:
        out += ["", _line("[[joint]]", j.notes.get("kind", "")),
                'kind = "revolute"',
                _line(f"parent = {_string(j.parent)}", ""),
                _line(f"child = {_string(j.child)}", ""),
                _line(f"parent_point = {_point(j.parent_point)}", j.notes.get("parent_point", "")),
                _line(f"child_point = {_point(j.child_point)}", j.notes.get("child_point", ""))]
    for w in robot.wheels:
        out += ["", "[[wheel]]",
                _line(f"name = {_string(w.name)}", w.notes.get("name", "")),
                _line(f"body = {_string(w.body)}", ""),
                _line(f"position = {_point(w.position)}", w.notes.get("position", "")),
                _line(f"radius = {number(w.radius)}", w.notes.get("radius", "")),
                _line(f"spin_inertia = {number(w.spin_inertia)}",
                      w.notes.get("spin", "") + ("; the wheel alone (+ J_r N^2 below)"
                                                 if w.rotor else "")),
                _line(f"diameter_inertia = {number(w.diameter_inertia)}",
                      w.notes.get("diameter", "")),
                _line(f"mass = {number(w.mass)}", w.notes.get("mass", "")),
                _line(f"driven = {'true' if w.driven else 'false'}", w.notes.get("driven", ""))]
        if w.rotor is not None:
            out += [_line(f"rotor_inertia = {number(w.rotor.inertia)}",
                          f"kg m^2, J_r: {w.notes.get('rotor', '')}"),
                    _line(f"gear_ratio = {number(w.rotor.gear_ratio)}",
                          f"N (J_r N^2 = {number(w.rotor.reflected)} kg m^2 added to the spin "
                          "inertia)")]
        elif w.driven:
            gear = number(w.gear_ratio_only) if w.gear_ratio_only else "?"
            source = w.notes["rotor"] if w.gear_ratio_only else "from the gearbox's datasheet"
            out += [_line("# rotor_inertia = ?", "kg m^2, J_r of the motor's rotor: not in the "
                          "file; from its datasheet (give both fields, or neither)"),
                    _line(f"# gear_ratio = {gear}", f"N: {source}")]
    return "\n".join(out) + "\n"
