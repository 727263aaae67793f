"""From a robot description to a ``ConstrainedSystem``: T, the wheel constraints, B.

* Kinetic energy: Σ ½ m |v_com|² + ½ I θ̇_body² over the bodies, and for each wheel
  ½ m_w |v_centre|² + ½ I_diameter θ̇_body² + ½ I_spin θ̇_wheel² (the wheel's mass at its
  centre, its vertical axis turning with its body).
* Constraints, for each wheel with centre velocity v and body axes e (forward), n (left):
  no side slip v·n = 0 — (6) for the paper's robot — and rolling r θ̇_w − v·e = 0, which is
  (7)–(8) with the paper's sign (so that Drishti's A is ``model.constraint_matrix()``). Rows
  are taken in a fixed order — no-side-slip rows in wheel file order, then rolling rows in
  coordinate order — and a row is dropped when it is a combination of the rows kept before
  it (two wheels on one axle give the same no-side-slip row). Rolling rows are never
  dropped: each is the only one with its wheel's rate.
* Inputs: each driven wheel's motor torque acts on that wheel's angle (B has a unit column
  per driven wheel; the reaction on the body is a pitch torque, which does no work in the
  plane). The driven wheel angles are the independent coordinates of the minimal form.

The result feeds ``modeling.lagrange.ConstrainedSystem`` unchanged, except that the
dependent constraint block is inverted by block-triangular elimination (any size) instead
of cofactors (up to 3×3): see ``modeling.description.elimination``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cache, cached_property

import sympy as sp

from modeling.description.canonical import trig_reduce
from modeling.description.elimination import (
    block_triangular_inverse,
    block_triangular_solve,
    evaluate_exactly,
    exact_det_is_zero,
    exact_rank,
    rational_point,
)
from modeling.description.kinematics import (
    Coordinates,
    Pose,
    body_poses,
    coordinates,
    driven_indices,
    heading,
    velocity,
)
from modeling.description.schema import (
    DescriptionError,
    RobotDescription,
    symbolize,
    validate,
)
from modeling.lagrange import ConstrainedSystem
from modeling.staged import Stage
from modeling.wheel_constraints import NO_SIDE_SLIP, ROLLING, WheelConstraint

HALF = sp.Rational(1, 2)
N_GENERIC_POINTS = 2  # rank decisions: full rank at any of these ⇒ generically full rank
SEED = 20170343


def cofactor_determinant(matrix: sp.Matrix) -> sp.Expr:
    """det by expansion along the first row, products left unexpanded (small blocks)."""
    n = matrix.rows
    if n == 0:
        return sp.S.One
    if n == 1:
        return matrix[0, 0]
    rest = list(range(1, n))
    return sp.Add(*[
        (-1) ** j * matrix[0, j] * cofactor_determinant(
            matrix.extract(rest, [c for c in range(n) if c != j]))
        for j in range(n) if matrix[0, j] != 0
    ])


@dataclass(frozen=True)
class DescribedSystem(ConstrainedSystem):
    """A ``ConstrainedSystem`` derived from a description, with its bookkeeping.

    ``description`` is the symbolised description (its ``values`` give the parameters'
    numbers), ``inputs`` the torque symbols of the driven wheels (the columns of B);
    ``wheel_constraints`` says what each row of A constrains and
    ``dropped_wheel_constraints`` the redundant rows left out.
    """

    description: RobotDescription | None = field(default=None, compare=False)
    coordinate_names: tuple[str, ...] = ()
    inputs: tuple[sp.Symbol, ...] = ()

    @cached_property
    def dependent_block_inverse(self) -> sp.Matrix:
        """A_d⁻¹ by block-triangular elimination (the trailer's A_d is 6×6)."""
        a_d = self._cols(self.constraint_matrix, self.dependent)
        return block_triangular_inverse(a_d, self.simplify)

    def staged_null_space(self, stage: Stage) -> sp.Matrix:
        """S(q) through ``stage``: A_d S_d = −A_i solved block by block in the stage
        (``block_triangular_solve``), so that each trailer's rates read its parent's as
        quantities; the closed form multiplies the chain out (its operations grow about
        threefold a trailer)."""
        return self._solved_null_space(stage, self.constraint_matrix, self.independent)

    def _staged_solve(self, stage: Stage, a_d: sp.Matrix, rhs: sp.Matrix) -> sp.Matrix:
        """A_d x = rhs block by block (``block_triangular_solve``)."""
        return block_triangular_solve(stage, a_d, rhs, self.simplify)

    def minimal_forward_dynamics(self, tau: sp.Matrix) -> sp.Matrix:
        """η̇ = adj(M̄)(Sᵀ B τ − H̄)/det(M̄) as in ``ConstrainedSystem``, but with det(M̄)
        left as the cofactor expansion of the (simplified) entries of M̄ = Sᵀ M S.

        The base class expands and factors det(M̄), which for the WMR collapses to a short
        parameter expression; for a tractor with a trailer det(M̄) depends on the hitch
        angle and expanding it in 24 parameters (31 000 operations) and factoring takes
        about a minute, for nothing that evaluation needs (CSE shares the entries of M̄).
        """
        mbar = self.minimal_mass_matrix
        adj = mbar.adjugate(method="berkowitz")
        det = cofactor_determinant(mbar)
        rhs = self.minimal_input_matrix * tau - self.minimal_bias
        return (adj * rhs) / det

    @property
    def tau(self) -> sp.Matrix:
        return sp.Matrix(self.inputs)

    @cached_property
    def parameters(self) -> tuple[sp.Symbol, ...]:
        """The parameter symbols of T, A and B, sorted by name."""
        exprs = sp.Matrix([self.kinetic_energy, *self.constraint_matrix, *self.input_matrix])
        fixed = set(self.q) | set(self.qdot) | set(self.qddot)
        return tuple(sorted(exprs.free_symbols - fixed, key=str))

    def parameter_values(self) -> tuple[float, ...]:
        """The numbers of ``parameters`` from the description's ``values``."""
        values = self.description.values if self.description is not None else {}
        missing = [str(p) for p in self.parameters if p not in values]
        if missing:
            raise DescriptionError(f"no value for the parameters {', '.join(missing)}")
        return tuple(values[p] for p in self.parameters)


# ---------------------------------------------------------------------------------------
# Kinetic energy
# ---------------------------------------------------------------------------------------
def _kinetic_energy(
    desc: RobotDescription, coords: Coordinates, poses: dict[str, Pose]
) -> sp.Expr:
    t = sp.S.Zero
    for b in desc.bodies:
        v = velocity(poses[b.name].point(b.com), coords)
        yaw_rate = coords.qdot[coords.body_angle[b.name]]
        t += HALF * b.mass * (v.T * v)[0] + HALF * b.yaw_inertia * yaw_rate**2
    for w in desc.wheels:
        v = velocity(poses[w.body].point(w.position), coords)
        yaw_rate = coords.qdot[coords.body_angle[w.body]]
        spin_rate = coords.qdot[coords.wheel_angle[w.name]]
        t += (HALF * w.mass * (v.T * v)[0] + HALF * w.diameter_inertia * yaw_rate**2
              + HALF * w.spin_inertia * spin_rate**2)
    return trig_reduce(t)


def description_kinetic_energy(desc: RobotDescription, numeric: bool = False) -> sp.Expr:
    """T(q, q̇) of the described robot, expanded with sin² + cos² = 1 applied, in the
    symbols of ``symbolize(desc, numeric)`` and the coordinates of
    ``kinematics.coordinates``."""
    sym = symbolize(desc, numeric)
    validate(sym, f"robot '{desc.name}'")
    coords = coordinates(sym)
    return _kinetic_energy(sym, coords, body_poses(sym, coords))


# ---------------------------------------------------------------------------------------
# Constraints
# ---------------------------------------------------------------------------------------
def constraint_candidates(
    desc: RobotDescription, coords: Coordinates, poses: dict[str, Pose]
) -> list[tuple[WheelConstraint, sp.Matrix]]:
    """(what it constrains, row of A) for every wheel constraint, in the fixed order of
    the module docstring, before redundant rows are dropped."""

    def row(expr: sp.Expr) -> sp.Matrix:
        # expr is linear in q̇ (velocities are Jacobians times q̇): its gradient is the row.
        return sp.Matrix([[trig_reduce(sp.diff(expr, v)) for v in coords.qdot]])

    centre = {w.name: velocity(poses[w.body].point(w.position), coords)
              for w in desc.wheels}
    out: list[tuple[WheelConstraint, sp.Matrix]] = []
    for w in desc.wheels:
        _, n = heading(poses[w.body].angle)
        out.append((WheelConstraint(NO_SIDE_SLIP, (w.name,)), row((centre[w.name].T * n)[0])))
    for w in sorted(desc.wheels, key=lambda w: coords.wheel_angle[w.name]):
        e, _ = heading(poses[w.body].angle)
        rate = coords.qdot[coords.wheel_angle[w.name]]
        out.append((WheelConstraint(ROLLING, (w.name,)),
                    row(w.radius * rate - (centre[w.name].T * e)[0])))
    return out


def _generic_points(matrix: sp.Matrix) -> list[sp.Matrix]:
    return [evaluate_exactly(matrix, rational_point(matrix, SEED + k))
            for k in range(N_GENERIC_POINTS)]


def independent_rows(rows: sp.Matrix) -> list[int]:
    """Indices of the rows kept, greedily in order: a row is kept if, with the rows kept
    before it, it has full rank at one of the exact random points (full rank at one point
    ⇒ full rank generically; dependent generically ⇒ dependent everywhere)."""
    points = _generic_points(rows)
    kept: list[int] = []
    for i in range(rows.rows):
        trial = [*kept, i]
        if any(exact_rank(p.extract(trial, list(range(p.cols)))) == len(trial)
               for p in points):
            kept.append(i)
    return kept


def _undetermined(a_d: sp.Matrix, names: list[str]) -> list[str]:
    """Coordinates whose velocity a singular A_d leaves free (its null space's support)."""
    point = evaluate_exactly(a_d, rational_point(a_d, SEED))
    free: set[str] = set()
    for vec in point.nullspace():
        free |= {names[i] for i in range(len(names)) if vec[i] != 0}
    return sorted(free, key=names.index)


def _check_minimal_form(
    where: str, a: sp.Matrix, names: tuple[str, ...], independent: tuple[int, ...],
    values: dict[sp.Symbol, float],
) -> None:
    """Raise unless the driven wheel rates are independent velocities: A_d square and
    invertible generically and at the given values."""
    n = len(names)
    dof = n - a.rows
    if dof != len(independent):
        raise DescriptionError(
            f"{where}: {dof} degree(s) of freedom ({n} coordinates − {a.rows} independent "
            f"wheel constraints) but {len(independent)} driven wheel(s): the minimal form "
            "takes the driven wheel angles as the independent velocities, so their number "
            "must equal the degrees of freedom"
        )
    dependent = [i for i in range(n) if i not in independent]
    a_d = a.extract(list(range(a.rows)), dependent)
    dep_names = [names[i] for i in dependent]
    if a_d.rows == 0:
        return
    if all(exact_det_is_zero(p) for p in _generic_points(a_d)):
        raise DescriptionError(
            f"{where}: S(q) does not exist: the driven wheel rates do not determine the "
            f"velocities {', '.join(_undetermined(a_d, dep_names))} (the constraint block "
            "of the dependent velocities is singular)"
        )
    if values and exact_det_is_zero(evaluate_exactly(a_d, rational_point(a_d, SEED, values))):
        raise DescriptionError(
            f"{where}: S(q) does not exist at the given parameter values (the constraint "
            "block of the dependent velocities is singular there, though not generically)"
        )


def description_input_matrix(desc: RobotDescription) -> sp.Matrix:
    """B: a unit column per driven wheel, on that wheel's angle."""
    coords = coordinates(desc)
    driven = driven_indices(desc, coords)
    b = sp.zeros(len(coords.q), len(driven))
    for k, i in enumerate(driven):
        b[i, k] = 1
    return b


@cache
def _system(sym: RobotDescription) -> DescribedSystem:
    where = f"robot '{sym.name}'"
    validate(sym, where)
    coords = coordinates(sym)
    poses = body_poses(sym, coords)
    candidates = constraint_candidates(sym, coords, poses)
    all_rows = sp.Matrix.vstack(*[r for _, r in candidates]) if candidates else sp.zeros(
        0, len(coords.q))
    kept = independent_rows(all_rows) if candidates else []
    a = all_rows.extract(kept, list(range(all_rows.cols)))
    if sym.values and kept:
        at_values = evaluate_exactly(a, rational_point(a, SEED, sym.values))
        if exact_rank(at_values) < len(kept):
            raise DescriptionError(
                f"{where}: the wheel constraints are dependent at the given parameter values "
                "but not generically: the symbolic model would not hold there (give the "
                "geometry as numbers, or share the symbols that make rows coincide)"
            )
    independent = driven_indices(sym, coords)
    _check_minimal_form(where, a, coords.names, independent, dict(sym.values))
    return DescribedSystem(
        q=coords.q,
        qdot=coords.qdot,
        qddot=coords.qddot,
        kinetic_energy=_kinetic_energy(sym, coords, poses),
        constraint_matrix=a,
        input_matrix=description_input_matrix(sym),
        independent=independent,
        simplify=trig_reduce,
        planar_frame=(0, 1, coords.body_angle[sym.root.name],
                      *(coords.body_angle[b.name] for b in sym.bodies if b is not sym.root)),
        description=sym,
        coordinate_names=coords.names,
        inputs=tuple(sp.Symbol(f"tau_{w.name}", real=True) for w in sym.wheels if w.driven),
        wheel_constraints=tuple(candidates[i][0] for i in kept),
        dropped_wheel_constraints=tuple(
            what for i, (what, _) in enumerate(candidates) if i not in kept),
    )


def description_system(desc: RobotDescription, numeric: bool = False) -> DescribedSystem:
    """The described robot as a constrained Lagrangian system (9): q, T, A (independent
    rows only), B, independent = the driven wheel angles. Raises DescriptionError if the
    description is invalid, if the degrees of freedom differ from the number of driven
    wheels, or if S(q) does not exist. ``numeric``: see ``schema.symbolize``. Cached per
    description."""
    return _system(symbolize(desc, numeric))
