"""Generalised coordinates and planar point kinematics of a robot description.

Coordinates, in this order:

* the root body's (x, y, θ): the world position of its body-frame origin and its yaw;
* one **absolute** yaw angle per child body (bodies in file order): the hitch's position
  constraint is holonomic and is eliminated by expressing each child's origin through the
  chain of hitch points, so only the angle is left. Absolute rather than relative angles
  because each body's kinetic energy and each wheel's constraints then involve only that
  body's own θ (½ I θ̇ᵢ² instead of ½ I (θ̇₀ + … + θ̇ᵢ)², e = (cos θᵢ, sin θᵢ) instead of a
  sum of angles), which keeps M, A and the trigonometric canonical forms small; the hitch
  angle is θ_child − θ_parent;
* one rolling angle per wheel: driven wheels first, in file order, then passive ones.

Velocities are the Jacobians of the world positions, d/dt p(q) = ∂p/∂q · q̇, so nothing
is hand-differentiated.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from modeling.description.schema import RobotDescription


@dataclass(frozen=True)
class Coordinates:
    """q, q̇, q̈ (plain real symbols) and where each body's yaw and wheel's angle sit."""

    names: tuple[str, ...]
    q: tuple[sp.Symbol, ...]
    qdot: tuple[sp.Symbol, ...]
    qddot: tuple[sp.Symbol, ...]
    body_angle: dict[str, int]
    wheel_angle: dict[str, int]


def _derivative_name(name: str, suffix: str) -> str:
    base, owner = name.split("_", 1)
    return f"{base}{suffix}_{owner}"


def coordinates(desc: RobotDescription) -> Coordinates:
    """The generalised coordinates of ``desc`` (see the module docstring)."""
    root = desc.root.name
    names = [f"x_{root}", f"y_{root}"]
    body_angle: dict[str, int] = {}
    for b in desc.bodies:
        body_angle[b.name] = len(names)
        names.append(f"theta_{b.name}")
    wheel_angle: dict[str, int] = {}
    for w in [w for w in desc.wheels if w.driven] + [w for w in desc.wheels if not w.driven]:
        wheel_angle[w.name] = len(names)
        names.append(f"theta_{w.name}")
    q = tuple(sp.Symbol(n, real=True) for n in names)
    qdot = tuple(sp.Symbol(_derivative_name(n, "dot"), real=True) for n in names)
    qddot = tuple(sp.Symbol(_derivative_name(n, "ddot"), real=True) for n in names)
    return Coordinates(tuple(names), q, qdot, qddot, body_angle, wheel_angle)


def driven_indices(desc: RobotDescription, coords: Coordinates) -> tuple[int, ...]:
    """Indices in q of the driven wheel angles, in file order."""
    return tuple(coords.wheel_angle[w.name] for w in desc.wheels if w.driven)


def rotation(angle: sp.Expr) -> sp.Matrix:
    return sp.Matrix([[sp.cos(angle), -sp.sin(angle)], [sp.sin(angle), sp.cos(angle)]])


def heading(angle: sp.Expr) -> tuple[sp.Matrix, sp.Matrix]:
    """e = (cos θ, sin θ), the body's x axis (rolling direction); n = (−sin θ, cos θ), its
    y axis (the wheel axle)."""
    return sp.Matrix([sp.cos(angle), sp.sin(angle)]), sp.Matrix([-sp.sin(angle), sp.cos(angle)])


@dataclass(frozen=True)
class Pose:
    """World position of a body frame's origin and the frame's yaw, as functions of q."""

    origin: sp.Matrix
    angle: sp.Symbol

    def point(self, local: tuple[sp.Expr, sp.Expr]) -> sp.Matrix:
        """World position of a body-frame point."""
        return self.origin + rotation(self.angle) * sp.Matrix(local)


def body_poses(desc: RobotDescription, coords: Coordinates) -> dict[str, Pose]:
    """Poses of all bodies, children placed so that their hitch points coincide:
    origin_child = parent.point(parent_point) − R(θ_child) child_point."""
    root = desc.root.name
    poses = {root: Pose(sp.Matrix(coords.q[:2]), coords.q[coords.body_angle[root]])}
    pending = list(desc.joints)
    while pending:
        ready = [j for j in pending if j.parent in poses]
        if not ready:  # validate() rules this out: the joints form a tree on the root
            raise ValueError(f"joints not connected to the root: {pending}")
        for j in ready:
            angle = coords.q[coords.body_angle[j.child]]
            hitch = poses[j.parent].point(j.parent_point)
            origin = hitch - rotation(angle) * sp.Matrix(j.child_point)
            poses[j.child] = Pose(origin, angle)
            pending.remove(j)
    return poses


def velocity(position: sp.Matrix, coords: Coordinates) -> sp.Matrix:
    """d/dt of a world position p(q): ∂p/∂q · q̇, expanded."""
    return (position.jacobian(coords.q) * sp.Matrix(coords.qdot)).applyfunc(sp.expand)
