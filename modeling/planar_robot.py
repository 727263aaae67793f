"""A robot's physical layout in numbers: planar bodies, hitches and wheels, no SymPy.

What a physics engine needs to build the robot (``modeling.mjcf_export``): every body's
mass, yaw inertia about its own centre of mass and centre of mass; every revolute hitch;
every wheel's centre, radius, spin and diameter inertia and mass. It is the numeric
image of a description (``modeling.description``: :func:`from_description` takes one read
from a ``[[body]]`` file, floats not yet symbolised) or of the paper's lumped format
(:func:`from_lumped`: one platform and two massless wheels, as
``modeling.robots.drishti.description`` builds it symbolically). The generated ``robot.py``
of a bodies-and-wheels robot carries it as ``LAYOUT`` (:meth:`PlanarRobot.to_data`), so
the runtime builds an engine's robot from generated code without SymPy.

The coordinates q of the derived model follow from it as ``modeling.description``
orders them: the root's (x, y, θ), each further body's absolute yaw in body order, then
the wheels' angles, driven wheels first in file order, then passive ones
(:meth:`PlanarRobot.coordinate_order`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

Point = tuple[float, float]


@dataclass(frozen=True)
class PlanarBody:
    """A rigid body: mass (kg), yaw inertia about its own centre of mass (kg m²) and the
    centre of mass in the body frame (m; x forward, y left)."""

    name: str
    mass: float
    yaw_inertia: float
    com: Point


@dataclass(frozen=True)
class PlanarJoint:
    """A revolute hitch: ``parent_point`` (parent frame) and ``child_point`` (child frame)
    coincide."""

    parent: str
    child: str
    parent_point: Point
    child_point: Point


@dataclass(frozen=True)
class PlanarWheel:
    """A fixed standard wheel on ``body``: centre ``position`` (body frame), axle along the
    body's y axis; ``spin_inertia`` about the axle (a motor's reflected rotor inertia
    included), ``diameter_inertia`` about the vertical, ``mass`` at the centre."""

    name: str
    body: str
    position: Point
    radius: float
    spin_inertia: float
    diameter_inertia: float
    mass: float
    driven: bool


@dataclass(frozen=True)
class PlanarSupport:
    """A frictionless support (a caster or skid: it carries a normal load, no traction):
    a sphere of ``radius`` on ``body`` touching the ground under ``position`` (body
    frame). A robot file's ``[[support]]`` (``modeling.supports``)."""

    name: str
    body: str
    position: Point
    radius: float

    def to_data(self) -> list[Any]:
        return [self.name, self.body, list(self.position), self.radius]

    @classmethod
    def from_data(cls, data: Any) -> PlanarSupport:
        name, body, (x, y), radius = data
        return cls(str(name), str(body), (float(x), float(y)), float(radius))


@dataclass(frozen=True)
class PlanarRobot:
    """Bodies (the first is the root), hitches and wheels, in numbers; ``supports``: the
    robot file's stated supports (None: not stated, ``modeling.supports.default_supports``
    derives them; ``()``: stated as none)."""

    name: str
    bodies: tuple[PlanarBody, ...]
    joints: tuple[PlanarJoint, ...]
    wheels: tuple[PlanarWheel, ...]
    supports: tuple[PlanarSupport, ...] | None = None

    @property
    def root(self) -> PlanarBody:
        return self.bodies[0]

    def joint_of(self, child: str) -> PlanarJoint:
        return next(j for j in self.joints if j.child == child)

    def ordered_wheels(self) -> tuple[PlanarWheel, ...]:
        """Driven wheels in file order, then passive ones (the order of their angles in q)."""
        return (tuple(w for w in self.wheels if w.driven)
                + tuple(w for w in self.wheels if not w.driven))

    def coordinate_order(self) -> tuple[str, ...]:
        """What each entry of q is: ``x``, ``y``, then ``yaw:<body>`` for every body (root
        first) and ``wheel:<name>`` for every wheel in :meth:`ordered_wheels` order."""
        return ("x", "y", *(f"yaw:{b.name}" for b in self.bodies),
                *(f"wheel:{w.name}" for w in self.ordered_wheels()))

    def total_mass(self) -> float:
        return sum(b.mass for b in self.bodies) + sum(w.mass for w in self.wheels)

    def to_data(self) -> dict[str, Any]:
        """Plain data (str, float, bool, lists) for a generated ``robot.py``: bodies,
        hitches and wheels (its ``LAYOUT``; the supports are its ``SUPPORTS``, for every
        kind of robot file)."""
        return {
            "name": self.name,
            "bodies": [[b.name, b.mass, b.yaw_inertia, list(b.com)] for b in self.bodies],
            "joints": [[j.parent, j.child, list(j.parent_point), list(j.child_point)]
                       for j in self.joints],
            "wheels": [[w.name, w.body, list(w.position), w.radius, w.spin_inertia,
                        w.diameter_inertia, w.mass, w.driven] for w in self.wheels],
        }

    @classmethod
    def from_data(cls, data: Mapping[str, Any]) -> PlanarRobot:
        """The inverse of :meth:`to_data`."""
        def pt(v: Any) -> Point:
            return float(v[0]), float(v[1])

        return cls(
            str(data["name"]),
            tuple(PlanarBody(n, float(m), float(i), pt(c)) for n, m, i, c in data["bodies"]),
            tuple(PlanarJoint(p, c, pt(pp), pt(cp)) for p, c, pp, cp in data["joints"]),
            tuple(PlanarWheel(n, b, pt(pos), float(r), float(s), float(d), float(m), bool(dr))
                  for n, b, pos, r, s, d, m, dr in data["wheels"]),
        )


