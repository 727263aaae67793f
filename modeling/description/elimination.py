"""Exact generic rank and a block-triangular inverse for constraint blocks of any size.

``ConstrainedSystem`` inverts the dependent block A_d of the constraint matrix by cofactors,
which ``modeling.symbolic_linalg`` limits to 3×3. A robot with a trailer has a 6×6 A_d,
but a sparse one: the tractor's rows involve only the tractor's velocities, the trailer's
no-side-slip row adds the trailer's yaw rate, and each passive wheel's rolling row adds only
that wheel's rate. Permuted to block lower-triangular form (a perfect matching of rows to
columns, then the strongly connected components of the dependency graph) the diagonal
blocks are at most 3×3, and block forward substitution keeps every entry a polynomial in
sin/cos over a parameter-only determinant, as the cofactor route does for the WMR.

Ranks are decided exactly: each angle's (sin, cos) becomes a rational point on the unit
circle, ((1 − t²)/(1 + t²), 2t/(1 + t²)) with random rational t, and each parameter a
rational number, so that the rank works over ℚ with no rounding threshold. Ranks and
determinants of those rational matrices are taken over SymPy's domain ℚ
(``DomainMatrix``, fraction-free): ``Matrix.rank`` on the same numbers treats them as
expressions and its time grows about threefold a row (a 17-row block of the five-cart
train: 30 s; ℚ: milliseconds), for the same exact answer.
"""

from __future__ import annotations

import random
from collections.abc import Mapping

import sympy as sp
from sympy.polys.matrices import DomainMatrix
from sympy.utilities.iterables import strongly_connected_components

from modeling.staged import Stage
from modeling.symbolic_linalg import Simplifier, inverse_by_cofactors


def _identity(expr: sp.Expr) -> sp.Expr:
    return expr


def _perfect_matching(nonzero: list[list[bool]]) -> list[int] | None:
    """column[i] matched to row i with nonzero[i][column[i]] (Kuhn's augmenting paths,
    rows and columns tried in index order so the result is deterministic)."""
    n = len(nonzero)
    row_of: list[int | None] = [None] * n

    def augment(i: int, seen: set[int]) -> bool:
        for j in range(n):
            if nonzero[i][j] and j not in seen:
                seen.add(j)
                k = row_of[j]
                if k is None or augment(k, seen):
                    row_of[j] = i
                    return True
        return False

    for i in range(n):
        if not augment(i, set()):
            return None
    column = [0] * n
    for j, row in enumerate(row_of):
        assert row is not None
        column[row] = j
    return column


def block_triangular_inverse(matrix: sp.Matrix, simplify: Simplifier = _identity) -> sp.Matrix:
    """A⁻¹ by block forward substitution on the block-triangular form of A.

    Raises ZeroDivisionError if A is structurally singular (no perfect matching) or a
    diagonal block has a zero determinant. Diagonal blocks up to 3×3 use cofactors; larger
    ones (a dense coupling) fall back to SymPy's LU inverse.
    """
    n = matrix.rows
    if matrix.cols != n:
        raise ValueError(f"square matrix expected, got {matrix.shape}")
    a = matrix.applyfunc(simplify)
    nonzero = [[a[i, j] != 0 for j in range(n)] for i in range(n)]
    column = _perfect_matching(nonzero)
    if column is None:
        raise ZeroDivisionError("the block is structurally singular (no perfect matching)")
    row_solving = {column[i]: i for i in range(n)}
    # Row i depends on row k if it involves the unknown (column) that row k is matched to.
    edges = [(i, row_solving[j]) for i in range(n) for j in range(n)
             if nonzero[i][j] and row_solving[j] != i]
    blocks = strongly_connected_components((list(range(n)), edges))  # dependencies first
    inverse = sp.zeros(n, n)
    done: list[int] = []  # columns already expressed through the right-hand side
    for rows in blocks:
        rows = sorted(rows)
        cols = [column[i] for i in rows]
        rhs = sp.eye(n).extract(rows, list(range(n)))
        if done:
            rhs -= a.extract(rows, done) * inverse.extract(done, list(range(n)))
        diag = a.extract(rows, cols)
        if diag.rows <= 3:
            diag_inv = inverse_by_cofactors(diag, simplify)
        else:
            diag_inv = diag.inv(method="LU").applyfunc(simplify)
        solved = (diag_inv * rhs).applyfunc(simplify)
        for r, c in enumerate(cols):
            inverse[c, :] = solved[r, :]
        done += cols
    return inverse


