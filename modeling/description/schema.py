"""Robot descriptions: planar rigid bodies, revolute hitches and fixed standard wheels.

The dataclasses are the in-memory form (``modeling.description.files`` reads the TOML form
documented in :mod:`modeling.description` into them); ``validate`` checks a description,
from a file or built in Python, naming the offending field; ``symbolize`` turns the
numbers of a description into the symbols that the derivation works with.

Parameter values are Python numbers or SymPy expressions. ``symbolize`` applies one rule:

* a Python number in an *inertial* field (masses, inertias, centres of mass) or a wheel
  radius becomes a symbol named after the field and its owner (``mass_tractor``,
  ``com_x_cart``, ``radius_right``) and its value goes into ``values``, so that the
  derivation is symbolic in them (as Drishti's ``model`` is in m, I, K, …);
* a Python number in a *geometric* field that decides the constraint structure (wheel
  positions, hitch points) becomes the exact rational of its decimal form (0.207 → 207/1000).
  Which rows are redundant and whether S(q) exists depend on equalities between these
  numbers (two wheels on one axle share their x); independent symbols per wheel would
  make every axle generic and the rank analysis would disagree with the robot;
* with ``numeric=True`` every Python number becomes an exact rational (no symbols);
* SymPy expressions (symbols, ``sp.Integer(0)``, ``b/2``) are taken as they are: a caller
  who wants symbolic geometry shares the symbols that express the structure (see
  ``modeling.robots.drishti.description``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any, TypeAlias

import sympy as sp

from modeling.planar_robot import PlanarSupport
from modeling.robot_io import RobotFileError

Value: TypeAlias = float | sp.Expr
Point: TypeAlias = tuple[Value, Value]


class DescriptionError(RobotFileError):
    """A robot description that cannot describe a robot; the message names the field."""


@dataclass(frozen=True)
class BodySpec:
    """A planar rigid body: mass, yaw inertia about its own centre of mass, and the centre
    of mass in the body frame (x forward, y left)."""

    name: str
    mass: Value
    yaw_inertia: Value
    com: Point = (0.0, 0.0)


@dataclass(frozen=True)
class JointSpec:
    """A revolute hitch: ``parent_point`` (parent frame) and ``child_point`` (child frame)
    coincide. The child's yaw is a generalised coordinate."""

    parent: str
    child: str
    parent_point: Point
    child_point: Point = (0.0, 0.0)
    kind: str = "revolute"


@dataclass(frozen=True)
class WheelSpec:
    """A fixed standard wheel on ``body``: centre at ``position`` (body frame), axle along
    the body's y axis, so it rolls along the body's x axis; its angle is positive when it
    rolls forward. ``mass`` sits at the centre; ``diameter_inertia`` is about the vertical
    axis (turning with the body), ``spin_inertia`` about the axle."""

    name: str
    body: str
    position: Point
    radius: Value
    spin_inertia: Value
    diameter_inertia: Value = 0.0
    mass: Value = 0.0
    driven: bool = False


@dataclass(frozen=True)
class RobotDescription:
    """Bodies (the first is the root), joints and wheels; ``values`` holds the numbers of
    the parameter symbols (empty for a purely symbolic description). ``warnings``: the
    physics audit's findings on the file it was read from (``modeling.audit``; not part of
    the robot: ignored by equality and hashing, dropped by ``symbolize``). ``supports``:
    the file's ``[[support]]`` (``modeling.supports``; None: not stated, the default), in
    numbers: where it stands, not part of the derivation (dropped by ``symbolize``)."""

    name: str
    bodies: tuple[BodySpec, ...]
    joints: tuple[JointSpec, ...] = ()
    wheels: tuple[WheelSpec, ...] = ()
    values: Mapping[sp.Symbol, float] = field(default_factory=dict, hash=False)
    warnings: tuple[str, ...] = field(default=(), compare=False)
    supports: tuple[PlanarSupport, ...] | None = field(default=None, compare=False)

    @property
    def root(self) -> BodySpec:
        return self.bodies[0]

    def body(self, name: str) -> BodySpec:
        return next(b for b in self.bodies if b.name == name)


