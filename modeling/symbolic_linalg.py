"""Structured symbolic linear algebra: elimination instead of inverses.

A symbolic ``Matrix.inv()`` or ``LUsolve`` on a dense 5×5 expands every entry into a
sum over permutations. Eliminating in a fixed pivot order while skipping entries that
are structurally zero keeps the expressions close to what a hand derivation would give
and lets CSE share the pivots (see the op counts in the generated report).
"""

from __future__ import annotations

from collections.abc import Callable

import sympy as sp

Simplifier = Callable[[sp.Expr], sp.Expr]


def _identity(expr: sp.Expr) -> sp.Expr:
    return expr


def adjugate_and_determinant(
    matrix: sp.Matrix, simplify: Simplifier = _identity
) -> tuple[sp.Matrix, sp.Expr]:
    """(adj A, det A) for the small blocks of a structured elimination (n ≤ 3).

    Kept apart so that callers multiply polynomials and divide once at the end: expanding
    a product that already carries 1/det is what makes naive symbolic solves explode.
    The determinant is simplified once, so for a mass-matrix block or the constraint block
    it collapses to a parameter expression free of the configuration (e.g. det A_d = b).
    """
    if matrix.rows != matrix.cols or matrix.rows > 3:
        raise ValueError(f"cofactor inversion is for blocks up to 3×3, got {matrix.shape}")
    det = sp.factor(simplify(matrix.det(method="berkowitz")))
    if det == 0:
        raise ZeroDivisionError("the block is structurally singular")
    return matrix.adjugate(method="berkowitz").applyfunc(simplify), det


def inverse_by_cofactors(matrix: sp.Matrix, simplify: Simplifier = _identity) -> sp.Matrix:
    """adj(A) / det(A), each entry simplified (see adjugate_and_determinant)."""
    adj, det = adjugate_and_determinant(matrix, simplify)
    return adj.applyfunc(lambda e: simplify(e / det))


def time_derivative(
    expr: sp.MatrixBase | sp.Expr,
    coordinates: tuple[sp.Symbol, ...],
    velocities: tuple[sp.Symbol, ...],
    accelerations: tuple[sp.Symbol, ...] | None = None,
) -> sp.Expr:
    """d/dt of an expression in (q, q̇[, …]) by the chain rule, with plain symbols."""
    out = sum((sp.diff(expr, qi) * vi for qi, vi in zip(coordinates, velocities, strict=True)),
              sp.S.Zero * expr)
    if accelerations is not None:
        out = out + sum(
            (sp.diff(expr, vi) * ai for vi, ai in zip(velocities, accelerations, strict=True)),
            sp.S.Zero * expr,
        )
    return out