def block_triangular_solve(stage: Stage, matrix: sp.Matrix, rhs: sp.Matrix,
                           simplify: Simplifier = _identity) -> sp.Matrix:
    """x with A x = rhs through ``stage``'s quantities, by block forward substitution on
    A's block-triangular form (as ``block_triangular_inverse``): each diagonal block
    solved in the stage (``Stage.solve_general``), each solved unknown a quantity the
    later blocks read. The cost grows with the number of blocks, not combinatorially as
    the closed-form inverse does along a chain of trailers."""
    n = matrix.rows
    if matrix.cols != n:
        raise ValueError(f"square matrix expected, got {matrix.shape}")
    nonzero = [[matrix[i, j] != 0 for j in range(n)] for i in range(n)]
    column = _perfect_matching(nonzero)
    if column is None:
        raise ZeroDivisionError("the block is structurally singular (no perfect matching)")
    row_solving = {column[i]: i for i in range(n)}
    edges = [(i, row_solving[j]) for i in range(n) for j in range(n)
             if nonzero[i][j] and row_solving[j] != i]
    x = sp.zeros(n, rhs.cols)
    done: list[int] = []
    for rows in strongly_connected_components((list(range(n)), edges)):
        rows = sorted(rows)
        cols = [column[i] for i in rows]
        b = rhs.extract(rows, list(range(rhs.cols)))
        if done:
            b -= matrix.extract(rows, done) * x.extract(done, list(range(rhs.cols)))
        solved = stage.solve_general(matrix.extract(rows, cols), b, simplify)
        for r, c in enumerate(cols):
            x[c, :] = solved[r, :]
        done += cols
    return x


# ---------------------------------------------------------------------------------------
# Exact evaluation at random rational points
# ---------------------------------------------------------------------------------------
def _rational(x: float) -> sp.Rational:
    return sp.Rational(repr(float(x)))


def rational_point(
    exprs: sp.MatrixBase,
    seed: int,
    values: Mapping[sp.Symbol, float] | None = None,
) -> dict[sp.Basic, sp.Rational]:
    """A substitution sending every sin(θ), cos(θ) in ``exprs`` to a rational point on the
    unit circle and every other symbol to its value (if in ``values``) or to a random
    rational in [1/2, 2]."""
    rng = random.Random(seed)
    subs: dict[sp.Basic, sp.Rational] = {}
    angles = sorted({f.args[0] for f in exprs.atoms(sp.sin, sp.cos)}, key=sp.default_sort_key)
    for angle in angles:
        t = sp.Rational(rng.randint(-997, 997), rng.randint(1, 997))
        subs[sp.cos(angle)] = (1 - t**2) / (1 + t**2)
        subs[sp.sin(angle)] = 2 * t / (1 + t**2)
    for symbol in sorted(exprs.free_symbols, key=sp.default_sort_key):
        if values is not None and symbol in values:
            subs[symbol] = _rational(values[symbol])
        else:
            subs[symbol] = sp.Rational(rng.randint(500, 2000), 1000)
    return subs


def exact_rank(matrix: sp.Matrix) -> int:
    """The rank of a matrix of rational numbers, exactly (over ℚ)."""
    if matrix.rows == 0 or matrix.cols == 0:
        return 0
    return int(DomainMatrix.from_Matrix(matrix).convert_to(sp.QQ).rank())


def exact_det_is_zero(matrix: sp.Matrix) -> bool:
    """Whether a square matrix of rational numbers is singular, exactly (over ℚ)."""
    return exact_rank(matrix) < matrix.rows


def evaluate_exactly(matrix: sp.Matrix, subs: Mapping[sp.Basic, sp.Rational]) -> sp.Matrix:
    """``matrix`` at a rational point; every entry must come out rational (the angles
    occur only inside sin/cos)."""
    out = matrix.xreplace(dict(subs))
    bad = [e for e in out if not e.is_Rational]
    if bad:
        raise ValueError(f"not a rational number after substitution: {bad[0]}")
    return out