# ---------------------------------------------------------------------------------------
# Field tables: (name, kind) with kind "positive", "non-negative", "any", "point",
# "string" or "bool". Inertial fields become symbols in ``symbolize``; geometric ones exact.
# ---------------------------------------------------------------------------------------
BODY_FIELDS = {"name": "string", "mass": "positive", "yaw_inertia": "non-negative",
               "com": "point"}
JOINT_FIELDS = {"kind": "string", "parent": "string", "child": "string",
                "parent_point": "point", "child_point": "point"}
WHEEL_FIELDS = {"name": "string", "body": "string", "position": "point", "radius": "positive",
                "spin_inertia": "non-negative", "diameter_inertia": "non-negative",
                "mass": "non-negative", "driven": "bool"}
OPTIONAL = {"joint": {"kind"}}
SECTIONS = {"body": BODY_FIELDS, "joint": JOINT_FIELDS, "wheel": WHEEL_FIELDS}
GEOMETRIC_FIELDS = {"position", "parent_point", "child_point"}


def fail(where: str, message: str) -> DescriptionError:
    return DescriptionError(f"{where}: {message}")


def _is_number(value: Any) -> bool:
    return not isinstance(value, bool) and isinstance(value, int | float)


def check_value(where: str, label: str, kind: str, value: Any) -> None:
    """Sign checks for numbers (Python or SymPy); symbolic values are not checked."""
    if isinstance(value, sp.Basic):
        if not value.is_number:
            return
        x = float(value)
    elif _is_number(value):
        x = float(value)
    else:
        raise fail(where, f"field '{label}' must be a number, got {value!r}")
    if not math.isfinite(x):
        raise fail(where, f"field '{label}' must be finite, got {value!r}")
    if kind == "positive" and x <= 0:
        raise fail(where, f"field '{label}' must be positive, got {value!r}")
    if kind == "non-negative" and x < 0:
        raise fail(where, f"field '{label}' must be non-negative, got {value!r}")


def check_point(where: str, label: str, value: Any) -> None:
    if not isinstance(value, tuple | list) or len(value) != 2:
        raise fail(where, f"field '{label}' must be a pair [x, y] of numbers, got {value!r}")
    for axis, v in zip("xy", value, strict=True):
        check_value(where, f"{label}.{axis}", "any", v)


def validate(desc: RobotDescription, where: str = "<description>") -> None:
    """Raise DescriptionError naming the field if ``desc`` cannot describe a robot."""
    if not desc.name:
        raise fail(where, "field 'name' must be a non-empty string")
    if not desc.bodies:
        raise fail(where, "field 'body' must list at least one body (the first is the root)")
    seen: dict[str, str] = {}
    entries: list[tuple[str, Any, dict[str, str]]] = []
    entries += [(f"body[{i}]", b, BODY_FIELDS) for i, b in enumerate(desc.bodies)]
    entries += [(f"joint[{i}]", j, JOINT_FIELDS) for i, j in enumerate(desc.joints)]
    entries += [(f"wheel[{i}]", w, WHEEL_FIELDS) for i, w in enumerate(desc.wheels)]
    for label, entry, fields in entries:
        for key, kind in fields.items():
            value = getattr(entry, key)
            if kind == "point":
                check_point(where, f"{label}.{key}", value)
            elif kind == "string":
                if not isinstance(value, str) or not value:
                    raise fail(where, f"field '{label}.{key}' must be a non-empty string")
            elif kind == "bool":
                if not isinstance(value, bool):
                    raise fail(where, f"field '{label}.{key}' must be true or false")
            else:
                check_value(where, f"{label}.{key}", kind, value)
        if not label.startswith("joint"):
            if entry.name in seen:
                raise fail(where, f"field '{label}.name': duplicate name '{entry.name}' "
                            f"(already used by {seen[entry.name]}); bodies and wheels "
                            "share one namespace (it names the coordinates)")
            seen[entry.name] = label
    bodies = {b.name for b in desc.bodies}
    root = desc.root.name
    parent_of: dict[str, str] = {}
    for i, j in enumerate(desc.joints):
        if j.kind != "revolute":
            raise fail(where, f"field 'joint[{i}].kind' must be \"revolute\", got {j.kind!r}")
        for key in ("parent", "child"):
            if getattr(j, key) not in bodies:
                raise fail(where, f"field 'joint[{i}].{key}' names unknown body "
                            f"'{getattr(j, key)}'")
        if j.child == root:
            raise fail(where, f"field 'joint[{i}].child': the root body '{root}' (the first "
                        "body) cannot be a joint's child")
        if j.child in parent_of:
            raise fail(where, f"field 'joint[{i}].child': body '{j.child}' already has a "
                        f"parent ('{parent_of[j.child]}'); closed chains are not supported")
        parent_of[j.child] = j.parent
    for i, b in enumerate(desc.bodies[1:], start=1):
        chain, name = [b.name], b.name
        while name != root:
            if name not in parent_of:
                raise fail(where, f"field 'body[{i}]': body '{b.name}' is not connected to "
                            f"the root body '{root}' by joints")
            name = parent_of[name]
            if name in chain:
                raise fail(where, f"field 'body[{i}]': body '{b.name}' is on a closed "
                            "chain of joints")
            chain.append(name)
    for i, w in enumerate(desc.wheels):
        if w.body not in bodies:
            raise fail(where, f"field 'wheel[{i}].body' names unknown body '{w.body}'")


