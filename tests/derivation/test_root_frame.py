"""The root-frame evaluation of a described robot (``ConstrainedSystem.in_root_frame``)
and what the generated code gains from it.

A planar robot's T, A and B are invariant under a rigid motion of the whole robot, so M̄,
H̄ and η̇ are the same functions of q evaluated with the root's yaw at 0 and the other
yaws relative to it, and q̇'s and q̈'s (x, y) rows are that evaluation's rotated by
R(θ_root). The staged world-frame forms are the reference here (evaluated at the same
points, θ_root far from 0); the generated code's agreement with routes that share nothing
with the staging is tests/derivation/test_staged_robots.py and
tests/generated/test_any_robot_pipeline.py.
"""

from __future__ import annotations

import random
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
import sympy as sp

from codegen.cse import _merge_equal_temps
from codegen.robot_functions import _trig_of_inputs_only, array, out
from codegen.spec import FunctionSpec
from modeling.robot_file import load_robot_model
from modeling.robot_io import shipped_robot_file
from modeling.staged import Stage, evaluate

OFF_AXLE = Path(__file__).resolve().parents[1] / "robots" / "drishti_bodies.toml"


def _forms(robot: str, frame: bool, twist: bool = True) -> tuple[Stage, list[sp.Matrix], Any]:
    """M̄, H̄, η̇, q̈ and q̇ (world frame) staged, in the root frame or not; ``twist``: the
    wheel radii declared positive, so that the root frame's solve may run in the root's
    twist (``ConstrainedSystem._root_twist``)."""
    path = OFF_AXLE if robot == "drishti_bodies" else shipped_robot_file(robot)
    model, _ = load_robot_model(path)
    stage = Stage("_t")
    sm = model.system.staged_minimal(stage, root_frame=frame,
                                     positive=model.positive_symbols if twist else ())
    assert (sm.solved is not None) == (frame and twist)
    eta_dot, qdd = sm.forward_dynamics(model.tau)
    return stage, [sm.mass_matrix, sm.bias, eta_dot, qdd, sm.world_velocities()], model


@pytest.mark.parametrize(("robot", "twist"), [("trailer", True), ("trailer2", True),
                                              ("trailer", False), ("drishti_bodies", True)])
def test_root_frame_forms_are_the_world_frame_functions(robot: str, twist: bool) -> None:
    """M̄, H̄, η̇, q̈ and q̇ in the root frame (solved in the root's twist, or in the wheel
    rates when the twist is refused) equal the world-frame forms at random states (1e-12
    relative), with only the relative yaws' sin and cos in M̄, H̄ and η̇. Drishti as bodies
    has its root frame's origin 0.12 m ahead of the driven axle: its lateral velocity d ω is
    not zero, so the twist's transport terms (ω v_y, ω v_x) are exercised; the trailers'
    origins are on their axles."""
    world_stage, world, model = _forms(robot, frame=False)
    root_stage, root, _ = _forms(robot, frame=True, twist=twist)
    rng = random.Random(7)
    inputs = [*model.q, *(model.qdot[i] for i in model.actuated), *model.tau]
    for _ in range(5):
        values = {s: rng.uniform(-3.0, 3.0) for s in inputs}
        values[model.q[2]] = rng.uniform(20.0, 40.0)  # far from the root frame's 0
        values.update({p.symbol: model.values[p.key] * rng.uniform(0.9, 1.1)
                       for p in model.params})
        for w, r in zip(world, root, strict=True):
            a = evaluate(world_stage.definitions_for(list(w)), list(w), values)
            b = evaluate(root_stage.definitions_for(list(r)), list(r), values)
            scale = max(1.0, *(abs(x) for x in a))
            assert all(abs(x - y) <= 1e-12 * scale for x, y in zip(a, b, strict=True))
    yaws = [model.q[i] for i in model.system.planar_frame[2:]]
    for m in root[:3]:
        args = {f.args[0] for _, e in root_stage.definitions_for(list(m))
                for f in e.atoms(sp.sin, sp.cos)}
        assert not args & set(yaws), args  # differences of yaws only ...
        assert all(len(sp.Add.make_args(a)) == 2 for a in args), args
        assert bool(args) == (len(yaws) > 1), args  # ... and none without a hitch


