"""Lagrangian mechanics with Pfaffian constraints, for any robot.

From generalised coordinates q, a kinetic energy T(q, q̇) (and optionally a potential
V(q)), Pfaffian velocity constraints A(q) q̇ = 0 and an input map B, this module computes

* the Euler–Lagrange form (9):  M(q) q̈ + H(q, q̇) = B τ − Aᵀ(q) λ;
* a null-space basis S(q) with A S = 0 from a split of q into dependent and independent
  coordinates, so that q̇ = S(q) η with η the independent velocities;
* the multipliers λ as functions of (q, q̇, q̈ᵢ) — the route of (10)–(12) — and of
  (q, q̇, τ) through the minimal form;
* the reduced, multiplier-free form of (14):  M̃(q) q̈ + H̃(q, q̇) = B τ, built exactly as
  the paper describes (dependent rows: (9) with λ(q, q̇, q̈ᵢ) substituted; independent rows:
  (9) with λ solved from the dependent rows);
* the minimal form in η:  Sᵀ M S η̇ + Sᵀ(M Ṡ η + H) = Sᵀ B τ.

Nothing here computes with wheels (what each row of A constrains is only carried). Symbols
are plain ``sympy.Symbol``; time derivatives use the chain rule on (q, q̇, q̈).
"""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass
from functools import cached_property
from itertools import combinations

import sympy as sp

from modeling.chain_inertia import ChainInertia, chain_inertia
from modeling.chain_kinematics import ChainKinematics, chain_kinematics
from modeling.staged import Stage
from modeling.symbolic_linalg import (
    Simplifier,
    adjugate_and_determinant,
    inverse_by_cofactors,
    time_derivative,
)
from modeling.wheel_constraints import WheelConstraint

# The fewest hitches for which M S and M Ṡη + H are evaluated in chain order (``ordered_chain``)
MIN_ORDERED_HITCHES = 2


def default_simplify(expr: sp.Expr) -> sp.Expr:
    """Cheap canonical form: expanded, with sin² + cos² = 1 applied (see trig_canonical)."""
    return trig_canonical(sp.expand(expr))


def trig_canonical(expr: sp.Expr) -> sp.Expr:
    """Reduce a polynomial in sin(a), cos(a) modulo sin²(a) + cos²(a) − 1 for each angle a.

    The remainder (degree ≤ 1 in sin) is a canonical form, so an identity such as
    M S − S M = 0 is recognised by expansion alone; this is orders of magnitude faster
    than ``trigsimp`` and never changes the value. Expressions with a trigonometric
    function in a denominator are returned unchanged.
    """
    angles = sorted({f.args[0] for f in expr.atoms(sp.sin, sp.cos)}, key=sp.default_sort_key)
    for angle in angles:
        s_, c_ = sp.Dummy("s"), sp.Dummy("c")
        sub = sp.expand(expr.subs({sp.sin(angle): s_, sp.cos(angle): c_}))
        try:
            rem = sp.Poly(sub, s_).rem(sp.Poly(s_**2 + c_**2 - 1, s_))
        except sp.PolynomialError:
            continue
        expr = sp.expand(rem.as_expr()).subs({s_: sp.sin(angle), c_: sp.cos(angle)})
    return expr


