"""The chain-ordered S, Ṡ η, M S and M Ṡ η + H of a hitch chain (``modeling.chain_inertia``,
``modeling.chain_kinematics``, issue 51) against the dense route they replace, for every
staged robot.

* the composite-body structure is found in each robot's own M and H (in its base
  parameters): not finding it would silently keep the O(n²) products;
* M v + H(q̇) in chain order equals the dense M v + H of (9) at random states, columns and
  parameters, in the absolute yaws and in the root body's frame;
* S(q) and Ṡ η solved body by body (``modeling.chain_kinematics``) and the staged
  M̄ = Sᵀ M S and H̄ = Sᵀ(M Ṡ η + H) the model functions, the contact forces and the TDROC
  step read equal the dense route's (``chain_ordered=False``: A's block solve, the slopes
  of S, the dense products) to 1e-12.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from functools import cache
from typing import Any

import numpy as np
import pytest
import sympy as sp

from modeling.description import packaged_description
from modeling.robot_model import RobotModel, described_model
from modeling.staged import Stage

ROBOTS = ("trailer", "trailer2", "trailer3", "train5")
N_STATES = 8
TOL = 1e-12


@cache
def model(robot: str) -> RobotModel:
    return described_model(packaged_description(robot))


def compiled(definitions: Sequence[tuple[sp.Symbol, sp.Expr]], outputs: Sequence[sp.Expr],
             inputs: Sequence[sp.Symbol]) -> Callable[..., list[float]]:
    """A Python function evaluating ``definitions`` in order, then ``outputs``: a staged
    evaluation at float inputs (lambdify of one expression would multiply it out)."""
    names = {s: f"v{k}" for k, s in enumerate([*inputs, *(d for d, _ in definitions)])}

    def code(e: sp.Expr) -> str:
        return sp.pycode(e.xreplace({s: sp.Symbol(n) for s, n in names.items()}),
                         fully_qualified_modules=True)

    lines = [f"def f({', '.join(names[s] for s in inputs)}):"]
    lines += [f"    {names[d]} = {code(e)}" for d, e in definitions]
    lines.append(f"    return [{', '.join(code(sp.sympify(o)) for o in outputs)}]")
    scope: dict[str, Any] = {"math": math}
    exec("\n".join(lines), scope)  # code printed from our own definitions
    return scope["f"]  # type: ignore[no-any-return]


def draws(m: RobotModel, inputs: Sequence[sp.Symbol], seed: int) -> list[list[float]]:
    """Random values of ``inputs``: angles in (−π, π), rates in (−15, 15), each parameter
    its shipped value times a factor in (0.7, 1.3) (independently: the identities hold
    for any parameters, physical or not)."""
    rng = np.random.default_rng(seed)
    values = {p.symbol: m.values[p.key] for p in m.params}
    q = set(m.q)
    return [[float(values[s] * rng.uniform(0.7, 1.3)) if s in values
             else float(rng.uniform(-np.pi, np.pi)) if s in q
             else float(rng.uniform(-15, 15)) for s in inputs] for _ in range(N_STATES)]


def close(a: Sequence[float], b: Sequence[float]) -> bool:
    a_, b_ = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return bool(np.all(np.abs(a_ - b_) <= TOL * max(1.0, float(np.max(np.abs(b_))))))


@pytest.mark.parametrize("robot", ROBOTS)
def test_the_chain_structure_is_found_in_the_robots_own_mass_matrix(robot: str) -> None:
    s = model(robot).system
    chain = s.chain_inertia
    assert chain is not None
    assert len(chain.yaws) == len(packaged_description(robot).bodies)
    assert s.chain_kinematics is not None


@pytest.mark.parametrize("robot", ROBOTS)
@pytest.mark.parametrize("root_frame", [False, True])
def test_chain_ordered_inertial_forces_equal_the_dense_ones(robot: str, root_frame: bool
                                                            ) -> None:
    m = model(robot)
    s = m.system
    chain = s.chain_at(root_frame)
    assert chain is not None
    n = len(s.q)
    column = sp.symbols(f"c0:{n}", real=True)
    rates = sp.symbols(f"r0:{n}", real=True)
    stage = Stage("_t")
    fast = chain.product(stage, column, rates)
    at = s.root_frame_point() if root_frame else {}
    dense = (s.mass_matrix.xreplace(at) * sp.Matrix(column)
             + s.bias.xreplace(at).xreplace(dict(zip(s.qdot, rates, strict=True))))
    inputs = sorted({*s.q, *column, *rates, *(p.symbol for p in m.params)}, key=str)
    f_fast = compiled(stage.definitions_for(list(fast)), list(fast), inputs)
    f_dense = compiled((), list(dense), inputs)
    for values in draws(m, inputs, 51):
        assert close(f_fast(*values), f_dense(*values))


@cache
def minimal_forms(robot: str, chain_ordered: bool) -> tuple[Stage, list[sp.Expr]]:
    """M̄, H̄, then S, Ṡ η (the root's twist's, ``StagedMinimal.solved``: M̄_u, H̄_u)."""
    m = model(robot)
    stage = Stage("_t")
    sm = m.system.staged_minimal(stage, root_frame=True, positive=m.positive_symbols,
                                 chain_ordered=chain_ordered)
    return stage, [*sm.mass_matrix, *sm.bias, *sm.null_space, *sm.null_space_rate]


@pytest.mark.parametrize("robot", ROBOTS)
def test_chain_ordered_minimal_form_equals_the_dense_one(robot: str) -> None:
    m = model(robot)
    s = m.system
    out = {}
    inputs = sorted({*s.q, *s.eta, *(p.symbol for p in m.params)}, key=str)
    for chain_ordered in (True, False):
        stage, exprs = minimal_forms(robot, chain_ordered)
        out[chain_ordered] = compiled(stage.definitions_for(exprs), exprs, inputs)
    for values in draws(m, inputs, 30):
        assert close(out[True](*values), out[False](*values))


def test_the_chain_ordered_route_is_taken() -> None:
    """train5's S, Ṡ η, M̄ and H̄ through the chain-ordered sums take under half the
    operations of the dense route (which pairs every two bodies)."""
    ops, dense_ops = (sum(sp.count_ops(e) for _, e in stage.definitions_for(exprs))
                      for stage, exprs in (minimal_forms("train5", c) for c in (True, False)))
    assert ops < 0.5 * dense_ops
