"""The robots generated through staged quantities (``modeling.staged``: the tractor with
two and with three trailers) against routes that share nothing with the staging.

* KKT: the saddle-point solve of (9), [[M, Aᵀ], [A, 0]] [q̈; λ] = [Bτ − H; −Ȧq̇], with M, H,
  A, B of the description in its physical numbers (no base parameters, no null space, no
  minimal form), at consistent states whose dependent velocities solve A q̇ = 0 numerically;
* Kane: ``sympy.physics.mechanics`` rebuilt from the description's fields
  (tests/derivation/test_description_kane.py), the same states;
* the generated forward dynamics (NumPy; C = NumPy is tests/generated/test_any_robot_pipeline.py)
  agrees with both to 1e-10, and the staged M̄ is positive definite at every state.
"""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np
import pytest
import sympy as sp
from description_numeric import rel
from test_description_kane import KaneRobot, inertial_values

from modeling.description import description_system, packaged_description
from runtime.bindings.generated import load_robot_code

ROBOTS = ("trailer2", "trailer3")
N_STATES = 30
RTOL = 1e-10


@cache
def kkt(robot: str) -> tuple[Any, Any, Any, Any, Any, tuple[int, ...]]:
    """Lambdified M, H, A, B and Ȧq̇ of the description in its own numbers."""
    s = description_system(packaged_description(robot), numeric=True)
    args = (s.q, s.qdot)

    def f(expr: sp.MatrixBase) -> Any:
        return sp.lambdify(args, expr, "numpy", cse=True)

    return (f(s.mass_matrix), f(s.bias), f(s.constraint_matrix), f(s.input_matrix),
            f(s.constraint_rate_term), tuple(s.independent))


def states(robot: str, seed: int) -> list[tuple[np.ndarray, ...]]:
    """(q, q̇, τ): q̇'s independent rows random, the others from A(q) q̇ = 0 (a solve)."""
    _, _, a_of, _, _, independent = kkt(robot)
    rng = np.random.default_rng(seed)
    out = []
    code = load_robot_code(robot)
    for _ in range(N_STATES):
        q = np.r_[rng.uniform(-5, 5, 2), rng.uniform(-np.pi, np.pi, code.nq - 2)]
        a = np.asarray(a_of(q, np.zeros(code.nq)), dtype=float)
        dependent = [i for i in range(code.nq) if i not in independent]
        qdot = np.zeros(code.nq)
        qdot[list(independent)] = rng.uniform(-15, 15, len(independent))
        qdot[dependent] = np.linalg.solve(a[:, dependent], -a[:, list(independent)]
                                          @ qdot[list(independent)])
        out.append((q, qdot, rng.uniform(-10, 10, code.nu)))
    return out


def kkt_accelerations(robot: str, q: np.ndarray, qdot: np.ndarray,
                      tau: np.ndarray) -> np.ndarray:
    m_of, h_of, a_of, b_of, rate_of, _ = kkt(robot)
    m = np.asarray(m_of(q, qdot), dtype=float)
    a = np.asarray(a_of(q, qdot), dtype=float)
    n, k = m.shape[0], a.shape[0]
    lhs = np.block([[m, a.T], [a, np.zeros((k, k))]])
    rhs = np.r_[np.asarray(b_of(q, qdot), dtype=float) @ tau
                - np.ravel(h_of(q, qdot)), -np.ravel(rate_of(q, qdot))]
    return np.linalg.solve(lhs, rhs)[:n]


@pytest.mark.parametrize("robot", ROBOTS)
def test_generated_forward_dynamics_equals_kkt_and_kane(robot: str) -> None:
    code = load_robot_code(robot)
    desc = packaged_description(robot)
    kane = KaneRobot(desc)
    p_kane = inertial_values(desc)
    worst_kkt = worst_kane = worst_route = 0.0
    for q, qdot, tau in states(robot, seed=11):
        qdd = code.model.forward_dynamics(q, qdot, tau, code.params)
        reference = kkt_accelerations(robot, q, qdot, tau)
        by_kane = kane.accelerations(q, qdot, tau, p_kane)
        worst_kkt = max(worst_kkt, rel(qdd, reference))
        worst_kane = max(worst_kane, rel(qdd, by_kane))
        worst_route = max(worst_route, rel(by_kane, reference))  # the two references agree
        mbar = np.asarray(code.model.minimal_mass_matrix(q, code.params)).reshape(2, 2)
        assert np.all(np.linalg.eigvalsh(mbar) > 0)
    assert worst_route < RTOL, worst_route
    assert worst_kkt < RTOL, worst_kkt
    assert worst_kane < RTOL, worst_kane


@pytest.mark.parametrize("robot", ROBOTS)
def test_comparison_has_teeth(robot: str) -> None:
    """A 1 % heavier last cart in the generated model's parameters (its mass-like base
    parameters scaled) is seen by the KKT comparison: the tolerance is not vacuous."""
    code = load_robot_code(robot)
    last = f"cart{robot[-1]}"
    heavier = {k: v * 1.01 if k.endswith(last) or k.endswith(f"{last}_x_tractor") else v
               for k, v in code.params.items()}
    assert heavier != code.params
    worst = max(rel(code.model.forward_dynamics(q, qdot, tau, heavier),
                    kkt_accelerations(robot, q, qdot, tau))
                for q, qdot, tau in states(robot, seed=12))
    assert worst > 1e3 * RTOL, worst
