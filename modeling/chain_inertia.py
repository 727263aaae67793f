"""M q̈ + H of a planar hitch chain in O(n): the composite-body structure of its mass matrix.

With absolute yaws, the kinetic energy of a tractor towing a chain of carts couples every
pair of bodies (body j's centre of mass moves with the yaw rate of every body ahead of
it), so M is dense in the yaws and Sᵀ M S, Sᵀ(M Ṡ η + H) multiplied out pair by pair cost
O(n²) (issue 51). The coupling has a rank-one structure along the chain, which is what
the composite-rigid-body and articulated-body algorithms (Featherstone) exploit:

* g_j = (M_{x θj}, M_{y θj}): the first moment of the subtree towed from body j's hitch,
  turned with θ_j (the base parameters ``K_θj_x`` and ``K_θj_x_2`` are its two
  components in body j's frame);
* e_i(θ_i): the velocity of body i's rear hitch per unit yaw rate of body i (J R(θ_i) h_i,
  h_i the hitch in body i's frame), so that M_{θi θj} = e_i · g_j for i before j;
* M_{θi θi}, the wheels' spin inertias and the (x, y) block: constant.

Then (M v)_{θi} = g_i · P_i + M_{θi θi} v_{θi} + e_i · Q_i, with P_i = (v_x, v_y) +
Σ_{j<i} e_j v_{θj} (body i's hitch velocity, a prefix sum) and Q_i = Σ_{j>i} g_j v_{θj} (a
suffix sum), each a 2-vector accumulated forwards or backwards in O(1) a body. Because
each M_ij depends on θ_i and θ_j only, (9)'s H_i = Σ_j ∂M_ij/∂q_j q̇_j²: the same sums
with g'_j = ∂g_j/∂θ_j, e'_j = ∂e_j/∂θ_j weighted by θ̇_j² (the hitches' centripetal
accelerations). Every accumulated sum is a named quantity of the stage, so CSE never sees
the n² products.

The structure is not assumed: :func:`chain_inertia` solves e_i from M's own entries (in
the base parameters) and checks M and H against it exactly (sin² + cos² = 1 reduced);
any robot whose M or H is not of this form (a tree, a potential, a coupling of a wheel's
spin) gets None and the dense products.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import sympy as sp

from modeling.staged import Stage

Vector = tuple[sp.Expr, sp.Expr]


@dataclass(frozen=True)
class ChainInertia:
    """The mass matrix of a planar hitch chain as its composite-body quantities (see the
    module docstring); ``yaws`` in chain order, from the root."""

    x: int
    y: int
    yaws: tuple[int, ...]
    position_block: sp.Matrix  # constant 2 × 2: M of (x, y)
    moments: tuple[Vector, ...]  # g_j
    moment_slopes: tuple[Vector, ...]  # g'_j = ∂g_j/∂θ_j
    hitches: tuple[Vector, ...]  # e_i (the last body's is zero: it tows nothing)
    hitch_slopes: tuple[Vector, ...]  # e'_i = ∂e_i/∂θ_i
    diagonal: tuple[sp.Expr, ...]  # M_kk for every coordinate (x, y's read position_block)

    def at(self, point: Mapping[sp.Symbol, sp.Expr]) -> ChainInertia:
        """The same quantities evaluated at ``point`` (the root frame's substitution,
        after the slopes are taken in the absolute yaws)."""
        def vec(vs: tuple[Vector, ...]) -> tuple[Vector, ...]:
            return tuple((a.xreplace(point), b.xreplace(point)) for a, b in vs)
        return ChainInertia(self.x, self.y, self.yaws, self.position_block.xreplace(point),
                            vec(self.moments), vec(self.moment_slopes), vec(self.hitches),
                            vec(self.hitch_slopes),
                            tuple(d.xreplace(point) for d in self.diagonal))

    def product(self, stage: Stage, column: Sequence[sp.Expr],
                rates: Sequence[sp.Expr] | None = None) -> sp.Matrix:
        """M ``column`` (+ H at the velocities ``rates`` when given) through ``stage``, in
        O(n): the hitch velocities P_i forwards, the towed moments Q_i backwards."""
        n, k = len(self.diagonal), len(self.yaws)
        d = stage.define
        col = [column[i] for i in self.yaws]
        sq = [d(rates[i] ** 2) if rates is not None else sp.S.Zero for i in self.yaws]
        g = [(d(a), d(b)) for a, b in self.moments]
        gs = [(d(a), d(b)) for a, b in self.moment_slopes]
        e = [(d(a), d(b)) for a, b in self.hitches]
        es = [(d(a), d(b)) for a, b in self.hitch_slopes]
        prefix = self._hitch_velocities(stage, column, [(ax * q, ay * q) for (ax, ay), q
                                                        in zip(es, sq, strict=True)])
        suffix: list[Vector] = [(sp.S.Zero, sp.S.Zero)] * k
        total: Vector = (sp.S.Zero, sp.S.Zero)
        for i in reversed(range(k)):
            if i < k - 1:
                suffix[i] = total
            qx, qy = suffix[i]
            total = (d(qx + g[i][0] * col[i] + gs[i][0] * sq[i]),
                     d(qy + g[i][1] * col[i] + gs[i][1] * sq[i]))
        out = [d(self.diagonal[i] * column[i]) for i in range(n)]
        pos = self.position_block * sp.Matrix([column[self.x], column[self.y]])
        out[self.x] = d(pos[0] + total[0])
        out[self.y] = d(pos[1] + total[1])
        for i, yaw in enumerate(self.yaws):
            (gx, gy), (px, py), (ex, ey), (qx, qy) = g[i], prefix[i], e[i], suffix[i]
            out[yaw] = d(gx * px + gy * py + self.diagonal[yaw] * col[i] + ex * qx + ey * qy)
        return sp.Matrix(out)


    def _hitch_velocities(self, stage: Stage, column: Sequence[sp.Expr],
                          centripetal: Sequence[Vector] | None = None) -> list[Vector]:
        """P_i of ``column``: (v_x, v_y), then P_{i+1} = P_i + e_i v_θi (+ the hitch's
        ``centripetal`` term e'_i θ̇_i², for the accelerations)."""
        d = stage.define
        prefix: list[Vector] = [(column[self.x], column[self.y])]
        for i in range(len(self.yaws) - 1):
            (px, py), (ex, ey), rate = prefix[-1], self.hitches[i], column[self.yaws[i]]
            cx, cy = centripetal[i] if centripetal is not None else (sp.S.Zero, sp.S.Zero)
            prefix.append((d(px + d(ex) * rate + cx), d(py + d(ey) * rate + cy)))
        return prefix

    def congruence(self, stage: Stage, s: sp.Matrix) -> sp.Matrix:
        """Sᵀ M S forwards only: the suffix sums folded into the prefix ones,
        Σ_i S_iᵃ e_i · Q_iᵇ = Σ_j S_jᵇ g_j · (P_jᵃ − P_0ᵃ), so that

        (Sᵀ M S)_ab = P_0ᵃᵀ M_xy P_0ᵇ + Σ_i (S_iᵃ g_i · P_iᵇ + S_iᵇ g_i · P_iᵃ)
                      + Σ_k M_kk S_kᵃ S_kᵇ (k: the yaws and the wheels),

        each term added to a running sum body by body (a quantity each), so that a
        step's evaluation streams along the chain (few values live at once)."""
        k = s.cols
        return self._projected(stage, s, [s[:, b] for b in range(k)], None,
                               symmetric=True)

    def projected(self, stage: Stage, s: sp.Matrix, column: Sequence[sp.Expr],
                  rates: Sequence[sp.Expr]) -> sp.Matrix:
        """Sᵀ(M ``column`` + H(``rates``)) forwards only (as :meth:`congruence`, the
        column's g_j v_j with the towed moments' centripetal g'_j θ̇_j² added, its hitch
        accelerations with e'_j θ̇_j²)."""
        return self._projected(stage, s, [sp.Matrix(column)], rates, symmetric=False)[:, 0]

    def _projected(self, stage: Stage, s: sp.Matrix, columns: list[sp.Matrix],
                   rates: Sequence[sp.Expr] | None, symmetric: bool) -> sp.Matrix:
        d = stage.define
        k, n = s.cols, len(self.diagonal)
        g = [(d(a), d(b)) for a, b in self.moments]
        left = [self._hitch_velocities(stage, s[:, a]) for a in range(k)]
        if rates is None:
            right = left
            weight = [[(g[i][0] * columns[b][y], g[i][1] * columns[b][y])
                       for i, y in enumerate(self.yaws)] for b in range(len(columns))]
        else:
            sq = [d(rates[y] ** 2) for y in self.yaws]
            es = [(d(a) * q, d(b) * q) for (a, b), q in zip(self.hitch_slopes, sq,
                                                                strict=True)]
            column = columns[0]
            right = [self._hitch_velocities(stage, column, es)]
            weight = [[(g[i][0] * column[y] + d(a) * sq[i], g[i][1] * column[y] + d(b) * sq[i])
                       for i, (y, (a, b)) in enumerate(zip(self.yaws, self.moment_slopes,
                                                           strict=True))]]
        out = sp.zeros(k, len(columns))
        others = [i for i in range(n) if i not in (self.x, self.y)]
        for a in range(k):
            for b in range(len(columns)):
                if symmetric and b < a:
                    out[a, b] = out[b, a]
                    continue
                pa, pb = left[a][0], right[b][0]
                pos = (sp.Matrix([pa]) * self.position_block * sp.Matrix(pb))[0]
                total = d(pos + sum((self.diagonal[i] * s[i, a] * columns[b][i]
                                     for i in others if i not in self.yaws), sp.S.Zero))
                for i, yaw in enumerate(self.yaws):
                    (gx, gy), (wx, wy) = g[i], weight[b][i]
                    term = (s[yaw, a] * (gx * right[b][i][0] + gy * right[b][i][1])
                            + wx * left[a][i][0] + wy * left[a][i][1]
                            + self.diagonal[yaw] * s[yaw, a] * columns[b][yaw])
                    total = d(total + term)
                out[a, b] = total
        return out


def chain_inertia(mass: sp.Matrix, bias: sp.Matrix, q: Sequence[sp.Symbol],
                  qdot: Sequence[sp.Symbol], planar_frame: Sequence[int],
                  simplify: Callable[[sp.Expr], sp.Expr]) -> ChainInertia | None:
    """The chain structure of ``mass`` (and ``bias``, H of (9)) with the yaws of
    ``planar_frame`` (x, y, root yaw, the others) in chain order, checked exactly
    with ``simplify`` (a canonical form modulo sin² + cos² = 1); None when M or H is
    not of that form or the chain has fewer than two bodies."""
    if len(planar_frame) < 4:
        return None
    x, y, *yaws = planar_frame
    angles = [q[i] for i in yaws]
    n = len(q)
    block = {x, y, *yaws}
    qs = set(q)
    # Off the (x, y, yaws) block M is diagonal and constant; so are M_θiθi and (x, y).
    for i in range(n):
        for j in range(i, n):
            entry = mass[i, j]
            if (i == j or (i in (x, y) and j in (x, y))) and entry.free_symbols & qs:
                return None
            if i != j and not (i in block and j in block) and entry != 0:
                return None
    moments = [(mass[x, t], mass[y, t]) for t in yaws]
    for (a, b), theta in zip(moments, angles, strict=True):
        if (a.free_symbols | b.free_symbols) & qs - {theta}:
            return None
    hitches: list[Vector] = []
    for i in range(len(yaws) - 1):
        hitch = _hitch(mass[yaws[i], yaws[i + 1]], moments[i + 1], qs, simplify)
        if hitch is None or ({*hitch[0].free_symbols, *hitch[1].free_symbols}
                             & qs - {angles[i]}):
            return None
        hitches.append(hitch)
    hitches.append((sp.S.Zero, sp.S.Zero))
    for i in range(len(yaws)):
        for j in range(i + 1, len(yaws)):
            coupling = hitches[i][0] * moments[j][0] + hitches[i][1] * moments[j][1]
            if simplify(sp.expand(mass[yaws[i], yaws[j]] - coupling)) != 0:
                return None
    chain = ChainInertia(
        x, y, tuple(yaws), mass.extract([x, y], [x, y]), tuple(moments),
        tuple((sp.diff(a, t), sp.diff(b, t)) for (a, b), t in zip(moments, angles,
                                                                  strict=True)),
        tuple(hitches),
        tuple((sp.diff(a, t), sp.diff(b, t)) for (a, b), t in zip(hitches, angles,
                                                                  strict=True)),
        tuple(mass[i, i] for i in range(n)))
    if not _bias_matches(chain, bias, qdot, simplify):
        return None
    return chain


def _hitch(coupling: sp.Expr, moment: Vector, coordinates: set[sp.Symbol],
           simplify: Callable[[sp.Expr], sp.Expr]) -> Vector | None:
    """e with coupling = e · g for g = ``moment``, both linear in g's two parameters
    (its components in the towed body's frame): e = c A⁻¹ with g = A p, coupling = c p."""
    params = sorted((moment[0].free_symbols | moment[1].free_symbols) - coordinates,
                    key=str)
    if len(params) != 2 or any(sp.diff(m, p, 2) != 0 for m in moment for p in params):
        return None
    a = sp.Matrix(2, 2, lambda r, c: sp.diff(moment[r], params[c]))
    c = sp.Matrix(1, 2, lambda _, k: sp.diff(coupling, params[k]))
    if (a.free_symbols | c.free_symbols) & set(params):
        return None
    det = simplify(sp.expand(a.det()))
    if det == 0:
        return None
    e = c * a.adjugate()
    return simplify(sp.expand(e[0] / det)), simplify(sp.expand(e[1] / det))


def _bias_matches(chain: ChainInertia, bias: sp.Matrix, qdot: Sequence[sp.Symbol],
                  simplify: Callable[[sp.Expr], sp.Expr]) -> bool:
    """Whether H = Σ_j ∂M_ij/∂q_j q̇_j² (what M_ij depending on q_i, q_j only gives, with
    no potential) as the chain's sums, exactly."""
    k = len(chain.yaws)
    sq = [qdot[i] ** 2 for i in chain.yaws]
    want = [sp.S.Zero] * len(chain.diagonal)
    for c in range(2):
        want[(chain.x, chain.y)[c]] = sum((chain.moment_slopes[j][c] * sq[j]
                                           for j in range(k)), sp.S.Zero)
    for i, yaw in enumerate(chain.yaws):
        want[yaw] = sum((chain.moments[i][c] * chain.hitch_slopes[j][c] * sq[j]
                         for j in range(i) for c in range(2)), sp.S.Zero) + sum(
            (chain.hitches[i][c] * chain.moment_slopes[j][c] * sq[j]
             for j in range(i + 1, k) for c in range(2)), sp.S.Zero)
    return all(simplify(sp.expand(h - w)) == 0 for h, w in zip(bias, want, strict=True))