@dataclass(frozen=True)
class StagedMinimal:
    """The minimal form through named quantities of a :class:`~modeling.staged.Stage`:
    S(q), v = S η (q̇ on the constraint manifold), M, H on the manifold, Ṡ η, then
    M̄ = Sᵀ M S, H̄ = Sᵀ(M Ṡ η + H) and Sᵀ B, entry by entry; never multiplied out.

    With a ``twist`` W the solve runs in the root body's twist u = W η instead
    (``ConstrainedSystem.staged_minimal``): ``null_space`` is S_u (q̇ = S_u u),
    ``solved`` holds M̄_u, H̄_u and S_uᵀ B, and the wheel-rate forms are
    M̄ = Wᵀ M̄_u W, H̄ = Wᵀ H̄_u, Sᵀ B = Wᵀ S_uᵀ B (W constant)."""

    stage: Stage
    null_space: sp.Matrix  # S (or S_u), n × k
    velocities: sp.Matrix  # S η, n × 1
    null_space_rate: sp.Matrix  # Ṡ η, n × 1
    mass_matrix: sp.Matrix  # M̄ = Sᵀ M S, k × k
    bias: sp.Matrix  # H̄, k × 1
    input_matrix: sp.Matrix  # Sᵀ B, k × m
    # (x, y indices, the root yaw) when S, q̇ and Ṡ η are the root frame's (their x, y
    # rows rotate by R(θ_root) into the world's); None: they are the world frame's
    plane: tuple[int, int, sp.Symbol] | None = None
    eta_rows: tuple[int, ...] = ()  # the rows of q̈ that are η̇
    # (M̄_u, H̄_u, S_uᵀ B) in the coordinates the solve runs in; None: M̄, H̄, Sᵀ B
    solved: tuple[sp.Matrix, sp.Matrix, sp.Matrix] | None = None

    @property
    def solved_mass_matrix(self) -> sp.Matrix:
        """The mass matrix the forward dynamics factor: M̄_u with a twist, else M̄. It is
        positive definite exactly when M̄ is (M̄ = Wᵀ M̄_u W, W invertible)."""
        return self.mass_matrix if self.solved is None else self.solved[0]

    def forward_dynamics(self, tau: sp.Matrix) -> tuple[sp.Matrix, sp.Matrix]:
        """(η̇, q̈): M̄ η̇ = Sᵀ B τ − H̄ (or M̄_u u̇ = S_uᵀ B τ − H̄_u) solved in the stage,
        q̈ = S η̇ + Ṡ η in the world frame, η̇ its ``eta_rows``."""
        eta_dot, qdd = self.accelerations(tau)
        return eta_dot, self.in_world(qdd)

    def accelerations(self, tau: sp.Matrix) -> tuple[sp.Matrix, sp.Matrix]:
        """(η̇, q̈) as :meth:`forward_dynamics`, q̈ in the frame of S (the root body's
        with a ``plane``: its x, y rows not rotated into the world's)."""
        mass, bias, inputs = ((self.mass_matrix, self.bias, self.input_matrix)
                              if self.solved is None else self.solved)
        rates = self.stage.solve(mass, inputs * tau - bias)
        qdd = self.stage.matrix(self.null_space * rates + self.null_space_rate)
        eta_dot = rates if self.solved is None else sp.Matrix([qdd[i] for i in self.eta_rows])
        return eta_dot, qdd

    def world_velocities(self) -> sp.Matrix:
        """q̇ = S η in the world frame."""
        return self.in_world(self.velocities)

    def in_world(self, column: sp.Matrix) -> sp.Matrix:
        """A column over q with its (x, y) rows rotated by R(θ_root) once when they are
        the root frame's (``plane``); unchanged otherwise."""
        if self.plane is None:
            return column
        x, y, theta = self.plane
        a, b = column[x], column[y]
        c, s = sp.cos(theta), sp.sin(theta)
        out = sp.Matrix(column)
        out[x], out[y] = self.stage.define(c * a - s * b), self.stage.define(s * a + c * b)
        return out


def _congruence(stage: Stage, s: sp.Matrix, m: sp.Matrix,
                chain: ChainInertia | None = None) -> sp.Matrix:
    """Sᵀ M S for a symmetric M through the stage: M S once, then each entry on and above
    the diagonal once (the result is symmetric); along a hitch ``chain``, its running
    sums in O(n) (``ChainInertia.congruence``)."""
    if chain is not None:
        return chain.congruence(stage, s)
    k = s.cols
    ms = stage.matrix(m * s)
    return sp.Matrix(k, k, lambda i, j: stage.define((s[:, min(i, j)].T * ms[:, max(i, j)])[0]))


