"""Reading robot descriptions from TOML (the format is in :mod:`modeling.description`).

Errors are ``DescriptionError``s naming the file and the field; a file is either loaded
whole or rejected (nothing is half-loaded). The entries are checked here for their TOML
types (numbers, pairs, strings, booleans, known and required keys) and then by
``schema.validate`` for what makes a robot (names, joints, connectivity, signs).
"""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

from modeling.description.schema import (
    OPTIONAL,
    SECTIONS,
    BodySpec,
    JointSpec,
    RobotDescription,
    WheelSpec,
    check_point,
    check_value,
    fail,
    validate,
)
from modeling.robot_io import shipped_robot_file


def _entry(where: str, section: str, index: int, data: Any) -> dict[str, Any]:
    fields = SECTIONS[section]
    label = f"{section}[{index}]"
    if not isinstance(data, dict):
        raise fail(where, f"field '{label}' must be a table ([[{section}]])")
    unknown = sorted(set(data) - set(fields))
    if unknown:
        raise fail(where, f"unknown field '{label}.{unknown[0]}' "
                    f"(expected: {', '.join(fields)})")
    missing = [k for k in fields if k not in data and k not in OPTIONAL.get(section, set())]
    if missing:
        raise fail(where, f"missing field '{label}.{missing[0]}'")
    out = dict(data)
    for key, kind in fields.items():
        if key not in out:
            continue
        value = out[key]
        if kind == "point":
            check_point(where, f"{label}.{key}", value)
            out[key] = (float(value[0]), float(value[1]))
        elif kind in ("positive", "non-negative", "any"):
            check_value(where, f"{label}.{key}", kind, value)
            out[key] = float(value)
    return out


def parse_description(text: str, where: str = "<string>") -> RobotDescription:
    """A RobotDescription (numbers as floats) from TOML text; errors name ``where`` and
    the field. See the format in :mod:`modeling.description`."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise fail(where, f"not valid TOML: {exc}") from None
    unknown = sorted(set(data) - {"name", *SECTIONS})
    if unknown:
        raise fail(where, f"unknown field '{unknown[0]}' (expected name, [[body]], "
                    "[[joint]], [[wheel]])")
    name = data.get("name", Path(where).stem)
    if not isinstance(name, str) or not name:
        raise fail(where, "field 'name' must be a non-empty string")
    parts: dict[str, list[dict[str, Any]]] = {}
    for section in SECTIONS:
        items = data.get(section, [])
        if not isinstance(items, list):
            raise fail(where, f"field '{section}' must be an array of tables ([[{section}]])")
        parts[section] = [_entry(where, section, i, item) for i, item in enumerate(items)]
    desc = RobotDescription(
        name=name,
        bodies=tuple(BodySpec(**b) for b in parts["body"]),
        joints=tuple(JointSpec(**j) for j in parts["joint"]),
        wheels=tuple(WheelSpec(**w) for w in parts["wheel"]),
    )
    validate(desc, where)
    return desc


def load_description(path: str | Path) -> RobotDescription:
    """Read and parse a description file; a missing or unreadable file is a
    DescriptionError naming the path."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise fail(str(p), "robot description not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise fail(str(p), f"cannot read robot description: {exc}") from None
    return parse_description(text, str(p))


def packaged_description(name: str) -> RobotDescription:
    """A description shipped in ``modeling/robots/<name>/`` (e.g. "trailer")."""
    return load_description(shipped_robot_file(name))
