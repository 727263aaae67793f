"""An independent derivation of a described robot with sympy.physics.mechanics (Kane).

Nothing here comes from ``modeling.description``'s derivation: the description's numbers
are read field by field, and the robot is rebuilt with ReferenceFrame/Point kinematics —
each body a RigidBody in its own frame (the children oriented absolutely, their origin
placed through the hitch with v2pt_theory), each wheel a RigidBody in a frame spinning
about its body's y axis, with the inertia tensor (I_d, I_s, I_d). Nonholonomic
constraints are imposed on material points: zero forward velocity of each wheel's contact
point (rolling, (7)–(8)) and no sideways velocity of the first wheel's centre on each body
(the no-side-slip row (6); the other wheels on that axle would repeat it). The motor
torques act between wheel and body. KanesMethod with the driven wheel rates as independent
speeds and all other rates as ``u_dependent`` then gives q̈ from its mass matrix and forcing
(the dynamical equations stacked with the differentiated constraints).

Compared with the description route's ``reduced_forward_dynamics`` (q̈) and
``minimal_forward_dynamics`` (η̇) at N_STATES random consistent states for the trailer's
numbers, perturbed numbers and an asymmetric geometry: relative 1e-10, norm-wise.
The Kane model is symbolic in its own inertial parameters (geometry as exact numbers), so
perturbed numbers reuse one derivation on each side.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from functools import cache
from typing import Any

import numpy as np
import pytest
import sympy as sp
import sympy.physics.mechanics as me
from description_numeric import (
    asymmetric,
    numeric_description,
    parameter_vector,
    perturbed,
    rel,
    trailer,
)

from modeling.description import RobotDescription

RTOL = 1e-10
N_STATES = 25
SEED = 2017


def exact(x: Any) -> sp.Rational:
    return sp.Rational(repr(float(x)))


def inertial_values(desc: RobotDescription) -> np.ndarray:
    """Per body (m, I, x_g, y_g), then per wheel in file order (m, I_s, I_d, r)."""
    out: list[float] = []
    for b in desc.bodies:
        out += [b.mass, b.yaw_inertia, b.com[0], b.com[1]]
    for w in desc.wheels:
        out += [w.mass, w.spin_inertia, w.diameter_inertia, w.radius]
    return np.array(out, dtype=float)


class KaneRobot:
    """Kane's equations of a described robot: MM(q, p) u̇ = F(q, u, τ, p) with u = q̇."""

    def __init__(self, desc: RobotDescription) -> None:
        t = me.dynamicsymbols._t
        names = [b.name for b in desc.bodies]
        driven = [w for w in desc.wheels if w.driven]
        order = driven + [w for w in desc.wheels if not w.driven]  # coordinate order
        coords = me.dynamicsymbols(f"x y {' '.join('th_' + n for n in names)} "
                                   f"{' '.join('phi_' + w.name for w in order)}")
        speeds = me.dynamicsymbols(f"u0:{len(coords)}")
        params = sp.symbols(f"p0:{4 * len(desc.bodies) + 4 * len(desc.wheels)}", real=True)
        taus = sp.symbols(f"tau0:{len(driven)}", real=True)
        index = {w.name: 2 + len(names) + i for i, w in enumerate(order)}

        n_frame = me.ReferenceFrame("N")
        origin = me.Point("O")
        origin.set_vel(n_frame, 0)
        frames, origins = {}, {}
        root = names[0]
        frames[root] = n_frame.orientnew(root, "Axis", [coords[2], n_frame.z])
        frames[root].set_ang_vel(n_frame, speeds[2] * n_frame.z)
        origins[root] = origin.locatenew(f"O_{root}", coords[0] * n_frame.x
                                         + coords[1] * n_frame.y)
        origins[root].set_vel(n_frame, speeds[0] * n_frame.x + speeds[1] * n_frame.y)
        pending = list(desc.joints)
        while pending:
            j = next(j for j in pending if j.parent in frames)
            pending.remove(j)
            k = names.index(j.child)
            parent = frames[j.parent]
            frame = n_frame.orientnew(j.child, "Axis", [coords[2 + k], n_frame.z])
            frame.set_ang_vel(n_frame, speeds[2 + k] * n_frame.z)
            hitch = origins[j.parent].locatenew(
                f"H_{j.child}", exact(j.parent_point[0]) * parent.x
                + exact(j.parent_point[1]) * parent.y)
            hitch.v2pt_theory(origins[j.parent], n_frame, parent)
            child_origin = hitch.locatenew(
                f"O_{j.child}", -exact(j.child_point[0]) * frame.x
                - exact(j.child_point[1]) * frame.y)
            child_origin.v2pt_theory(hitch, n_frame, frame)
            frames[j.child], origins[j.child] = frame, child_origin

        bodies: list[Any] = []
        for i, b in enumerate(desc.bodies):
            m, inertia, xg, yg = params[4 * i: 4 * i + 4]
            frame = frames[b.name]
            com = origins[b.name].locatenew(f"G_{b.name}", xg * frame.x + yg * frame.y)
            com.v2pt_theory(origins[b.name], n_frame, frame)
            bodies.append(me.RigidBody(b.name, com, frame, m,
                                       (me.inertia(frame, 0, 0, inertia), com)))
        constraints: list[Any] = []
        side_slip: dict[str, Any] = {}
        loads: list[Any] = []
        base = 4 * len(desc.bodies)
        for i, w in enumerate(desc.wheels):
            m, spin, diameter, radius = params[base + 4 * i: base + 4 * i + 4]
            body = frames[w.body]
            k = index[w.name]
            wheel_frame = body.orientnew(f"W_{w.name}", "Axis", [coords[k], body.y])
            wheel_frame.set_ang_vel(body, speeds[k] * body.y)
            centre = origins[w.body].locatenew(
                f"C_{w.name}", exact(w.position[0]) * body.x + exact(w.position[1]) * body.y)
            centre.v2pt_theory(origins[w.body], n_frame, body)
            contact = centre.locatenew(f"P_{w.name}", -radius * n_frame.z)  # material point
            contact.v2pt_theory(centre, n_frame, wheel_frame)
            bodies.append(me.RigidBody(w.name, centre, wheel_frame, m,
                                       (me.inertia(wheel_frame, diameter, spin, diameter),
                                        centre)))
            constraints.append(contact.vel(n_frame).dot(body.x))
            side_slip.setdefault(w.body, centre.vel(n_frame).dot(body.y))
            if w.driven:
                torque = taus[driven.index(w)]
                loads += [(wheel_frame, torque * body.y), (body, -torque * body.y)]
        constraints = list(side_slip.values()) + constraints

        ind = [speeds[index[w.name]] for w in driven]
        dep = [u for u in speeds if u not in ind]
        kane = me.KanesMethod(
            n_frame, q_ind=list(coords), u_ind=ind, u_dependent=dep,
            kd_eqs=[q.diff(t) - u for q, u in zip(coords, speeds, strict=True)],
            velocity_constraints=constraints)
        kane.kanes_equations(bodies, loads)

        qs = sp.symbols(f"q0:{len(coords)}", real=True)
        us = sp.symbols(f"v0:{len(coords)}", real=True)
        plain = dict(zip(coords, qs, strict=True)) | dict(zip(speeds, us, strict=True))
        mass, forcing = kane.mass_matrix.xreplace(plain), kane.forcing.xreplace(plain)
        assert not mass.has(t) and not forcing.has(t)
        args = (qs, us, taus, params)
        self.order = np.array([list(speeds).index(u) for u in kane.u])
        self.n = len(coords)
        self.mass: Callable[..., Any] = sp.lambdify(args, mass, "numpy", cse=True)
        self.forcing: Callable[..., Any] = sp.lambdify(args, forcing, "numpy", cse=True)
        con = sp.Matrix(constraints).xreplace(plain).jacobian(us)
        self.constraints: Callable[..., Any] = sp.lambdify(args, con, "numpy", cse=True)
        self.n_taus = len(taus)

    def accelerations(self, q: np.ndarray, u: np.ndarray, tau: np.ndarray,
                      p: np.ndarray) -> np.ndarray:
        mm = np.asarray(self.mass(q, u, tau, p), dtype=float)
        f = np.asarray(self.forcing(q, u, tau, p), dtype=float).ravel()
        out = np.empty(self.n)
        out[self.order] = np.linalg.solve(mm, f)
        return out

    def constraint_residual(self, q: np.ndarray, u: np.ndarray, p: np.ndarray) -> float:
        c = np.asarray(self.constraints(q, u, np.zeros(self.n_taus), p), dtype=float)
        return float(np.linalg.norm(c @ u) / np.linalg.norm(u))


