"""An independent derivation of the WMR dynamics with sympy.physics.mechanics (Kane).

Nothing here comes from Drishti's ``model.py`` except the final comparison: the robot is built
from its bodies with ReferenceFrame/Point kinematics — a platform rigid body (mass m_P, yaw
inertia I_P about its centre of mass at (x_P, y_P) from the axle midpoint) and two wheel
rigid bodies (mass m_w, inertia I_w about the axle and I_m about a diameter) that spin
about the axle relative to the platform — and the three rolling conditions are imposed as
nonholonomic constraints on the velocities of material points: no sideways velocity of the
axle midpoint (6), and zero forward velocity of each wheel's contact point (7)–(8). The
motor torques act between platform and wheel. Kane's method with the wheel rates as
independent speeds then gives q̈ from a 5×5 linear system (the dynamical equations and the
differentiated constraints).

The comparison is with ``wmr.wmr_system(lateral_moment=True)`` evaluated at the lumped
values that ``wmr.lumped_relations(wmr.physical_bodies())`` assigns to the same physical
parameters, at N_STATES random states and torques for each of N_ROBOTS random robots
(x_P, y_P ≠ 0, so that K ≠ m d and K_lat ≠ 0). Tolerance: relative 1e-10, norm-wise
(measured: at most 1.2e-14).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
import sympy as sp
import sympy.physics.mechanics as me

from modeling.robots.drishti import model as wmr

RTOL = 1e-10
N_ROBOTS = 4
N_STATES = 20
SEED = 343

# Physical parameters of the Kane model (its own symbols, not wmr's).
PHYS_NAMES = ("m_P", "I_P", "x_P", "y_P", "m_w", "I_w", "I_m", "r", "b", "d")
PHYS = sp.symbols(PHYS_NAMES, real=True)
TAU = sp.symbols("tau_r tau_l", real=True)


class KaneWMR:
    """The Kane equations of the robot, lambdified: MM(q, p) q̈ = F(q, u, τ, p), and the
    velocity constraints C(q, p) u = 0."""

    def __init__(self) -> None:
        m_p, i_p, x_p, y_p, m_w, i_w, i_m, r, b, d = PHYS
        tau_r, tau_l = TAU
        coords = me.dynamicsymbols("x y theta theta_r theta_l")
        speeds = me.dynamicsymbols("u1:6")
        x, y, th, th_r, th_l = coords
        u1, u2, u3, u4, u5 = speeds

        n = me.ReferenceFrame("N")
        origin = me.Point("O")
        origin.set_vel(n, 0)
        body = n.orientnew("B", "Axis", [th, n.z])
        body.set_ang_vel(n, u3 * n.z)
        c = origin.locatenew("C", x * n.x + y * n.y)
        c.set_vel(n, u1 * n.x + u2 * n.y)
        axle = c.locatenew("A0", -d * body.x)
        axle.v2pt_theory(c, n, body)
        com = axle.locatenew("P", x_p * body.x + y_p * body.y)
        com.v2pt_theory(c, n, body)

        wheel_frames, wheel_bodies, contacts = [], [], []
        for side, angle, rate, sign in (("r", th_r, u4, -1), ("l", th_l, u5, 1)):
            frame = body.orientnew(f"W{side}", "Axis", [angle, body.y])
            frame.set_ang_vel(body, rate * body.y)
            centre = axle.locatenew(f"C{side}", sign * b / 2 * body.y)
            centre.v2pt_theory(c, n, body)
            contact = centre.locatenew(f"G{side}", -r * body.z)  # material point of the wheel
            contact.v2pt_theory(centre, n, frame)
            wheel_frames.append(frame)
            contacts.append(contact)
            wheel_bodies.append(
                me.RigidBody(f"wheel_{side}", centre, frame, m_w,
                             (me.inertia(frame, i_m, i_w, i_m), centre))
            )
        platform = me.RigidBody("platform", com, body, m_p, (me.inertia(body, 0, 0, i_p), com))

        constraints = [
            axle.vel(n).dot(body.y),  # (6): no side slip of the axle
            contacts[0].vel(n).dot(body.x),  # (7): right wheel rolls without slipping
            contacts[1].vel(n).dot(body.x),  # (8): left wheel
        ]
        loads = [
            (wheel_frames[0], tau_r * body.y),
            (wheel_frames[1], tau_l * body.y),
            (body, -(tau_r + tau_l) * body.y),  # reaction on the platform (stator)
        ]
        kane = me.KanesMethod(
            n,
            q_ind=list(coords),
            u_ind=[u4, u5],
            u_dependent=[u1, u2, u3],
            kd_eqs=[qi.diff(me.dynamicsymbols._t) - ui for qi, ui in zip(coords, speeds,
                                                                          strict=True)],
            velocity_constraints=constraints,
        )
        kane.kanes_equations([platform, *wheel_bodies], loads)

        qs = sp.symbols("q0:5", real=True)
        us = sp.symbols("u0:5", real=True)
        plain = dict(zip(coords, qs, strict=True)) | dict(zip(speeds, us, strict=True))
        mass = kane.mass_matrix.xreplace(plain)
        forcing = kane.forcing.xreplace(plain)
        assert not mass.has(me.dynamicsymbols._t) and not forcing.has(me.dynamicsymbols._t)
        con = sp.Matrix(constraints).xreplace(plain)
        con_matrix = con.jacobian(us)
        assert (con - con_matrix * sp.Matrix(us)).applyfunc(sp.expand) == sp.zeros(3, 1)

        # Kane orders the speeds (and so the columns of its mass matrix) as u_ind + u_dep.
        self.order = np.array([list(speeds).index(ui) for ui in kane.u])
        args = (qs, us, TAU, PHYS)
        self.mass: Callable[..., Any] = sp.lambdify(args, mass, "numpy", cse=True)
        self.forcing: Callable[..., Any] = sp.lambdify(args, forcing, "numpy", cse=True)
        self.constraints: Callable[..., Any] = sp.lambdify(args, con_matrix, "numpy", cse=True)

    def speeds_from_wheel_rates(self, q: np.ndarray, eta: np.ndarray, p: np.ndarray) -> np.ndarray:
        """Solve the velocity constraints for (ẋ, ẏ, θ̇) given the wheel rates."""
        cm = np.asarray(self.constraints(q, np.zeros(5), (0, 0), p), dtype=float)
        dep = np.linalg.solve(cm[:, :3], -cm[:, 3:] @ eta)
        return np.r_[dep, eta]

    def accelerations(self, q: np.ndarray, u: np.ndarray, tau: np.ndarray,
                      p: np.ndarray) -> np.ndarray:
        mm = np.asarray(self.mass(q, u, tau, p), dtype=float)
        f = np.asarray(self.forcing(q, u, tau, p), dtype=float).ravel()
        out = np.empty(5)
        out[self.order] = np.linalg.solve(mm, f)
        return out


@pytest.fixture(scope="module")
def kane() -> KaneWMR:
    return KaneWMR()


@pytest.fixture(scope="module")
def lumped_from_physical() -> Callable[[np.ndarray], np.ndarray]:
    """Physical parameter vector (PHYS_NAMES order) → wmr.PLANT_SYMBOLS values, through
    ``wmr.lumped_relations(wmr.physical_bodies())``."""
    rel = wmr.lumped_relations(wmr.physical_bodies())
    wmr_phys = (wmr.m_P, wmr.I_P, wmr.x_P, wmr.y_P, wmr.m_w, wmr.I_w, wmr.I_m, wmr.r, wmr.b,
                wmr.d)
    exprs = [rel.get(s, s) for s in wmr.PLANT_SYMBOLS]
    f = sp.lambdify([wmr_phys], exprs, "numpy")
    return lambda phys: np.asarray(f(phys), dtype=float)


def random_robot(rng: np.random.Generator) -> np.ndarray:
    return np.array([
        rng.uniform(10, 50),  # m_P
        rng.uniform(0.5, 5),  # I_P
        rng.uniform(-0.2, 0.2),  # x_P
        rng.uniform(-0.2, 0.2),  # y_P
        rng.uniform(0.5, 5),  # m_w
        rng.uniform(0.01, 0.2),  # I_w
        rng.uniform(0.01, 0.1),  # I_m
        rng.uniform(0.05, 0.2),  # r
        rng.uniform(0.2, 0.6),  # b
        rng.uniform(0.0, 0.3),  # d
    ])


ROBOTS = [random_robot(np.random.default_rng(SEED + i)) for i in range(N_ROBOTS)]


def rel(x: np.ndarray, ref: np.ndarray) -> float:
    scale = float(np.linalg.norm(ref))
    assert scale > 0
    return float(np.linalg.norm(np.ravel(x) - np.ravel(ref)) / scale)


@pytest.mark.parametrize("phys", ROBOTS, ids=[f"robot{i}" for i in range(N_ROBOTS)])
def test_kane_accelerations_match_lumped_model(
    kane: KaneWMR, lumped_from_physical: Callable[[np.ndarray], np.ndarray],
    lateral_model: Any, phys: np.ndarray,
) -> None:
    p = lumped_from_physical(phys)
    assert abs(p[3]) > 1e-3, "K_lat should be exercised"  # m_P y_P
    assert abs(p[2] - p[0] * p[7]) > 1e-3, "K should differ from m d"
    rng = np.random.default_rng(int(phys[0] * 1e6))
    worst_kin = worst_dyn = worst_min = 0.0
    for _ in range(N_STATES):
        q = np.r_[rng.uniform(-5, 5, 2), rng.uniform(-np.pi, np.pi), rng.uniform(-50, 50, 2)]
        eta = rng.uniform(-15, 15, 2)
        tau = rng.uniform(-10, 10, 2)
        u = kane.speeds_from_wheel_rates(q, eta, phys)
        # kinematics: the same velocities satisfy (6)–(8) of wmr, i.e. q̇ = S(q) η
        worst_kin = max(worst_kin, rel(lateral_model.qdot_on_manifold(q, eta, p), u))
        qdd_kane = kane.accelerations(q, u, tau, phys)
        qdd_wmr = lateral_model.qdd_red(q, u, tau=tau, p=p)
        worst_dyn = max(worst_dyn, rel(qdd_wmr, qdd_kane))
        worst_min = max(worst_min, rel(lateral_model.eta_dot(q, u, tau=tau, p=p), qdd_kane[3:]))
    assert max(worst_kin, worst_dyn, worst_min) < RTOL, (worst_kin, worst_dyn, worst_min)


def test_kane_model_sees_a_wrong_lumped_value(
    kane: KaneWMR, lumped_from_physical: Callable[[np.ndarray], np.ndarray],
    lateral_model: Any,
) -> None:
    """The comparison has teeth: perturbing K or K_lat by 1 % breaks the agreement."""
    phys = ROBOTS[0]
    p = lumped_from_physical(phys)
    rng = np.random.default_rng(1)
    q = np.r_[rng.uniform(-5, 5, 2), 0.4, 0.0, 0.0]
    eta = np.array([6.0, -2.0])
    tau = np.array([3.0, -1.0])
    u = kane.speeds_from_wheel_rates(q, eta, phys)
    qdd_kane = kane.accelerations(q, u, tau, phys)
    for index in (2, 3):  # K, K_lat
        wrong = p.copy()
        wrong[index] *= 1.01
        assert rel(lateral_model.qdd_red(q, u, tau=tau, p=wrong), qdd_kane) > 1e-6
