"""Numeric views of described robots for the tests (lambdified once per session).

Every function takes (q, qdot, qddot, tau, p) with p in the order of the system's
``parameters``; arguments an expression does not use are ignored. Parameter vectors come
from a (numeric) description through ``parameter_vector``, so a perturbed description
reuses the symbolic derivation of the original one.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import replace
from functools import cache
from typing import Any

import numpy as np
import sympy as sp

from modeling.description import (
    DescribedSystem,
    RobotDescription,
    description_system,
    packaged_description,
    symbolize,
)

NumFn = Callable[..., np.ndarray]


def rel(x: np.ndarray, ref: np.ndarray) -> float:
    """‖x − ref‖ / ‖ref‖ (norm-wise relative), refusing a vacuous zero reference."""
    x, ref = np.ravel(x), np.ravel(ref)
    scale = float(np.linalg.norm(ref))
    assert scale > 0, "reference is exactly zero: the comparison would be vacuous"
    return float(np.linalg.norm(x - ref) / scale)


class NumericDescribed:
    """Lambdified pieces of a DescribedSystem."""

    def __init__(self, system: DescribedSystem) -> None:
        s = system
        self.system = s
        self.n = len(s.q)
        self.k = len(s.independent)
        self.independent = list(s.independent)
        self.args = (s.q, s.qdot, s.qddot, s.inputs, s.parameters)
        self.M = self.numeric(s.mass_matrix)
        self.H = self.numeric(s.bias)
        self.A = self.numeric(s.constraint_matrix)
        self.B = self.numeric(s.input_matrix)
        self.S = self.numeric(s.null_space)
        self.Sdot_eta = self.numeric(s.null_space_rate)
        self.M_min = self.numeric(s.minimal_mass_matrix)
        self.H_min = self.numeric(s.minimal_bias)
        self.B_min = self.numeric(s.minimal_input_matrix)
        self.M_red = self.numeric(s.reduced_mass_matrix)
        self.H_red = self.numeric(s.reduced_bias)
        self.eta_dot = self.numeric(s.minimal_forward_dynamics(s.tau))
        self.qdd_red = self.numeric(s.reduced_forward_dynamics(s.tau))
        lhs, rhs = s.kkt_matrix()
        self.kkt_lhs = self.numeric(lhs)
        self.kkt_rhs = self.numeric(rhs)
        self.T = self.numeric(s.kinetic_energy)

    def numeric(self, expr: sp.Expr | sp.MatrixBase) -> NumFn:
        f = sp.lambdify(self.args, expr, "numpy", cse=True)
        n, k = self.n, self.k

        def call(q: Any, qd: Any = None, qdd: Any = None, tau: Any = None,
                 p: Any = None) -> np.ndarray:
            assert p is not None
            qd = np.zeros(n) if qd is None else qd
            qdd = np.zeros(n) if qdd is None else qdd
            tau = np.zeros(k) if tau is None else tau
            return np.asarray(f(q, qd, qdd, tau, p), dtype=float)

        return call

    def qdot_on_manifold(self, q: np.ndarray, eta: np.ndarray, p: np.ndarray) -> np.ndarray:
        return (self.S(q, p=p) @ eta).ravel()

    def kkt_solve(
        self, q: np.ndarray, qd: np.ndarray, tau: np.ndarray, p: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """(q̈, λ) from [[M, Aᵀ], [A, 0]] [q̈; λ] = [B τ − H; −Ȧ q̇]: only M, H, A, B of (9)."""
        lhs = self.kkt_lhs(q, qd, p=p)
        rhs = self.kkt_rhs(q, qd, p=p).ravel()
        rhs[: self.n] += (self.B(q, p=p) @ tau).ravel()
        sol = np.linalg.solve(lhs, rhs)
        return sol[: self.n], sol[self.n :]

    def states(
        self, p: np.ndarray, seed: int, count: int
    ) -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
        """(q, η, q̇ = S η, τ): positions ±5 m, every angle anywhere (hitch angles too:
        the equations do not care about jackknifing), driven rates ±15 rad/s, τ ±10 N m."""
        rng = np.random.default_rng(seed)
        for _ in range(count):
            q = np.r_[rng.uniform(-5, 5, 2), rng.uniform(-np.pi, np.pi, self.n - 2)]
            eta = rng.uniform(-15, 15, self.k)
            tau = rng.uniform(-10, 10, self.k)
            yield q, eta, self.qdot_on_manifold(q, eta, p), tau


def parameter_vector(system: DescribedSystem, desc: RobotDescription) -> np.ndarray:
    """The values of ``system.parameters`` for a numeric description with the same
    structure (matched by symbol name), so perturbed descriptions need no re-derivation."""
    values = {str(k): v for k, v in symbolize(desc).values.items()}
    return np.array([values[str(s)] for s in system.parameters])


@cache
def numeric_description(desc: RobotDescription, numeric: bool = False) -> NumericDescribed:
    return NumericDescribed(description_system(desc, numeric))


def trailer() -> RobotDescription:
    return packaged_description("trailer")


def perturbed(desc: RobotDescription, rng: np.random.Generator) -> RobotDescription:
    """Inertial fields and radii × U(0.7, 1.3), centres of mass moved sideways by up to
    5 cm; the geometry (the structure of the constraints) is kept."""

    def f(x: Any) -> float:
        return float(x) * float(rng.uniform(0.7, 1.3))

    bodies = tuple(replace(b, mass=f(b.mass), yaw_inertia=f(b.yaw_inertia),
                           com=(f(b.com[0]), float(rng.uniform(-0.05, 0.05))))
                   for b in desc.bodies)
    wheels = tuple(replace(w, radius=f(w.radius), spin_inertia=f(w.spin_inertia),
                           diameter_inertia=f(w.diameter_inertia), mass=f(w.mass))
                   for w in desc.wheels)
    return replace(desc, bodies=bodies, wheels=wheels)


def asymmetric() -> RobotDescription:
    """The trailer with its hitch 4 cm left of the axis and 3 cm into the cart, unequal
    half-tracks and cart wheel radii, and the centres of mass off the axes."""
    desc = trailer()
    positions = {"right": (0.02, -0.19), "left": (0.02, 0.224),
                 "cart_right": (-0.55, -0.17), "cart_left": (-0.55, 0.23)}
    radii = {"cart_right": 0.08, "cart_left": 0.075}
    wheels = tuple(replace(w, position=positions[w.name], radius=radii.get(w.name, w.radius))
                   for w in desc.wheels)
    bodies = (replace(desc.bodies[0], com=(0.05, 0.02)),
              replace(desc.bodies[1], com=(-0.45, -0.03)))
    joints = (replace(desc.joints[0], parent_point=(-0.3, 0.04), child_point=(0.03, -0.02)),)
    return replace(desc, name="asymmetric", bodies=bodies, joints=joints, wheels=wheels)