def body_origins(robot: PlanarRobot) -> dict[str, Point]:
    """Each body frame's origin in the root frame with every hitch straight."""
    out: dict[str, Point] = {robot.root.name: (0.0, 0.0)}
    pending = list(robot.joints)
    while pending:
        for j in list(pending):
            if j.parent in out:
                px, py = out[j.parent]
                out[j.child] = (px + j.parent_point[0] - j.child_point[0],
                                py + j.parent_point[1] - j.child_point[1])
                pending.remove(j)
    return out


LUMPED_KEYS = ("m", "I", "K", "Iw", "r", "b", "d")


def from_lumped(name: str, params: Mapping[str, float],
                supports: tuple[PlanarSupport, ...] | None = None) -> PlanarRobot:
    """The paper's differential drive from its lumped parameters (m, I, K, I_w, r, b, d and
    optionally the lateral first moment K_lat): one platform of mass m whose centre of mass
    is K/m behind and K_lat/m left of C (the body frame's origin, d ahead of the axle
    midpoint), yaw inertia I − (K² + K_lat²)/m about it (I is about C), and two massless
    wheels of spin inertia I_w at (−d, ∓b/2), right first. Its kinetic energy is the
    lumped one, T = ½ m |v_C|² + ½ I θ̇² + K θ̇ (ẋ sin θ − ẏ cos θ) − K_lat θ̇ (ẋ cos θ +
    ẏ sin θ) plus the wheels' spin (``modeling.robots.drishti.model``). ``ValueError``
    naming the parameter if one is missing or not physical."""
    missing = [k for k in LUMPED_KEYS if k not in params]
    if missing:
        raise ValueError(f"robot '{name}': lumped parameter '{missing[0]}' missing")
    p = {k: float(v) for k, v in params.items()}
    m, k_lon, k_lat = p["m"], p["K"], p.get("K_lat", 0.0)
    yaw = p["I"] - (k_lon**2 + k_lat**2) / m
    if m <= 0 or yaw <= 0:
        raise ValueError(f"robot '{name}': m = {m:g} and I = {p['I']:g} leave the platform "
                         f"a yaw inertia of {yaw:g} kg m^2 about its centre of mass (needs > 0)")
    platform = PlanarBody("platform", m, yaw, (-k_lon / m, k_lat / m))
    wheels = tuple(
        PlanarWheel(side, "platform", (-p["d"], sign * p["b"] / 2), p["r"], p["Iw"], 0.0, 0.0,
                    True)
        for side, sign in (("right", -1.0), ("left", 1.0))
    )
    return PlanarRobot(name, (platform,), (), wheels, supports)


def from_description(desc: Any) -> PlanarRobot:
    """A ``modeling.description.RobotDescription`` read from a file (its values Python
    numbers, not yet symbolised) in numbers."""
    def num(v: Any, label: str) -> float:
        x = float(v)
        if not math.isfinite(x):
            raise ValueError(f"robot '{desc.name}': {label} is not a finite number")
        return x

    def pt(v: Any, label: str) -> Point:
        return num(v[0], label), num(v[1], label)

    return PlanarRobot(
        desc.name,
        tuple(PlanarBody(b.name, num(b.mass, "mass"), num(b.yaw_inertia, "yaw_inertia"),
                         pt(b.com, "com")) for b in desc.bodies),
        tuple(PlanarJoint(j.parent, j.child, pt(j.parent_point, "parent_point"),
                          pt(j.child_point, "child_point")) for j in desc.joints),
        tuple(PlanarWheel(w.name, w.body, pt(w.position, "position"), num(w.radius, "radius"),
                          num(w.spin_inertia, "spin_inertia"),
                          num(w.diameter_inertia, "diameter_inertia"), num(w.mass, "mass"),
                          bool(w.driven)) for w in desc.wheels),
        desc.supports,
    )