@dataclass(frozen=True)
class ConstrainedSystem:
    """A mechanical system given by its energies, constraints and inputs.

    ``independent`` indexes the coordinates whose velocities stay free once the
    constraints hold (for a differential-drive robot: the two wheel angles). The remaining
    (dependent) block of A must be invertible.
    """

    q: tuple[sp.Symbol, ...]
    qdot: tuple[sp.Symbol, ...]
    qddot: tuple[sp.Symbol, ...]
    kinetic_energy: sp.Expr
    constraint_matrix: sp.Matrix  # A(q), rows = constraints
    input_matrix: sp.Matrix  # B
    independent: tuple[int, ...]
    potential_energy: sp.Expr = sp.S.Zero
    simplify: Simplifier = default_simplify
    # What each row of A constrains (the rolling or no side slip of which wheels), and the
    # redundant rows left out of A: carried for the wheel contact forces
    # (codegen.contact_forces), which read the wheels from here.
    wheel_constraints: tuple[WheelConstraint, ...] = ()
    dropped_wheel_constraints: tuple[WheelConstraint, ...] = ()
    # Indices of (x, y, the root body's yaw, the other bodies' absolute yaws) when T, A
    # and B are invariant under a rigid planar motion of the whole robot (x, y rotated and
    # shifted, every yaw turned by the same angle): ``staged_minimal(root_frame=True)``
    # and ``in_root_frame`` use it. Empty: no such symmetry is claimed.
    planar_frame: tuple[int, ...] = ()

    def __post_init__(self) -> None:
        n = len(self.q)
        if not (len(self.qdot) == len(self.qddot) == n):
            raise ValueError("q, qdot and qddot must have the same length")
        if self.constraint_matrix.cols != n or self.input_matrix.rows != n:
            raise ValueError("A must have n columns and B n rows")
        if len(self.independent) + self.constraint_matrix.rows != n:
            raise ValueError(
                "the number of independent coordinates plus the number of constraints "
                "must equal the number of coordinates"
            )

    @property
    def constraint_labels(self) -> tuple[str, ...]:
        """Each row of A in words ("rolling of wheel 'right'"), for reports."""
        return tuple(c.label for c in self.wheel_constraints)

    @property
    def dropped_constraints(self) -> tuple[str, ...]:
        """The redundant rows left out of A, in words."""
        return tuple(c.label for c in self.dropped_wheel_constraints)

    # --- index bookkeeping -------------------------------------------------------------
    @cached_property
    def dependent(self) -> tuple[int, ...]:
        return tuple(i for i in range(len(self.q)) if i not in self.independent)

    @property
    def eta(self) -> tuple[sp.Symbol, ...]:
        """Independent velocities η (a subset of q̇)."""
        return tuple(self.qdot[i] for i in self.independent)

    @property
    def eta_dot(self) -> tuple[sp.Symbol, ...]:
        return tuple(self.qddot[i] for i in self.independent)

    def _rows(self, m: sp.Matrix, idx: tuple[int, ...]) -> sp.Matrix:
        return m.extract(list(idx), list(range(m.cols)))

    def _cols(self, m: sp.Matrix, idx: tuple[int, ...]) -> sp.Matrix:
        return m.extract(list(range(m.rows)), list(idx))

    def ddt(self, expr: sp.MatrixBase | sp.Expr, with_accel: bool = False) -> sp.Expr:
        return time_derivative(expr, self.q, self.qdot, self.qddot if with_accel else None)

    # --- (9): Euler–Lagrange ----------------------------------------------------------
    @cached_property
    def mass_matrix(self) -> sp.Matrix:
        """M(q) of (9): the Hessian of T in q̇."""
        qd = sp.Matrix(self.qdot)
        return sp.hessian(self.kinetic_energy, qd).applyfunc(self.simplify)

    @cached_property
    def bias(self) -> sp.Matrix:
        """H(q, q̇) of (9): d/dt ∂T/∂q̇ − M q̈ − ∂T/∂q + ∂V/∂q (Coriolis, centripetal, gravity)."""
        t = self.kinetic_energy
        h = []
        for i, qi in enumerate(self.q):
            dT_dqdot = sp.diff(t, self.qdot[i])
            d_dt = self.ddt(dT_dqdot)  # velocity part of d/dt(∂T/∂q̇ᵢ)
            h.append(self.simplify(d_dt - sp.diff(t, qi) + sp.diff(self.potential_energy, qi)))
        return sp.Matrix(h)

    @cached_property
    def constraint_rate_term(self) -> sp.Matrix:
        """Ȧ q̇: differentiating A q̇ = 0 gives A q̈ + Ȧ q̇ = 0."""
        a_qdot = self.constraint_matrix * sp.Matrix(self.qdot)
        return sp.Matrix([self.simplify(self.ddt(e)) for e in a_qdot])

    # --- null space -------------------------------------------------------------------
    @cached_property
    def dependent_block_inverse(self) -> sp.Matrix:
        """A_d⁻¹, the inverse of A's columns of the dependent coordinates."""
        a_d = self._cols(self.constraint_matrix, self.dependent)
        return inverse_by_cofactors(a_d, self.simplify)

    @cached_property
    def null_space(self) -> sp.Matrix:
        """S(q) with A S = 0 and q̇ = S η: the dependent rows are −A_d⁻¹ A_i, the rest identity.

        For a wheeled robot the dependent rows are the kinematics (31).
        """
        a_i = self._cols(self.constraint_matrix, self.independent)
        s_dep = (-self.dependent_block_inverse * a_i).applyfunc(self.simplify)
        n, k = len(self.q), len(self.independent)
        s = sp.zeros(n, k)
        for row, i in enumerate(self.dependent):
            s[i, :] = s_dep[row, :]
        for col, i in enumerate(self.independent):
            s[i, col] = sp.S.One
        return s

    @cached_property
    def on_manifold(self) -> dict[sp.Symbol, sp.Expr]:
        """Substitution q̇_d → (S η)_d: restricts an expression to the constraint manifold."""
        sv = self.null_space * sp.Matrix(self.eta)
        return {self.qdot[i]: sv[i] for i in self.dependent}

    @cached_property
    def null_space_rate(self) -> sp.Matrix:
        """Ṡ η on the constraint manifold (the velocity-product part of q̈ = S η̇ + Ṡ η)."""
        s_eta = self.null_space * sp.Matrix(self.eta)
        rate = self.ddt(s_eta)  # ∂(Sη)/∂q · q̇ with η held fixed
        return rate.subs(self.on_manifold).applyfunc(self.simplify)

    @cached_property
    def chain_inertia(self) -> ChainInertia | None:
        """M and H as the composite-body sums of a planar hitch chain
        (``modeling.chain_inertia``, checked exactly), or None: not such a chain."""
        if not self.planar_frame:
            return None
        return chain_inertia(self.mass_matrix, self.bias, self.q, self.qdot,
                             self.planar_frame, self.simplify)

    @cached_property
    def chain_kinematics(self) -> ChainKinematics | None:
        """A's rows along the hitch chain of ``chain_inertia`` (``modeling.chain_kinematics``,
        checked exactly), or None."""
        chain = self.chain_inertia
        if chain is None:
            return None
        return chain_kinematics(chain, self.constraint_matrix, self.q, self.qdot,
                                self.simplify)

    def chain_at(self, root_frame: bool) -> ChainInertia | None:
        """``chain_inertia`` in the root body's frame (``root_frame_point``) or not."""
        chain = self.chain_inertia
        if chain is None or not root_frame:
            return chain
        return chain.at(self.root_frame_point())

    def ordered_chain(self, root_frame: bool) -> ChainInertia | None:
        """``chain_at(root_frame)`` where the chain order pays: two hitches or more. With
        one hitch M couples a single pair of yaws, so the dense products are already
        O(1); the running sums only add operations (20–23 on the one-trailer robot) and
        widen the float32 certifier's enclosures (the trailer's M̄ determinant, written
        through them, is no longer proved nonzero over its box: docs/FLOAT32.md)."""
        chain = self.chain_at(root_frame)
        return (chain if chain is not None and len(chain.yaws) - 1 >= MIN_ORDERED_HITCHES
                else None)

    # --- minimal form -----------------------------------------------------------------
    @cached_property
    def minimal_mass_matrix(self) -> sp.Matrix:
        """Sᵀ M S."""
        s = self.null_space
        return (s.T * self.mass_matrix * s).applyfunc(self.simplify)

    @cached_property
    def minimal_bias(self) -> sp.Matrix:
        """Sᵀ(M Ṡ η + H), with H on the constraint manifold."""
        s = self.null_space
        h = self.bias.subs(self.on_manifold)
        return (s.T * (self.mass_matrix * self.null_space_rate + h)).applyfunc(self.simplify)

    @cached_property
    def minimal_input_matrix(self) -> sp.Matrix:
        """Sᵀ B: the Lagrange multipliers do no work along S, so only Sᵀ B τ drives η."""
        return (self.null_space.T * self.input_matrix).applyfunc(self.simplify)

    def staged_minimal(self, stage: Stage, root_frame: bool = False,
                       positive: Collection[sp.Symbol] = (),
                       chain_ordered: bool = True) -> StagedMinimal:
        """The minimal form through ``stage``'s quantities (see :class:`StagedMinimal`):
        the cost of S, M and H, which are small, plus one product per entry, where
        ``minimal_mass_matrix`` and ``minimal_bias`` multiply out (tens of thousands of
        operations for a tractor with two trailers).

        ``root_frame`` (with a ``planar_frame``): S, its derivatives, M and H evaluated
        in the root body's frame (``root_frame_point``), every other quantity from them;
        M̄, H̄, Sᵀ B and η̇ are the same functions of q, S, q̇ and Ṡ η the root frame's
        (the result's ``plane`` rotates their x, y rows back). There S depends on the
        hitch angles only, so its slopes along a child's yaw and along the root's are
        equal and opposite, and Ṡ η is written once per hitch angle.

        When, in that frame, two (k) of the root's velocities (its forward speed and yaw
        rate for a differential drive) are a constant map u = W η of the wheel rates with
        det W a product of ``positive`` parameters (the caller's guards keep them
        positive), the solve runs in u (``_staged_in_twist``): S_u carries no wheel
        radius, so M̄_u and H̄_u are the short forms a hand derivation in (v, ω) writes.

        ``chain_ordered`` (a hitch chain's ``ordered_chain``): M S and M Ṡ η + H in chain
        order, O(n) (issue 51); False: the dense products, O(n²), the same values."""
        chain = (self.ordered_chain(root_frame and bool(self.planar_frame)) if chain_ordered
                 else None)
        s = self.staged_null_space(stage)
        eta = sp.Matrix(self.eta)
        if root_frame and self.planar_frame:
            twist = self._root_twist(stage, self.in_root_frame(stage, [s])[0], positive)
            if twist is not None:
                return self._staged_in_twist(stage, *twist, chain)
        slopes = self._slopes(stage, s, self.dependent)
        mass, bias = self.mass_matrix, self.bias
        plane: tuple[int, int, sp.Symbol] | None = None
        if root_frame and self.planar_frame:
            at_root = self.root_frame_point()
            s, at = self.in_root_frame(stage, [s, sp.Matrix(list(slopes.values()))])
            slopes = dict(zip(slopes, at, strict=True))
            mass, bias = mass.xreplace(at_root), bias.xreplace(at_root)
            plane = self.planar_frame[0], self.planar_frame[1], self.q[self.planar_frame[2]]
        v = stage.matrix(s * eta)  # q̇ on the manifold (independent rows: η itself)
        m, h = self._on_manifold(stage, v, mass, bias)
        rate = self._gathered_rate(stage, slopes, eta, v, self.dependent)
        return self._staged_products(stage, s, v, rate, m, h, plane, chain)

    def _on_manifold(self, stage: Stage, v: sp.Matrix, mass: sp.Matrix, bias: sp.Matrix
                     ) -> tuple[sp.Matrix, sp.Matrix]:
        """M and H (q̇ replaced by the velocities ``v``) as quantities of ``stage``."""
        on_manifold = {self.qdot[i]: v[i] for i in range(len(self.q)) if v[i] != self.qdot[i]}
        return stage.matrix(mass), stage.matrix(bias.xreplace(on_manifold))

    def _slopes(self, stage: Stage, s: sp.Matrix, rows: tuple[int, ...]
                ) -> dict[tuple[int, int, int], sp.Expr]:
        """{(row, j, column): ∂S/∂q_j} of ``s``'s ``rows``, nonzero ones: S's own entries
        differentiated (each a quantity)."""
        return {(i, j, a): d for i in rows for j in range(len(self.q)) for a in range(s.cols)
                if (d := stage.derivative(s[i, a], self.q[j])) != 0}

    def _gathered_rate(self, stage: Stage, slopes: dict[tuple[int, int, int], sp.Expr],
                       rates: sp.Matrix, v: sp.Matrix, rows: tuple[int, ...]) -> sp.Matrix:
        """Ṡ η = Σ_j ∂S/∂q_j η (S η)_j over ``slopes`` {(row, j, column): ∂S/∂q_j}, the
        terms of equal (or opposite) slopes gathered (one product per hitch angle)."""
        gathered: dict[int, dict[sp.Expr, sp.Expr]] = {i: {} for i in rows}
        for (i, j, a), d in slopes.items():
            if d != 0:  # a slope can vanish in the root frame
                sign, key = (-1, -d) if d.could_extract_minus_sign() else (1, d)
                gathered[i][key] = gathered[i].get(key, sp.S.Zero) + sign * rates[a] * v[j]
        rate = sp.zeros(len(self.q), 1)
        for i, terms in gathered.items():
            rate[i] = stage.define(sp.Add(*(d * stage.define(c) for d, c in terms.items())))
        return rate

    def _staged_products(self, stage: Stage, s: sp.Matrix, v: sp.Matrix, rate: sp.Matrix,
                         m: sp.Matrix, h: sp.Matrix,
                         plane: tuple[int, int, sp.Symbol] | None,
                         chain: ChainInertia | None = None) -> StagedMinimal:
        """M̄ = Sᵀ M S, H̄ = Sᵀ(M Ṡ η + H) and Sᵀ B through the stage (M, H staged at
        the velocities ``v``, ``_on_manifold``; along a hitch ``chain``, in the same
        frame, M S and M Ṡ η + H in chain order instead)."""
        mbar = _congruence(stage, s, m, chain)
        hbar = (stage.matrix(s.T * (m * rate + h)) if chain is None
                else chain.projected(stage, s, list(rate), list(v)))
        return StagedMinimal(stage, s, v, rate, mbar, hbar,
                             stage.matrix(s.T * self.input_matrix.xreplace(
                                 self.root_frame_point() if plane else {})),
                             plane, self.independent)

    def _root_twist(self, stage: Stage, s_root: sp.Matrix, positive: Collection[sp.Symbol]
                    ) -> tuple[tuple[int, ...], sp.Matrix] | None:
        """(rows, W): the first k of the root's (x, y, yaw) velocity rows of the root
        frame's S (``s_root``) that are constant, W their entries, with det W a nonzero
        number times powers of ``positive`` symbols; None when there are none."""
        k = len(self.independent)
        q = set(self.q)
        wanted = set(positive)
        for rows in combinations(self.planar_frame[:3], k):
            w = sp.Matrix([[stage.expand(s_root[r, a]) for a in range(k)] for r in rows])
            if w.free_symbols & q:
                continue
            det = sp.factor(sp.cancel(w.det(method="berkowitz")))
            factors = [f.base if f.is_Pow else f for f in sp.Mul.make_args(det)]
            if det != 0 and all(f.is_Number or f in wanted for f in factors):
                return rows, w.applyfunc(lambda e: stage.define(sp.factor(e)))
        return None

    def _staged_in_twist(self, stage: Stage, rows: tuple[int, ...], w: sp.Matrix,
                         chain: ChainInertia | None = None) -> StagedMinimal:
        """The minimal form solved in the root's twist u = W η (the velocities of ``rows``
        in the root frame): S_u from A evaluated in the root frame with those velocities
        independent (``_staged_solve``), its slopes along the relative yaws, and the root
        frame's turning rate θ̇ J (S_u u) added to Ṡ_u u's x, y rows (the frame turns with
        the root: d/dt R(θ) a = R(θ)(ȧ + θ̇ J a)). M̄ = Wᵀ M̄_u W, H̄ = Wᵀ H̄_u, Sᵀ B = Wᵀ S_uᵀ B
        for the functions that speak in wheel rates; η̇ = q̈'s wheel rows."""
        n = len(self.q)
        at_root = self.root_frame_point()
        dependent = tuple(i for i in range(n) if i not in rows)
        x, y, yaw = self.planar_frame[:3]
        kinematics = self.chain_kinematics if chain is not None else None
        if kinematics is not None and kinematics.solves(rows):
            # Along a hitch chain: S_u and Ṡ_u u body by body (O(n)), A (Ṡ_u u) = −Ȧ v
            # with the frame's turning term as the x row's known part.
            kinematics = kinematics.at(at_root)
            s = kinematics.null_space(stage, rows)
            u = stage.matrix(w * sp.Matrix(self.eta))
            v = stage.matrix(s * u)
            m, h = self.mass_matrix, self.bias  # read through ``chain`` only
            known = {i: sp.S.Zero for i in rows}
            known[x] = -v[yaw] * v[y]
            rate = kinematics.velocity_product(stage, v, known)
        else:
            s = self._solved_null_space(stage, self.constraint_matrix.xreplace(at_root), rows)
            u = stage.matrix(w * sp.Matrix(self.eta))
            v = stage.matrix(s * u)
            m, h = self._on_manifold(stage, v, self.mass_matrix.xreplace(at_root),
                                     self.bias.xreplace(at_root))
            rate = self._gathered_rate(stage, self._slopes(stage, s, dependent), u, v,
                                       dependent)
            turn = v[yaw]
            rate[x] = stage.define(rate[x] - turn * v[y])
            rate[y] = stage.define(rate[y] + turn * v[x])
        in_u = self._staged_products(stage, s, v, rate, m, h, (x, y, self.q[yaw]), chain)
        return StagedMinimal(stage, s, v, rate, _congruence(stage, w, in_u.mass_matrix),
                             stage.matrix(w.T * in_u.bias),
                             stage.matrix(w.T * in_u.input_matrix), in_u.plane,
                             self.independent,
                             (in_u.mass_matrix, in_u.bias, in_u.input_matrix))

    def _solved_null_space(self, stage: Stage, a: sp.Matrix, independent: tuple[int, ...]
                           ) -> sp.Matrix:
        """S with A S = 0 for the constraint matrix ``a`` and the ``independent``
        coordinates' velocities free: A_d S_d = −A_i solved in the stage
        (``_staged_solve``), the independent rows the identity."""
        a = stage.matrix(a)
        n = len(self.q)
        dependent = [i for i in range(n) if i not in independent]
        s_dep = self._staged_solve(stage, self._cols(a, tuple(dependent)),
                                   -self._cols(a, independent))
        s = sp.zeros(n, len(independent))
        for row, i in enumerate(dependent):
            s[i, :] = s_dep[row, :]
        for col, i in enumerate(independent):
            s[i, col] = sp.S.One
        return s

    def _staged_solve(self, stage: Stage, a_d: sp.Matrix, rhs: sp.Matrix) -> sp.Matrix:
        """x with A_d x = rhs in the stage (a described robot solves block by block)."""
        return stage.solve_general(a_d, rhs, self.simplify)

    def root_frame_point(self) -> dict[sp.Symbol, sp.Expr]:
        """The substitution evaluating a function of q in the root body's frame: the
        root's yaw 0, every other yaw relative to it (``planar_frame``); x and y do not
        occur in a planar robot's S, M or H."""
        _, _, root, *others = self.planar_frame
        theta = self.q[root]
        at_root: dict[sp.Symbol, sp.Expr] = {theta: sp.S.Zero}
        at_root.update({self.q[i]: self.q[i] - theta for i in others})
        return at_root

    def in_root_frame(self, stage: Stage, matrices: list[sp.Matrix]) -> list[sp.Matrix]:
        """``matrices`` (quantities of ``stage``) evaluated in the root body's frame
        (``root_frame_point``), written with the sines and cosines of the yaws relative to
        the root's only. For a quantity invariant under planar rigid motions (M̄, H̄, η̇, a
        multiplier of (9): a force along a wheel's own axes) that is the same function of
        q; ``staged_minimal(root_frame=True)`` also evaluates S and its slopes there.
        Unchanged without a ``planar_frame``."""
        if not self.planar_frame:
            return matrices
        flat = stage.substituted([e for m in matrices for e in m], self.root_frame_point())
        out, k = [], 0
        for m in matrices:
            out.append(sp.Matrix(m.rows, m.cols, flat[k:k + len(m)]))
            k += len(m)
        return out

    def staged_null_space(self, stage: Stage) -> sp.Matrix:
        """S(q) with its entries quantities of ``stage`` (here the closed form's entries;
        a described robot solves its constraint block in the stage instead)."""
        return stage.matrix(self.null_space)

    # --- multipliers ------------------------------------------------------------------
    def multipliers_given_accelerations(self, tau: sp.Matrix) -> sp.Matrix:
        """λ(q, q̇, η̇, τ): the dependent rows of (9) with q̈ = S η̇ + Ṡ η — the route of (10)–(12).

        A_dᵀ λ = (B τ − H − M q̈)_d.
        """
        qdd = self.null_space * sp.Matrix(self.eta_dot) + self.null_space_rate
        rhs = self.input_matrix * tau - self.bias.subs(self.on_manifold) - self.mass_matrix * qdd
        a_d_inv_t = self.dependent_block_inverse.T
        return (a_d_inv_t * self._rows(rhs, self.dependent)).applyfunc(self.simplify)

    def multipliers_given_full_accelerations(self, tau: sp.Matrix) -> sp.Matrix:
        """λ(q, q̇, q̈, τ) from the dependent rows of (9) alone, without the constraints."""
        rhs = self.input_matrix * tau - self.bias - self.mass_matrix * sp.Matrix(self.qddot)
        return self.dependent_block_inverse.T * self._rows(rhs, self.dependent)

    # --- (14): reduced, multiplier-free form ------------------------------------------
    def _require_unactuated_dependent_rows(self) -> None:
        b_d = self._rows(self.input_matrix, self.dependent)
        if any(e != 0 for e in b_d):
            raise ValueError(
                "the reduced form (14) assumes the inputs act on independent coordinates "
                "only (the dependent rows of B must be zero)"
            )

    @cached_property
    def reduced_mass_matrix(self) -> sp.Matrix:
        """M̃ of (14).

        Dependent rows: M_d q̈ + H_d + A_dᵀ λ(q, q̇, η̇) = 0 reduces to M_d q̈ − (M S)_d η̇ − (M Ṡ η)_d,
        i.e. M_dd (q̈_d − S_d η̇ − (Ṡη)_d) = 0: the constraints' second derivative weighted by M.
        Independent rows: (9)ᵢ with λ from (9)_d: M_i − A_iᵀ A_d⁻ᵀ M_d. M̃ is not symmetric.
        """
        self._require_unactuated_dependent_rows()
        m = self.mass_matrix
        n = len(self.q)
        out = sp.zeros(n, n)
        ms = m * self.null_space
        for i in self.dependent:
            out[i, :] = m[i, :]
            for col, j in enumerate(self.independent):
                out[i, j] = m[i, j] - ms[i, col]
        a_i = self._cols(self.constraint_matrix, self.independent)
        g = a_i.T * self.dependent_block_inverse.T  # A_iᵀ A_d⁻ᵀ
        m_d = self._rows(m, self.dependent)
        m_ind = self._rows(m, self.independent) - g * m_d
        for row, i in enumerate(self.independent):
            out[i, :] = m_ind[row, :]
        return out.applyfunc(self.simplify)

    @cached_property
    def reduced_bias(self) -> sp.Matrix:
        """H̃ of (14): −(M Ṡ η)_d in the dependent rows, H_i − A_iᵀ A_d⁻ᵀ H_d in the others."""
        self._require_unactuated_dependent_rows()
        n = len(self.q)
        out = sp.zeros(n, 1)
        ms_rate = self.mass_matrix * self.null_space_rate
        for i in self.dependent:
            out[i] = -ms_rate[i]
        a_i = self._cols(self.constraint_matrix, self.independent)
        g = a_i.T * self.dependent_block_inverse.T
        h_ind = self._rows(self.bias, self.independent) - g * self._rows(self.bias, self.dependent)
        for row, i in enumerate(self.independent):
            out[i] = h_ind[row]
        return out.applyfunc(self.simplify)

    # --- forward dynamics -------------------------------------------------------------
    @cached_property
    def minimal_mass_matrix_inverse(self) -> sp.Matrix:
        """(Sᵀ M S)⁻¹ by cofactors: the minimal form has as many rows as inputs (2 for a WMR)."""
        return inverse_by_cofactors(self.minimal_mass_matrix, self.simplify)

    def minimal_forward_dynamics(self, tau: sp.Matrix) -> sp.Matrix:
        """η̇ = (Sᵀ M S)⁻¹ (Sᵀ B τ − Sᵀ(M Ṡ η + H)) as adj(M̄)(rhs)/det(M̄), left unexpanded.

        Expanding the product would multiply out parameter polynomials (over 100 mul after
        CSE for two outputs); kept as a product, CSE shares the entries of M̄ and H̄.
        """
        adj, det = adjugate_and_determinant(self.minimal_mass_matrix, self.simplify)
        rhs = self.minimal_input_matrix * tau - self.minimal_bias
        return (adj * rhs) / det

    def reduced_forward_dynamics(self, tau: sp.Matrix) -> sp.Matrix:
        """q̈ solving (14) with u = B τ, by structured elimination instead of a 5×5 solve.

        The dependent rows of (14) say M_dd (q̈_d − S_d η̇ − (Ṡη)_d) = 0 and M_dd is a
        positive-definite block, so q̈ = S η̇ + Ṡ η. The independent rows times S give
        (M_i − A_iᵀA_d⁻ᵀ M_d) S = Sᵀ M S because S_d = −A_d⁻¹ A_i, so η̇ is the minimal
        form's. (The tests check this against a numerical solve of (14) and of the KKT
        system.) Only η = q̇ᵢ enters: q̇ is taken on the constraint manifold.
        """
        return self.null_space * self.minimal_forward_dynamics(tau) + self.null_space_rate

    def compact_forward_dynamics(
        self, tau: sp.Matrix, form: Simplifier
    ) -> tuple[sp.Matrix, sp.Matrix]:
        """(η̇, q̈) for evaluation: the same values as ``minimal_forward_dynamics`` and
        ``reduced_forward_dynamics``, arranged so that CSE finds the shared factors.

        ``form`` puts each entry of Sᵀ M S in a grouped, unexpanded form (the robot knows
        which groups: for the WMR, powers of r/b times the inertia about the axle); H̄, S
        and Ṡη are factored; the 2×2 solve is written out with 1/det computed once.
        Expanded polynomials in the parameters, which the canonical forms above use,
        cost about twice the multiplications. Tests check both forms are equal.
        """
        mbar = self.minimal_mass_matrix.applyfunc(form)
        if mbar.shape != (2, 2):
            raise ValueError("compact_forward_dynamics is written for two independent speeds")
        hbar = self.minimal_bias.applyfunc(sp.factor)
        rhs = self.minimal_input_matrix * tau - hbar
        inv_det = 1 / (mbar[0, 0] * mbar[1, 1] - mbar[0, 1] * mbar[1, 0])
        eta_dot = sp.Matrix([
            mbar[1, 1] * rhs[0] - mbar[0, 1] * rhs[1],
            mbar[0, 0] * rhs[1] - mbar[1, 0] * rhs[0],
        ]) * inv_det
        qdd = self.null_space.applyfunc(sp.factor) * eta_dot + self.null_space_rate.applyfunc(
            sp.factor
        )
        return eta_dot, qdd

    @cached_property
    def reduced_mass_matrix_inverse(self) -> sp.Matrix:
        """M̃⁻¹ of (14) by block elimination.

        M̃ x = y: the dependent rows give x_d = S_d xᵢ + M_dd⁻¹ y_d; substituting in the
        independent rows N_d x_d + N_i xᵢ = yᵢ with N_d S_d + N_i = Sᵀ M S gives
        xᵢ = (Sᵀ M S)⁻¹ (yᵢ − N_d M_dd⁻¹ y_d).
        """
        n = len(self.q)
        dep, ind = list(self.dependent), list(self.independent)
        m_dd_inv = inverse_by_cofactors(
            self.mass_matrix.extract(dep, dep), self.simplify
        )
        n_d = self.reduced_mass_matrix.extract(ind, dep)
        mbar_inv = self.minimal_mass_matrix_inverse
        s_d = self.null_space.extract(dep, list(range(len(ind))))
        # x_i = Mbar⁻¹ [ −N_d M_dd⁻¹ | I ] y ;  x_d = S_d x_i + [ M_dd⁻¹ | 0 ] y
        e_d = sp.zeros(len(dep), n)
        e_i = sp.zeros(len(ind), n)
        for row, i in enumerate(dep):
            e_d[row, i] = 1
        for row, i in enumerate(ind):
            e_i[row, i] = 1
        x_i = mbar_inv * (e_i - n_d * m_dd_inv * e_d)
        x_d = s_d * x_i + m_dd_inv * e_d
        out = sp.zeros(n, n)
        for row, i in enumerate(dep):
            out[i, :] = x_d[row, :]
        for row, i in enumerate(ind):
            out[i, :] = x_i[row, :]
        return out  # left unexpanded: CSE shares the blocks; tests check M̃ M̃⁻¹ = I numerically

    def kkt_matrix(self) -> tuple[sp.Matrix, sp.Matrix]:
        """The saddle-point system of (9) with A q̈ + Ȧ q̇ = 0, for tests:
        [[M, Aᵀ], [A, 0]] [q̈; λ] = [B τ − H; −Ȧ q̇] returns (lhs, rhs-without-Bτ)."""
        a = self.constraint_matrix
        k = a.rows
        lhs = sp.BlockMatrix([[self.mass_matrix, a.T], [a, sp.zeros(k, k)]]).as_explicit()
        rhs = sp.Matrix.vstack(-self.bias, -self.constraint_rate_term)
        return lhs, rhs