# ---------------------------------------------------------------------------------------
# Numbers → symbols
# ---------------------------------------------------------------------------------------
def _exact(value: Value) -> sp.Expr:
    # repr is the shortest decimal that round-trips, i.e. what the file says.
    return sp.Rational(repr(float(value))) if _is_number(value) else sp.sympify(value)


def symbolize(desc: RobotDescription, numeric: bool = False) -> RobotDescription:
    """``desc`` with Python numbers replaced by symbols (inertial fields, radii; values in
    ``values``) or exact rationals (geometry): see the module docstring. Idempotent.

    ``numeric=True`` makes every Python number an exact rational: a derivation for one
    robot's numbers, about twenty times faster for the trailer than one symbolic in its
    24 inertial parameters.
    """
    values: dict[sp.Symbol, float] = dict(desc.values)

    def param(value: Value, field_name: str, owner: str) -> sp.Expr:
        if not _is_number(value):
            return sp.sympify(value)
        if numeric:
            return _exact(value)
        symbol = sp.Symbol(f"{field_name}_{owner}", real=True)
        if symbol in values and values[symbol] != float(value):
            raise DescriptionError(f"symbol '{symbol}' would get two values")
        values[symbol] = float(value)
        return symbol

    def point(value: Point, field_name: str, owner: str) -> tuple[sp.Expr, sp.Expr]:
        if field_name in GEOMETRIC_FIELDS:
            return _exact(value[0]), _exact(value[1])
        return param(value[0], f"{field_name}_x", owner), param(value[1], f"{field_name}_y",
                                                                owner)

    bodies = tuple(
        replace(b, mass=param(b.mass, "mass", b.name),
                yaw_inertia=param(b.yaw_inertia, "yaw_inertia", b.name),
                com=point(b.com, "com", b.name))
        for b in desc.bodies
    )
    joints = tuple(
        replace(j, parent_point=point(j.parent_point, "parent_point", j.child),
                child_point=point(j.child_point, "child_point", j.child))
        for j in desc.joints
    )
    wheels = tuple(
        replace(w, position=point(w.position, "position", w.name),
                radius=param(w.radius, "radius", w.name),
                spin_inertia=param(w.spin_inertia, "spin_inertia", w.name),
                diameter_inertia=param(w.diameter_inertia, "diameter_inertia", w.name),
                mass=param(w.mass, "mass", w.name))
        for w in desc.wheels
    )
    return RobotDescription(desc.name, bodies, joints, wheels, values)
