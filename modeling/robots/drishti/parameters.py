"""Drishti's parameters, declared once, and the robot-file tables that give them (no SymPy).

``LUMPED`` is the paper's lumped parameters m, I, K, Iw, r, b, d: the controllers' model
takes them at run time (``model.robot_model``), a ``[lumped]`` robot file gives them, and
the generated C struct, ``C_FIELD_NAMES``, MODEL.md and the error messages below read key,
meaning, unit and C spelling from here. ``K_LAT`` is the plant's extra parameter; the
``PHYSICAL`` fields are a ``[physical]`` robot file's (platform + two wheels, from which
``robot_file.lumped_from_physical`` derives the lumped ones)::

    name = "drishti"
    [lumped]                      # the paper's parameters, used directly
    m = 36.0  I = 5.72  K = 0.34  Iw = 0.07  r = 0.096  b = 0.414  d = 0.12

    name = "my-robot"
    [physical]                    # platform + two wheels (modeling.robots.drishti.model)
    m_P = 30.0  I_P = 2.0  x_P = 0.0  y_P = 0.0  m_w = 3.0  Iw = 0.07  Im = 0.04
    r = 0.096  b = 0.414  d = 0.12

Either may state where the robot stands besides its two wheels: ``[[support]]`` tables on
the one body, ``platform`` (frame origin C, x forward; ``modeling.supports``: format, the
default of a file that states none, which Drishti's own file is, and the checks).

:func:`read_tables` checks such a file's numbers field by field (every error names the
file and the field); turning them into a robot is ``robot_file``'s, which needs SymPy only
for a ``[physical]`` table. ``model`` reads its defaults (``drishti.toml``) through here,
so that this module, not the model, is what the robot-file modules build on.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from modeling.parameter_table import ParameterInfo
from modeling.planar_robot import PlanarSupport
from modeling.robot_io import RobotFileError, packaged_source
from modeling.supports import supports_of

# The order of the generated structs.
LUMPED: tuple[ParameterInfo, ...] = (
    ParameterInfo("m", "total mass", "kg"),
    # C99's <complex.h> defines I (the imaginary unit) as a macro.
    ParameterInfo("I", "yaw inertia about C", "kg m^2", c_name="Iz"),
    ParameterInfo("K", "first moment of mass behind C", "kg m"),
    ParameterInfo("Iw", "wheel spin inertia", "kg m^2"),
    ParameterInfo("r", "wheel radius", "m"),
    ParameterInfo("b", "track width", "m"),
    ParameterInfo("d", "distance of C ahead of the axle midpoint", "m"),
)
K_LAT = ParameterInfo("K_lat", "first moment of mass left of C", "kg m",
                      remark="off-axis payload")
_SHARED = {p.key: p for p in LUMPED}
PHYSICAL: tuple[ParameterInfo, ...] = (
    ParameterInfo("m_P", "platform mass", "kg"),
    ParameterInfo("I_P", "platform yaw inertia about its centre of mass", "kg m^2"),
    ParameterInfo("x_P", "platform centre of mass ahead of the axle midpoint", "m"),
    ParameterInfo("y_P", "platform centre of mass left of the axis", "m"),
    ParameterInfo("m_w", "wheel mass", "kg"),
    _SHARED["Iw"],
    ParameterInfo("Im", "wheel inertia about a vertical diameter", "kg m^2"),
    _SHARED["r"],
    _SHARED["b"],
    _SHARED["d"],
)

# A robot file's fields: key -> "meaning [unit]" (what a missing field's message says).
LUMPED_FIELDS: dict[str, str] = {p.key: p.with_unit for p in LUMPED}
PHYSICAL_FIELDS: dict[str, str] = {p.key: p.with_unit for p in PHYSICAL}
# Must be > 0; K (a first moment) and the offsets may have either sign; d ≥ 0 by the
# paper's convention (C ahead of the axle), and d = 0 is allowed (C on the axle).
POSITIVE = {"m", "I", "Iw", "r", "b", "m_P", "I_P", "m_w"}
NON_NEGATIVE = {"d", "Im"}



@dataclass(frozen=True)
class RobotTables:
    """A ``[lumped]``/``[physical]`` robot file's name and the numbers of its one table."""

    name: str
    lumped: dict[str, float] | None
    physical: dict[str, float] | None
    supports: tuple[PlanarSupport, ...] | None = None  # [[support]] (modeling.supports)


