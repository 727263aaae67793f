"""The wheel contact forces of a robot from the multipliers of its constrained dynamics (9).

(9) reads M q̈ + H = B τ − Aᵀ λ, and the multipliers follow from its dependent rows once
q̈ is known (the route of (10)–(12)): A_dᵀ λ = (B τ − H − M q̈)_d, with q̈ = S η̇ + Ṡ η and
η̇ the minimal form's forward dynamics. Each row of A is one wheel constraint, declared with
the wheels it holds where the row is built (``ConstrainedSystem.wheel_constraints``), from
a contact velocity:

* a rolling row s (r_w θ̇_w − v_w · e) = 0: its generalised force −Aᵀλ pushes the wheel
  centre by +s λ e and brakes its spin by s λ r_w, so the ground's force on the wheel
  along its heading is F_x = s λ (N; positive forward, the sign of a driving torque);
* a no-side-slip row s (v_w · n) = 0 (n the wheel's axle direction, to its body's left):
  the ground's force on the wheel along n is F_y = −s λ (N; positive to the left).

s is the row's scale: the norm of its coefficients of the root's (ẋ, ẏ), which every
contact velocity carries with unit weight (1 for the rows ``modeling`` builds; checked
here, not assumed). Two wheels on one axle have one no-side-slip row (the second is
redundant and dropped): its force is the axle's, and the rigid model does not split it
between the wheels (statically indeterminate); a runtime splits it (``runtime.sim.
slip_monitor``). ``contact_rows`` says which row belongs to which wheel.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import sympy as sp

from modeling.description.elimination import block_triangular_solve
from modeling.lagrange import StagedMinimal
from modeling.robot_model import RobotModel
from modeling.staged import Stage
from modeling.wheel_constraints import NO_SIDE_SLIP, ROLLING


@dataclass(frozen=True)
class ContactRows:
    """Which rows of A are whose. ``driven``: the driven wheels' names in the order of τ;
    ``rolling``: the row of each one's rolling constraint; ``lateral``: the no-side-slip
    rows kept; ``lateral_wheels``: the wheels each of them holds (an axle's wheels)."""

    driven: tuple[str, ...]
    rolling: tuple[int, ...]
    lateral: tuple[int, ...]
    lateral_wheels: tuple[tuple[str, ...], ...]


@cache
def contact_rows(model: RobotModel) -> ContactRows:
    """The rows of ``model``'s A by wheel (see :class:`ContactRows`), from what each row
    declares it constrains. A no-side-slip row dropped as redundant goes to the kept row of
    the wheel on the same body and axle (same position along the body's x axis).
    ``ValueError`` naming the row otherwise."""
    s = model.system
    rows = s.wheel_constraints
    where = f"robot '{model.name}'"
    if len(rows) != s.constraint_matrix.rows:
        raise ValueError(f"{where}: its constraint rows are not declared (A has "
                         f"{s.constraint_matrix.rows} rows, {len(rows)} wheel constraints)")
    a = s.constraint_matrix
    rolling, driven = [], []
    for col in model.actuated:
        found = [i for i in range(a.rows) if a[i, col] != 0]
        if len(found) != 1 or rows[found[0]].kind != ROLLING:
            raise ValueError(f"{where}: driven coordinate {model.coordinate_names[col]} is "
                             "not in exactly one rolling row of A")
        rolling.append(found[0])
        driven.append(rows[found[0]].wheels[0])
    lateral = [i for i, row in enumerate(rows) if row.kind == NO_SIDE_SLIP]
    wheels = [list(rows[i].wheels) for i in lateral]
    dropped = [row for row in s.dropped_wheel_constraints if row.kind == NO_SIDE_SLIP]
    if dropped:
        layout = {w[0]: (w[1], float(w[2][0])) for w in (model.layout or {}).get("wheels", [])}
        for row in dropped:
            name = row.wheels[0]
            axle = layout.get(name)
            match = [k for k, ws in enumerate(wheels)
                     if axle is not None and layout.get(ws[0]) is not None
                     and layout[ws[0]][0] == axle[0] and abs(layout[ws[0]][1] - axle[1]) < 1e-9]
            if len(match) != 1:
                raise ValueError(f"{where}: the no-side-slip row of wheel '{name}' is redundant "
                                 "but no kept row is on its axle: its lateral force has no row")
            wheels[match[0]].append(name)
    return ContactRows(tuple(driven), tuple(rolling), tuple(lateral),
                       tuple(tuple(w) for w in wheels))


def _row_scale(model: RobotModel, row: int) -> sp.Expr:
    """s of a row: the norm of its coefficients of the root's (ẋ, ẏ) (module docstring)."""
    a = model.system.constraint_matrix
    squared = model.system.simplify(sp.expand(a[row, 0] ** 2 + a[row, 1] ** 2))
    scale = sp.sqrt(squared)
    if not (scale.is_number and scale.is_positive):
        raise ValueError(f"robot '{model.name}': row {row} of A "
                         f"({model.system.constraint_labels[row]}) has no constant scale "
                         f"in the root's velocity (|coefficients|² = {squared})")
    return scale


@dataclass(frozen=True)
class ContactForms:
    """F_x of each driven wheel (τ order), F_y of each no-side-slip row, and the stage
    quantities they read (``stage.definitions_for``)."""

    stage: Stage
    longitudinal: sp.Matrix
    lateral: sp.Matrix


@cache
def contact_force_forms(model: RobotModel) -> ContactForms:
    """The contact forces of ``model`` in (q, η, τ) through a stage of their own: the
    minimal forward dynamics of (9), q̈ = S η̇ + Ṡ η, then A_dᵀ λ = (B τ − H − M q̈)_d solved
    block by block (a trailer's A_d is block triangular), then each row's λ in newtons."""
    s = model.system
    rows = contact_rows(model)
    stage = Stage("_cf")
    sm = s.staged_minimal(stage)
    _, qdd = sm.forward_dynamics(model.tau)
    dep = list(s.dependent)
    on_manifold = {s.qdot[i]: sm.velocities[i] for i in dep}
    m = stage.matrix(s.mass_matrix)
    h = stage.matrix(s.bias.xreplace(on_manifold))
    rhs = stage.matrix(s.input_matrix * model.tau - h - m * qdd)
    a_d = s.constraint_matrix.extract(list(range(s.constraint_matrix.rows)), dep)
    lam = block_triangular_solve(stage, a_d.T, rhs.extract(dep, [0]), s.simplify)
    forces = [stage.define(_row_scale(model, r) * lam[r]) for r in rows.rolling]
    forces += [stage.define(-_row_scale(model, r) * lam[r]) for r in rows.lateral]
    m = len(rows.rolling)
    # The multipliers are invariant under planar rigid motions (each a force along its
    # wheel's own axes): evaluated in the root body's frame.
    longitudinal, lateral = s.in_root_frame(stage, [sp.Matrix(forces[:m]),
                                                    sp.Matrix(forces[m:])])
    return ContactForms(stage, longitudinal, lateral)


def root_frame_contact_forms(model: RobotModel, sm: StagedMinimal) -> ContactForms:
    """The contact forces of :func:`contact_force_forms` through the quantities of the
    model's own root-frame stage ``sm`` (``staged_minimal(root_frame=True)``, the model
    functions' of a staged robot with a planar frame): q̈ = S η̇ + Ṡ η of its forward
    dynamics in the root body's frame, M, H and A_d evaluated there
    (``root_frame_point``; M q̈ + H in chain order along a hitch chain,
    ``ConstrainedSystem.chain_inertia``), where the multipliers are the same functions
    of q. S(q), M̄, H̄ and the solve are then the model functions' quantities, not a
    second derivation of them (issue 51: one helper evaluates them for all,
    ``codegen.shared``)."""
    s = model.system
    if not s.planar_frame or sm.plane is None:
        raise ValueError(f"robot '{model.name}': no root frame to write its contact forces in")
    rows = contact_rows(model)
    stage = sm.stage
    _, qdd = sm.accelerations(model.tau)
    at_root = s.root_frame_point()
    dep = list(s.dependent)
    on_manifold = {s.qdot[i]: sm.velocities[i] for i in range(len(s.q))
                   if sm.velocities[i] != s.qdot[i]}
    chain = s.ordered_chain(root_frame=True)
    if chain is None:
        m = stage.matrix(s.mass_matrix.xreplace(at_root))
        h = stage.matrix(s.bias.xreplace(at_root).xreplace(on_manifold))
        inertial = m * qdd + h
    else:  # a hitch chain: M q̈ + H in chain order, O(n) (modeling.chain_inertia)
        inertial = chain.product(stage, qdd, sm.velocities)
    rhs = stage.matrix(s.input_matrix * model.tau - inertial)
    a = s.constraint_matrix.xreplace(at_root)
    a_d = a.extract(list(range(a.rows)), dep)
    lam = block_triangular_solve(stage, a_d.T, rhs.extract(dep, [0]), s.simplify)
    forces = [stage.define(_row_scale(model, r) * lam[r]) for r in rows.rolling]
    forces += [stage.define(-_row_scale(model, r) * lam[r]) for r in rows.lateral]
    k = len(rows.rolling)
    return ContactForms(stage, sp.Matrix(forces[:k]), sp.Matrix(forces[k:]))
