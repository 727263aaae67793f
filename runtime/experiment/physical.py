"""Uncertainty in the robot's own terms: ranges of its bodies' masses, yaw inertias and
centres of mass, and of a payload on the root body (section ``[physical_uncertainty]`` of
an experiment or campaign file).

    [physical_uncertainty]
    mass = 0.2                 # every body's mass within ±20 % of its own (relative)
    yaw_inertia = 0.2          # every body's yaw inertia within ±20 %
    com = 0.02                 # m: every body's centre of mass within ±2 cm in x and in y
    payload_mass = [0.0, 9.0]  # kg, a point payload on the root body …
    payload_x = [-0.1, 0.1]    # m … anywhere in this box of its frame
    payload_y = [-0.1, 0.1]

    [physical_uncertainty.cart] # one body's (or wheel's) own ranges, over the defaults:
    mass = [12.0, 20.0]        # [min, max] absolute; a number is relative (com_x, com_y:
    com_x = [-0.5, -0.4]       # a half-width in m); a wheel has mass, spin_inertia,
                               # diameter_inertia

A quantity not stated keeps the robot file's value. The declaration is checked here
without the robot (numbers, ranges: one line naming the field); :func:`physical_box`
resolves it on a robot's generated code (its ``PHYSICAL`` quantities; a ``[lumped]``
robot has none: its uncertainty is the lumped box ``controller.uncertainty``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

SECTION = "physical_uncertainty"
DEFAULT_FIELDS = ("mass", "yaw_inertia", "com")  # relative, relative, half-width in m
PAYLOAD_FIELDS = ("payload_mass", "payload_x", "payload_y")  # [min, max] only
BODY_FIELDS = ("mass", "yaw_inertia", "com_x", "com_y")
WHEEL_FIELDS = ("mass", "spin_inertia", "diameter_inertia")
LENGTHS = ("com", "com_x", "com_y", "payload_x", "payload_y")

# (part, field, low, high, relative): part "" for a default or the payload; relative: the
# range is nominal × (1 ± low) for a mass or inertia, nominal ± low for a length.
Entry = tuple[str, str, float, float, bool]


class PhysicalUncertaintyError(ValueError):
    """A physical uncertainty declaration that cannot be used; the message names the
    field."""


@dataclass(frozen=True)
class PhysicalUncertainty:
    """A checked declaration (robot-independent), ``entries`` in file order; empty: none
    declared."""

    entries: tuple[Entry, ...] = ()

    def __bool__(self) -> bool:
        return bool(self.entries)

    def describe(self) -> str:
        """One line: what the declaration states."""
        parts = []
        for part, name, lo, hi, rel in self.entries:
            label = f"{part}.{name}" if part else name
            unit = " m" if name in LENGTHS else ""
            if rel:
                parts.append(f"{label} ±{lo:g}{unit}" if unit else f"{label} ±{lo:.0%}")
            else:
                parts.append(f"{label} [{lo:g}, {hi:g}]{unit}")
        return ", ".join(parts) if parts else "none"

    @classmethod
    def from_data(cls, data: Any) -> PhysicalUncertainty:
        """The inverse of ``dataclasses.asdict`` (a campaign's JSON payload)."""
        entries = (data or {}).get("entries", ())
        return cls(tuple((str(p), str(f), float(lo), float(hi), bool(r))
                         for p, f, lo, hi, r in entries))


def _bad(where: str, label: str, what: str, value: Any) -> PhysicalUncertaintyError:
    return PhysicalUncertaintyError(f"{where}: field '{SECTION}.{label}' must be {what}, got "
                                    f"{value!r}")


def _number(where: str, label: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(
            value):
        raise _bad(where, label, "a finite number", value)
    return float(value)


def _value(where: str, part: str, name: str, value: Any) -> Entry:
    label = f"{part}.{name}" if part else name
    if isinstance(value, list):
        if len(value) != 2:
            raise _bad(where, label, "[min, max]", value)
        lo, hi = (_number(where, label, v) for v in value)
        if not lo <= hi:
            raise _bad(where, label, "[min, max] with min <= max", value)
        if name not in LENGTHS and lo < 0:
            raise _bad(where, label, "a range of non-negative values", value)
        return (part, name, lo, hi, False)
    if name in PAYLOAD_FIELDS:
        raise _bad(where, label, "[min, max]", value)
    s = _number(where, label, value)
    if name in LENGTHS:
        if s < 0:
            raise _bad(where, label, "a non-negative half-width (m) or [min, max]", value)
    elif not 0 <= s < 1:
        raise _bad(where, label, "a relative half-width in [0, 1) or [min, max]", value)
    return (part, name, s, s, True)


def parse_physical(data: Any, where: str) -> PhysicalUncertainty:
    """The ``[physical_uncertainty]`` table, checked (``PhysicalUncertaintyError``, a
    ``ValueError``, naming the field)."""
    if not isinstance(data, dict):
        raise PhysicalUncertaintyError(f"{where}: [{SECTION}] must be a table")
    entries: list[Entry] = []
    for key, value in data.items():
        if isinstance(value, dict):
            for name, v in value.items():
                if name not in BODY_FIELDS + WHEEL_FIELDS:
                    raise PhysicalUncertaintyError(
                        f"{where}: unknown field '{SECTION}.{key}.{name}' (a body has "
                        f"{', '.join(BODY_FIELDS)}; a wheel {', '.join(WHEEL_FIELDS)})")
                entries.append(_value(where, key, name, v))
            continue
        if key not in DEFAULT_FIELDS + PAYLOAD_FIELDS:
            raise PhysicalUncertaintyError(
                f"{where}: unknown field '{SECTION}.{key}' (expected one of "
                f"{', '.join(DEFAULT_FIELDS + PAYLOAD_FIELDS)}, or a table named by a body "
                "or wheel)")
        entries.append(_value(where, "", key, value))
    return PhysicalUncertainty(tuple(entries))


def physical_box(decl: PhysicalUncertainty, physical: Mapping[str, tuple[float, str, str]]
                 | None, bodies: tuple[str, ...], wheels: tuple[str, ...], robot: str
                 ) -> dict[str, tuple[float, float]]:
    """(min, max) of every physical quantity of the robot (``physical``: its generated
    ``PHYSICAL``, key -> (nominal, unit, what)), from the declaration: defaults first, then
    each body's or wheel's own ranges; a quantity not stated is its nominal value.
    ``PhysicalUncertaintyError`` naming the field for a part the robot does not have, a
    field a part cannot have, or a range that leaves a body's mass non-positive."""
    if physical is None:
        raise PhysicalUncertaintyError(
            f"robot '{robot}' is a [lumped]/[physical] robot: its model's parameters are "
            f"its lumped ones; state its uncertainty as controller.uncertainty (the lumped "
            f"box), not [{SECTION}]")
    nominal = {k: float(v[0]) for k, v in physical.items()}
    box = {k: (v, v) for k, v in nominal.items()}

    def put(key: str, lo: float, hi: float, rel: bool, name: str, label: str,
            body: bool = True) -> None:
        if rel:
            v = nominal[key]
            lo, hi = (v - lo, v + lo) if name in LENGTHS else (v * (1 - lo), v * (1 + lo))
        if body and name == "mass" and not lo > 0:
            raise PhysicalUncertaintyError(f"field '{SECTION}.{label}': {key} could be "
                                           f"{lo:g} kg; a body's mass must stay positive")
        box[key] = (lo, hi)

    for part, name, lo, hi, rel in decl.entries:
        if part:
            continue
        if name in PAYLOAD_FIELDS:
            put(name, lo, hi, rel, name, name)
            continue
        for body in bodies:
            for f in (("com_x", "com_y") if name == "com" else (name,)):
                put(f"{f}_{body}", lo, hi, rel, name, name)
    for part, name, lo, hi, rel in decl.entries:
        if not part:
            continue
        label = f"{part}.{name}"
        if part not in bodies and part not in wheels:
            raise PhysicalUncertaintyError(
                f"field '{SECTION}.{label}': robot '{robot}' has no body or wheel '{part}' "
                f"(bodies: {', '.join(bodies)}; wheels: {', '.join(wheels)})")
        fields = BODY_FIELDS if part in bodies else WHEEL_FIELDS
        if name not in fields:
            kind = "body" if part in bodies else "wheel"
            raise PhysicalUncertaintyError(
                f"field '{SECTION}.{label}': a {kind} has {', '.join(fields)}, not {name}")
        put(f"{name}_{part}", lo, hi, rel, name, label, body=part in bodies)
    return box
