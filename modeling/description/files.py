"""Reading robot descriptions from TOML (the format is in :mod:`modeling.description`).

Errors are ``DescriptionError``s naming the file and the field; a file is either loaded
whole or rejected (nothing is half-loaded). The entries are checked here for their TOML
types (numbers, pairs, strings, booleans, known and required keys), then by
``schema.validate`` for what makes a robot (names, joints, connectivity, signs), then by the
physics audit (``modeling.audit``: units, inertias, over-constrained layouts, motors), whose
warnings the description carries.

Two optional parts are read here and folded into the dataclasses: a driven wheel's motor
(``rotor_inertia`` J_r and ``gear_ratio`` N: its spin inertia becomes spin_inertia + J_r N²)
and the ``[import]`` table ``wmr import`` writes (``source``, ``findings``: the importer's
findings, which become warnings of the description).
"""

from __future__ import annotations

import tomllib
from dataclasses import replace
from pathlib import Path
from typing import Any

from modeling.audit import Rotor, audit_description
from modeling.contact_loads import checked_supports
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
from modeling.planar_robot import from_description
from modeling.robot_io import shipped_robot_file
from modeling.supports import default_radius, supports_of

# A wheel's motor, optional (both or neither): J_r (kg m²) and N; see the module docstring.
MOTOR_FIELDS = {"rotor_inertia": "non-negative", "gear_ratio": "positive"}
IMPORT_FIELDS = ("source", "findings")


def _motor(where: str, index: int, data: dict[str, Any]) -> Rotor | None:
    """Pop a wheel entry's motor fields (checked); None when it gives none."""
    given = [k for k in MOTOR_FIELDS if k in data]
    if not given:
        return None
    label = f"wheel[{index}]"
    if len(given) == 1:
        other = next(k for k in MOTOR_FIELDS if k not in data)
        raise fail(where, f"field '{label}.{given[0]}' needs '{label}.{other}' too (the rotor "
                    "adds J_r N^2 to the spin inertia: give both, or neither)")
    for key, kind in MOTOR_FIELDS.items():
        check_value(where, f"{label}.{key}", kind, data[key])
    if not data.get("driven", False):
        raise fail(where, f"field '{label}.rotor_inertia': wheel {index} is not driven (a "
                    "motor's rotor belongs to a driven wheel)")
    return Rotor(float(data.pop("rotor_inertia")), float(data.pop("gear_ratio")))


def _import_table(where: str, data: Any) -> tuple[str, ...]:
    """The findings of an ``[import]`` table (``wmr import``'s, with its source file)."""
    if not isinstance(data, dict):
        raise fail(where, "field 'import' must be a table ([import])")
    unknown = sorted(set(data) - set(IMPORT_FIELDS))
    if unknown:
        raise fail(where, f"unknown field 'import.{unknown[0]}' (expected: "
                    f"{', '.join(IMPORT_FIELDS)})")
    source = data.get("source", "")
    findings = data.get("findings", [])
    if not isinstance(source, str):
        raise fail(where, "field 'import.source' must be a string (the imported file)")
    if not isinstance(findings, list) or not all(isinstance(f, str) for f in findings):
        raise fail(where, "field 'import.findings' must be an array of strings")
    return tuple(f"import of {source}: {f}" if source else f"import: {f}" for f in findings)


def _entry(where: str, section: str, index: int, data: Any) -> dict[str, Any]:
    fields = SECTIONS[section]
    label = f"{section}[{index}]"
    if not isinstance(data, dict):
        raise fail(where, f"field '{label}' must be a table ([[{section}]])")
    known = set(fields) | (set(MOTOR_FIELDS) if section == "wheel" else set())
    unknown = sorted(set(data) - known)
    if unknown:
        optional = ", and optionally rotor_inertia, gear_ratio" if section == "wheel" else ""
        raise fail(where, f"unknown field '{label}.{unknown[0]}' "
                    f"(expected: {', '.join(fields)}{optional})")
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
    return description_of(data, where)


def description_of(data: dict[str, Any], where: str = "<string>") -> RobotDescription:
    """:func:`parse_description` of a file's TOML already parsed (``modeling.robot_file``
    parses a robot file once)."""
    unknown = sorted(set(data) - {"name", "import", "support", *SECTIONS})
    if unknown:
        raise fail(where, f"unknown field '{unknown[0]}' (expected name, [[body]], "
                    "[[joint]], [[wheel]] and optionally [[support]], [import])")
    name = data.get("name", Path(where).stem)
    if not isinstance(name, str) or not name:
        raise fail(where, "field 'name' must be a non-empty string")
    findings = _import_table(where, data["import"]) if "import" in data else ()
    parts: dict[str, list[dict[str, Any]]] = {}
    motors: dict[int, Rotor] = {}
    for section in SECTIONS:
        items = data.get(section, [])
        if not isinstance(items, list):
            raise fail(where, f"field '{section}' must be an array of tables ([[{section}]])")
        if section == "wheel":
            items = [dict(item) if isinstance(item, dict) else item for item in items]
            motors = {i: m for i, item in enumerate(items)
                      if isinstance(item, dict) and (m := _motor(where, i, item)) is not None}
        parts[section] = [_entry(where, section, i, item) for i, item in enumerate(items)]
    for i, motor in motors.items():
        parts["wheel"][i]["spin_inertia"] += motor.reflected
    desc = RobotDescription(
        name=name,
        bodies=tuple(BodySpec(**b) for b in parts["body"]),
        joints=tuple(JointSpec(**j) for j in parts["joint"]),
        wheels=tuple(WheelSpec(**w) for w in parts["wheel"]),
    )
    validate(desc, where)
    stands = supports_of(data, where, tuple(b.name for b in desc.bodies),
                         default_radius([float(w.radius) for w in desc.wheels]))
    desc = replace(desc, supports=stands)
    checked_supports(from_description(desc), where)
    rotors = {desc.wheels[i].name: m for i, m in motors.items()}
    warnings = audit_description(where, desc, rotors, findings)
    return replace(desc, warnings=warnings)


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
