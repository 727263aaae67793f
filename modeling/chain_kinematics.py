"""S(q) and Ṡ η of a planar hitch chain in O(n): its wheel constraints read the hitch
velocities.

With absolute yaws, a constraint row r of body k (the rolling or no side slip of one of
its wheels) is n_r · (velocity of a point of body k) plus its wheel's spin, and that
velocity is the hitch velocity P_k = (ẋ, ẏ) + Σ_{j<k} e_j θ̇_j plus body k's own turning:
A_r q̇ = c_r(θ_k) · P_k + Σ_o A_ro(θ_k) q̇_o over body k's own coordinates o (its yaw and
wheel angles), with e_j the hitch velocity per yaw rate of ``modeling.chain_inertia``.
Solved body by body in chain order, each body's block reads its parent's P_k (a named
quantity, P_{k+1} = P_k + e_k θ̇_k), so S costs O(1) a body where A's rows, multiplied
out, carry a term for every body ahead (O(n²)).

Ṡ η, the part of q̈ = S η̇ + Ṡ η without accelerations (the twist's, ``rates``), solves
the same blocks: A (Ṡ η) = −Ȧ v, and for row r of body k, Ȧ v = ċ_r · P_k(v) + c_r ·
Σ_{j<k} e'_j θ̇_j² + Σ_o Ȧ_ro v_o, so that the hitch's acceleration P̃_{k+1} = P̃_k +
e_k (Ṡ η)_{θk} + e'_k θ̇_k² is again a prefix sum (the centripetal terms of each hitch).

The structure is checked on A exactly (:func:`chain_kinematics`); None otherwise.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import sympy as sp

from modeling.chain_inertia import ChainInertia, Vector
from modeling.staged import Stage


@dataclass(frozen=True)
class ChainBody:
    """The constraint rows of one body of the chain and the coordinates they solve."""

    rows: tuple[int, ...]
    own: tuple[int, ...]  # the body's own coordinates (the root's: every one its rows read)
    entries: sp.Matrix  # A[rows, own]
    directions: tuple[Vector, ...]  # c_r (the root's rows: unused, zero)
    direction_rates: tuple[Vector, ...]  # ċ_r (∂c_r/∂θ_k θ̇_k)
    own_rates: tuple[sp.Expr, ...]  # Σ_o Ȧ_ro q̇_o (the root's rows: Ȧ_r q̇ whole)


@dataclass(frozen=True)
class ChainKinematics:
    """A's rows grouped by body along ``chain`` (see the module docstring); q̇ symbols
    stand for the velocities at which the rate terms are evaluated."""

    chain: ChainInertia
    qdot: tuple[sp.Symbol, ...]
    bodies: tuple[ChainBody, ...]
    simplify: Callable[[sp.Expr], sp.Expr]

    def at(self, point: Mapping[sp.Symbol, sp.Expr]) -> ChainKinematics:
        """Every quantity evaluated at ``point`` (the root frame's), the rates taken in
        the absolute yaws first."""
        def vec(vs: tuple[Vector, ...]) -> tuple[Vector, ...]:
            return tuple((a.xreplace(point), b.xreplace(point)) for a, b in vs)
        bodies = tuple(ChainBody(b.rows, b.own, b.entries.xreplace(point), vec(b.directions),
                                 vec(b.direction_rates),
                                 tuple(e.xreplace(point) for e in b.own_rates))
                       for b in self.bodies)
        return ChainKinematics(self.chain.at(point), self.qdot, bodies, self.simplify)

    def _solve(self, stage: Stage, known: Mapping[int, sp.Expr],
               rhs: Callable[[int, ChainBody], list[sp.Expr]],
               extra: Sequence[Vector] | None = None) -> list[sp.Expr]:
        """The column x with A x = the right-hand sides ``rhs(k, body)`` and x = ``known``
        on the coordinates given: body by body, P_k from the parent's (``extra``: added to
        each hitch step)."""
        chain = self.chain
        n = len(self.qdot)
        x: list[sp.Expr | None] = [None] * n
        for i, value in known.items():
            x[i] = value
        p: Vector = (sp.S.Zero, sp.S.Zero)
        for k, body in enumerate(self.bodies):
            b = rhs(k, body)
            if k == 0:
                unknown = [c for c in body.own if c not in known]
                given = [c for c in body.own if c in known]
                b = [b[r] - sum((body.entries[r, body.own.index(c)] * known[c]
                                 for c in given), sp.S.Zero) for r in range(len(b))]
                cols = [body.own.index(c) for c in unknown]
                block = body.entries.extract(list(range(len(body.rows))), cols)
            else:
                step = chain.hitches[k - 1]
                yaw = x[chain.yaws[k - 1]]
                assert yaw is not None
                px = p[0] + step[0] * yaw + (extra[k - 1][0] if extra else 0)
                py = p[1] + step[1] * yaw + (extra[k - 1][1] if extra else 0)
                p = (stage.define(px), stage.define(py))
                b = [b[r] - c[0] * p[0] - c[1] * p[1]
                     for r, c in enumerate(body.directions)]
                unknown, block = list(body.own), body.entries
            solved = stage.solve_general(block, sp.Matrix(b), self.simplify)
            for r, c in enumerate(unknown):
                x[c] = solved[r]
            if k == 0:
                xx, xy = x[chain.x], x[chain.y]
                assert xx is not None and xy is not None
                p = (xx, xy)
        assert all(e is not None for e in x)
        return [sp.S.Zero if e is None else e for e in x]

    def solves(self, independent: Sequence[int]) -> bool:
        """Whether the ``independent`` coordinates are the root's and leave its rows a
        square block (the other bodies' always are)."""
        own = self.bodies[0].own
        return set(independent) <= set(own) and len(own) - len(independent) == len(
            self.bodies[0].rows)

    def null_space(self, stage: Stage, independent: Sequence[int]) -> sp.Matrix:
        """S with A S = 0, the ``independent`` coordinates' velocities free."""
        columns = []
        for a in range(len(independent)):
            known = {i: sp.S.One if c == a else sp.S.Zero for c, i in enumerate(independent)}
            columns.append(self._solve(stage, known, lambda _k, body: [sp.S.Zero]
                                       * len(body.rows)))
        return sp.Matrix(len(self.qdot), len(independent),
                         lambda i, j: columns[j][i])

    def velocity_product(self, stage: Stage, v: Sequence[sp.Expr],
                         known: Mapping[int, sp.Expr]) -> sp.Matrix:
        """Ṡ η: A (Ṡ η) = −Ȧ v, (Ṡ η) = ``known`` on the independent coordinates; v the
        velocities (q̇ on the manifold) as quantities."""
        chain = self.chain
        at_v = {self.qdot[i]: v[i] for i in range(len(v))}
        sq = [stage.define(v[i] ** 2) for i in chain.yaws]
        extra = [(stage.define(a * s), stage.define(b * s))
                 for (a, b), s in zip(chain.hitch_slopes, sq, strict=True)]
        hitch_v: list[Vector] = [(v[chain.x], v[chain.y])]
        for k in range(len(chain.yaws) - 1):
            e, yaw = chain.hitches[k], v[chain.yaws[k]]
            hitch_v.append((stage.define(hitch_v[-1][0] + e[0] * yaw),
                            stage.define(hitch_v[-1][1] + e[1] * yaw)))

        def rhs(k: int, body: ChainBody) -> list[sp.Expr]:
            if k == 0:
                return [-stage.define(e.xreplace(at_v)) for e in body.own_rates]
            px, py = hitch_v[k]
            return [-stage.define(dc[0].xreplace(at_v) * px + dc[1].xreplace(at_v) * py
                                  + own.xreplace(at_v))
                    for dc, own in zip(body.direction_rates, body.own_rates, strict=True)]

        out = self._solve(stage, known, rhs, extra)
        return sp.Matrix([stage.define(e) for e in out])


def chain_kinematics(chain: ChainInertia, constraint: sp.Matrix, q: Sequence[sp.Symbol],
                     qdot: Sequence[sp.Symbol], simplify: Callable[[sp.Expr], sp.Expr]
                     ) -> ChainKinematics | None:
    """A's rows grouped by the body of ``chain`` they constrain, the coupling through the
    hitch velocities checked exactly; None when A is not of that form."""
    angles = [q[i] for i in chain.yaws]
    qs = set(q)
    groups: dict[int, list[int]] = {}
    for r in range(constraint.rows):
        row = constraint[r, :]
        present = row.free_symbols | {q[c] for c in range(len(q)) if row[c] != 0}
        ks = [k for k, t in enumerate(angles) if t in present]
        groups.setdefault(max(ks) if ks else 0, []).append(r)
    if sorted(groups) != list(range(len(angles))):
        return None
    bodies: list[ChainBody] = []
    claimed: set[int] = set()
    for k in range(len(angles)):
        rows = groups[k]
        ahead = {chain.x, chain.y, *chain.yaws[:k]} if k else set()
        own = sorted({c for r in rows for c in range(len(q)) if constraint[r, c] != 0}
                     - ahead)
        if claimed & set(own) or (k and len(own) != len(rows)):
            return None
        claimed |= set(own)
        theta = angles[k]
        entries = constraint.extract(rows, own)
        if entries.free_symbols & qs - {theta}:
            return None
        directions: list[Vector] = []
        direction_rates: list[Vector] = []
        own_rates: list[sp.Expr] = []
        for r in rows:
            if k == 0:
                directions.append((sp.S.Zero, sp.S.Zero))
                direction_rates.append((sp.S.Zero, sp.S.Zero))
                own_rates.append(sum((sp.diff(constraint[r, c], theta) * qdot[chain.yaws[0]]
                                      * qdot[c] for c in own), sp.S.Zero))
                continue
            c = (constraint[r, chain.x], constraint[r, chain.y])
            if (c[0].free_symbols | c[1].free_symbols) & qs - {theta}:
                return None
            for j in range(k):
                e = chain.hitches[j]
                if simplify(sp.expand(constraint[r, chain.yaws[j]] - c[0] * e[0]
                                      - c[1] * e[1])) != 0:
                    return None
            directions.append(c)
            direction_rates.append((sp.diff(c[0], theta) * qdot[chain.yaws[k]],
                                    sp.diff(c[1], theta) * qdot[chain.yaws[k]]))
            own_rates.append(sum((sp.diff(constraint[r, o], theta) * qdot[chain.yaws[k]]
                                  * qdot[o] for o in own), sp.S.Zero))
        bodies.append(ChainBody(tuple(rows), tuple(own), entries, tuple(directions),
                                tuple(direction_rates), tuple(own_rates)))
    if claimed != set(range(len(q))) or not {chain.x, chain.y} <= set(bodies[0].own):
        return None
    return ChainKinematics(chain, tuple(qdot), tuple(bodies), simplify)