@cache
def kane_model(desc: RobotDescription) -> KaneRobot:
    return KaneRobot(desc)


def geometry_key(desc: RobotDescription) -> RobotDescription:
    """The description with its inertial numbers zeroed: Kane models are per geometry."""
    return replace(desc, bodies=tuple(replace(b, mass=1.0, yaw_inertia=1.0, com=(0.0, 0.0))
                                      for b in desc.bodies),
                   wheels=tuple(replace(w, mass=0.0, spin_inertia=1.0, diameter_inertia=0.0,
                                        radius=1.0) for w in desc.wheels))


def kane_cases() -> list[tuple[str, RobotDescription, bool]]:
    rng = np.random.default_rng(SEED)
    return [("file", trailer(), False),
            ("perturbed0", perturbed(trailer(), rng), False),
            ("perturbed1", perturbed(trailer(), rng), False),
            ("asymmetric", asymmetric(), True)]


CASES = kane_cases()


def compare(desc: RobotDescription, numeric: bool, p_kane: np.ndarray,
            seed: int) -> dict[str, float]:
    if numeric:
        model, p = numeric_description(desc, True), np.zeros(0)
    else:
        model = numeric_description(trailer())
        p = parameter_vector(model.system, desc)
    kane = kane_model(geometry_key(desc))
    ind = model.independent
    worst = {"kinematics": 0.0, "qdd": 0.0, "eta_dot": 0.0}
    for q, _, qd, tau in model.states(p, seed=seed, count=N_STATES):
        worst["kinematics"] = max(worst["kinematics"], kane.constraint_residual(q, qd, p_kane))
        qdd_kane = kane.accelerations(q, qd, tau, p_kane)
        worst["qdd"] = max(worst["qdd"], rel(model.qdd_red(q, qd, tau=tau, p=p), qdd_kane))
        worst["eta_dot"] = max(worst["eta_dot"],
                               rel(model.eta_dot(q, qd, tau=tau, p=p), qdd_kane[ind]))
    return worst


@pytest.mark.parametrize(("desc", "numeric"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_kane_matches_description_route(desc: RobotDescription, numeric: bool) -> None:
    worst = compare(desc, numeric, inertial_values(desc), seed=SEED)
    assert max(worst.values()) < RTOL, worst


@pytest.mark.parametrize("field", ["cart_com_y", "cart_spin", "tractor_inertia"])
def test_kane_comparison_has_teeth(field: str) -> None:
    """A 1 % (or 1 cm) error in one inertial number of the Kane model breaks agreement."""
    p = inertial_values(trailer())
    wrong = p.copy()
    position = {"cart_com_y": 7, "cart_spin": 8 + 4 * 2 + 1, "tractor_inertia": 1}[field]
    wrong[position] = wrong[position] * 1.01 if wrong[position] else 0.01
    worst = compare(trailer(), False, wrong, seed=SEED)
    assert worst["kinematics"] < RTOL
    assert worst["qdd"] > 1e-6, worst