@pytest.mark.parametrize("robot", ["trailer", "trailer2", "trailer3"])
def test_twist_solve_is_the_hand_derivations_form(robot: str) -> None:
    """In the root's twist u = (v, ω) = W η: S_u's root rows are the identity, no row of
    S_u but the driven wheels' reads their radii (a hand derivation in (v, ω) has none),
    W is the differential drive's (r/2, ±r/(2b)), and M̄ = Wᵀ M̄_u W."""
    path = OFF_AXLE if robot == "drishti_bodies" else shipped_robot_file(robot)
    model, _ = load_robot_model(path)
    stage = Stage("_t")
    sm = model.system.staged_minimal(stage, root_frame=True, positive=model.positive_symbols)
    assert sm.solved is not None
    x, y, yaw = model.system.planar_frame[:3]
    s_u = sm.null_space
    assert s_u[x, :] == sp.Matrix([[1, 0]]) and s_u[yaw, :] == sp.Matrix([[0, 1]])
    assert s_u[y, :] == sp.zeros(1, 2)  # the tractor's axle does not slip sideways
    radii = {p.symbol for p in model.params if p.key in ("radius_right", "radius_left")}
    for i in range(len(model.q)):
        if i in model.actuated:
            continue
        read = {s for e in s_u.row(i) for s in stage.expand(e).free_symbols}
        assert not read & radii, (model.q[i], read & radii)
    r_r, r_l = (next(p.symbol for p in model.params if p.key == k)
                for k in ("radius_right", "radius_left"))
    # η = W⁻¹ u: the driven wheels' rows of S_u; W = [[r_R/2, r_L/2], [r_R/2b, −r_L/2b]]
    w = s_u.extract(list(model.actuated), [0, 1]).applyfunc(stage.expand).inv()
    w = w.applyfunc(sp.simplify)
    assert w[0, :] == sp.Matrix([[r_r / 2, r_l / 2]])
    inv_b = sp.simplify(w[1, 0] / w[0, 0])
    assert inv_b.is_Number and inv_b > 0 and sp.simplify(w[1, 1] / w[0, 1] + inv_b) == 0
    # M̄_u (from the twist's own constraint solve) = W⁻ᵀ M̄ W⁻¹ with M̄ the world frame's
    world = Stage("_w")
    mbar = model.system.staged_minimal(world).mass_matrix
    rng = random.Random(11)
    values = {s: rng.uniform(-3.0, 3.0) for s in model.q}
    values.update({p.symbol: model.values[p.key] for p in model.params})
    at = {k: sp.Float(v, 30) for k, v in values.items()}
    w_inv = w.inv().xreplace(at)
    expected = w_inv.T * sp.Matrix(2, 2, evaluate(world.definitions_for(list(mbar)),
                                                  list(mbar), values)) * w_inv
    got = evaluate(stage.definitions_for(list(sm.solved[0])), list(sm.solved[0]), values)
    assert all(abs(float(e) - g) <= 1e-12 * max(1.0, abs(g))
               for e, g in zip(expected, got, strict=True)), (expected, got)


def test_twist_needs_its_map_invertible_by_the_guards() -> None:
    """The twist is refused when det W is not a product of parameters the guards keep
    positive (here: only one driven wheel's radius declared positive)."""
    model, _ = load_robot_model(shipped_robot_file("trailer"))
    one = {p.symbol for p in model.params if p.key == "radius_right"}
    sm = model.system.staged_minimal(Stage("_t"), root_frame=True, positive=one)
    assert sm.solved is None


def test_root_frame_contact_forces_are_the_world_frame_functions() -> None:
    """The multipliers of (9) are invariant too: the contact forces in the root frame
    (in_root_frame) equal those of the same robot without a planar frame (the world
    frame's) at random states, with no sin or cos of the heading."""
    from codegen.contact_forces import contact_force_forms

    model, _ = load_robot_model(shipped_robot_file("trailer"))
    world_model = replace(model, system=replace(model.system, planar_frame=()))
    rng = random.Random(3)
    inputs = [*model.q, *(model.qdot[i] for i in model.actuated), *model.tau]
    evaluated = []
    for m in (model, world_model):
        forms = contact_force_forms(m)
        forces = [*forms.longitudinal, *forms.lateral]
        defs = forms.stage.definitions_for(forces)
        args = {f.args[0] for _, e in defs for f in e.atoms(sp.sin, sp.cos)}
        assert (model.q[2] in args) == (m is world_model), args
        evaluated.append((defs, forces))
    for _ in range(3):
        values = {s: rng.uniform(-3.0, 3.0) for s in inputs}
        values[model.q[2]] = rng.uniform(20.0, 40.0)
        values.update({p.symbol: model.values[p.key] for p in model.params})
        a, b = (evaluate(defs, forces, values) for defs, forces in evaluated)
        scale = max(1.0, *(abs(x) for x in a))
        assert all(abs(x - y) <= 1e-12 * scale for x, y in zip(a, b, strict=True))


def test_temporaries_equal_up_to_sign_are_computed_once() -> None:
    x, y, z, w, a, b, c = sp.symbols("x y z w a b c")
    temps = [(a, x * y + z), (b, -x * y - z), (c, b * w)]
    kept, outputs = _merge_equal_temps(temps, [b + c, a * b])
    assert kept == [(a, x * y + z), (c, -a * w)]
    assert outputs == [-a + c, -a**2]


def test_bounded_trig_takes_a_difference_within_one_array_only() -> None:
    """The steps' bounded sin/cos serve an input angle or a hitch angle (two yaws of one
    measured q); an angle between a reference and a measurement keeps libm's."""
    q = sp.symbols("q0:3", real=True)
    q_des = sp.symbols("qd0:3", real=True)
    args = (array("q", q), array("q_des", q_des))

    def spec(expr: sp.Expr) -> FunctionSpec:
        return FunctionSpec("f", "", args, (out("y", [expr]),))

    assert _trig_of_inputs_only(spec(sp.sin(q[2]) + sp.cos(q[1])))
    assert _trig_of_inputs_only(spec(sp.sin(q[2] - q[1])))
    assert not _trig_of_inputs_only(spec(sp.sin(q_des[2] - q[2])))
    assert not _trig_of_inputs_only(spec(sp.sin(q[2] + q[1])))
    assert not _trig_of_inputs_only(spec(sp.sin(2 * q[2] - q[1])))
