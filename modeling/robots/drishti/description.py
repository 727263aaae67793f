"""Drishti, the robot of Roy et al. (2017), as a description built from the paper's lumped
parameters (m, I, K, I_w, r, b, d).

One platform body of mass m whose centre of mass sits K/m behind the reference point C
(the body frame's origin, a distance d ahead of the axle midpoint), with yaw inertia
I − K²/m about that centre of mass (parallel axis: about C it is then I), and two massless
wheels with spin inertia I_w and no diameter inertia at (−d, −b/2) (right) and (−d, b/2)
(left). Its kinetic energy is exactly ``model.lumped_kinetic_energy()``:
½ m |v_C − (K/m) θ̇ n|² + ½ (I − K²/m) θ̇² = ½ m |v_C|² + ½ I θ̇² + K θ̇ (ẋ sin θ − ẏ cos θ).

With the default arguments the description is in :mod:`modeling.robots.drishti.model`'s
symbols, so the two derivations can be compared symbolically after renaming the
coordinates (``wmr_renaming``). ``tests/robots/drishti_bodies.toml`` is this description
at the paper's numbers, written as a robot file.
"""

from __future__ import annotations

import sympy as sp

from modeling.description.kinematics import Coordinates
from modeling.description.schema import BodySpec, RobotDescription, Value, WheelSpec
from modeling.lagrange import ConstrainedSystem
from modeling.robots.drishti import model as wmr


def drishti_from_lumped(
    m: Value = wmr.m,
    I: Value = wmr.I_z,
    K: Value = wmr.K,
    Iw: Value = wmr.I_w,
    r: Value = wmr.r,
    b: Value = wmr.b,
    d: Value = wmr.d,
) -> RobotDescription:
    """Drishti as one body and two wheels (see the module docstring). Symbolic arguments
    are used as they are; numbers follow ``schema.symbolize``'s rule."""
    zero: Value
    if all(isinstance(v, sp.Basic) for v in (m, I, K)):
        com_x: Value = -K / m
        yaw_inertia: Value = I - K**2 / m
        zero = sp.S.Zero  # structurally massless wheels: an exact zero, not a parameter
    else:  # numbers, as drishti_bodies.toml writes them
        com_x, yaw_inertia = -float(K) / float(m), float(I) - float(K) ** 2 / float(m)
        zero = 0.0
    half_track = b / 2
    platform = BodySpec("platform", mass=m, yaw_inertia=yaw_inertia, com=(com_x, zero))
    wheels = tuple(
        WheelSpec(name, "platform", position=(-d, side * half_track), radius=r,
                  spin_inertia=Iw, diameter_inertia=zero, mass=zero, driven=True)
        for name, side in (("right", -1), ("left", 1))
    )
    return RobotDescription("drishti", (platform,), (), wheels)


def wmr_renaming(system: ConstrainedSystem | Coordinates) -> dict[sp.Symbol, sp.Symbol]:
    """The description's q, q̇, q̈ → the model's (x_c, y_c, θ, θ_r, θ_l) ones."""
    pairs = zip((*system.q, *system.qdot, *system.qddot), (*wmr.q, *wmr.qdot, *wmr.qddot),
                strict=True)
    return dict(pairs)