def packaged_text() -> tuple[str, str]:
    """The text of Drishti's own robot file and the name errors give it (read once per
    process: ``modeling.robot_io.packaged_source``)."""
    source = packaged_source()
    return source.text, source.where


def _number(where: str, key: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise RobotFileError(f"{where}: field '{key}' must be a number, got {value!r}")
    x = float(value)
    if not math.isfinite(x):
        raise RobotFileError(f"{where}: field '{key}' must be finite, got {value!r}")
    if key in POSITIVE and x <= 0:
        raise RobotFileError(f"{where}: field '{key}' must be positive, got {value!r}")
    if key in NON_NEGATIVE and x < 0:
        raise RobotFileError(f"{where}: field '{key}' must be non-negative, got {value!r}")
    return x


def _table(where: str, section: str, data: Any, fields: dict[str, str]) -> dict[str, float]:
    if not isinstance(data, dict):
        raise RobotFileError(f"{where}: [{section}] must be a table")
    unknown = sorted(set(data) - set(fields))
    if unknown:
        raise RobotFileError(
            f"{where}: unknown field '{unknown[0]}' in [{section}] (expected: {', '.join(fields)})"
        )
    missing = [k for k in fields if k not in data]
    if missing:
        raise RobotFileError(
            f"{where}: missing field '{missing[0]}' in [{section}] ({fields[missing[0]]})"
        )
    return {k: _checked(where, section, k, data[k]) for k in fields}


def _checked(where: str, section: str, key: str, value: Any) -> float:
    try:
        return _number(where, key, value)
    except RobotFileError as exc:
        raise RobotFileError(
            str(exc).replace(f"field '{key}'", f"field '{section}.{key}'")
        ) from None


def check_lumped(where: str, p: dict[str, float], k_lat: float = 0.0) -> None:
    """The kinetic energy must be positive definite: m > 0 and I > (K² + K_lat²)/m."""
    if p["I"] <= (p["K"] ** 2 + k_lat**2) / p["m"]:
        raise RobotFileError(
            f"{where}: field 'I' = {p['I']} must exceed (K² + K_lat²)/m = "
            f"{(p['K'] ** 2 + k_lat**2) / p['m']:.6g}: otherwise the kinetic energy is not "
            "positive definite (I is the inertia about C, at least the centre-of-mass term)"
        )


def read_tables(text: str, where: str = "<string>") -> RobotTables:
    """The checked numbers of a ``[lumped]`` or ``[physical]`` robot file (a ``[lumped]``
    table is also checked by :func:`check_lumped`); ``RobotFileError`` names ``where`` and
    the field."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise RobotFileError(f"{where}: not valid TOML: {exc}") from None
    return tables_of(data, where)


def tables_of(data: dict[str, Any], where: str = "<string>") -> RobotTables:
    """:func:`read_tables` of a file's TOML already parsed (``modeling.robot_file`` parses
    a robot file once)."""
    unknown = sorted(set(data) - {"name", "lumped", "physical", "support"})
    if unknown:
        raise RobotFileError(
            f"{where}: unknown field '{unknown[0]}' (expected name, [lumped] or [physical], "
            "and optionally [[support]])"
        )
    name = data.get("name", Path(where).stem)
    if not isinstance(name, str) or not name:
        raise RobotFileError(f"{where}: field 'name' must be a non-empty string")
    if ("lumped" in data) == ("physical" in data):
        raise RobotFileError(f"{where}: give exactly one of the tables [lumped] or [physical]")
    if "lumped" in data:
        lumped = _table(where, "lumped", data["lumped"], LUMPED_FIELDS)
        check_lumped(where, lumped)
        return RobotTables(name, lumped, None, _supports(data, where, lumped["r"]))
    physical = _table(where, "physical", data["physical"], PHYSICAL_FIELDS)
    return RobotTables(name, None, physical, _supports(data, where, physical["r"]))


def _supports(data: dict[str, Any], where: str, r: float) -> tuple[PlanarSupport, ...] | None:
    """The file's ``[[support]]`` on the one body, ``platform`` (frame origin C; see
    ``modeling.supports``; default radius r/2)."""
    return supports_of(data, where, ("platform",), r / 2)
