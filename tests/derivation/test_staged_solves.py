"""The staged solves of modeling/staged.py on every branch, against a dense numeric solve.

No shipped robot reaches the branches beyond ``CLOSED_FORM_MAX`` unknowns (the unrolled LDLᵀ
of :meth:`Stage.solve`, the unrolled LU of :meth:`Stage.solve_general`): a robot with more
driven wheels or more trailers than the shipped ones would. Here each branch is built over
symbolic entries, evaluated in order at random numbers (``staged.evaluate``), and compared
with NumPy's LAPACK solve: a wrong factor, a wrong index or a wrong order in the triangular
solves is an error of order one, far above the 1e-10 allowed.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from modeling.staged import CLOSED_FORM_MAX, Stage, evaluate

RTOL = 1e-10


def _symbols(name: str, rows: int, cols: int) -> sp.Matrix:
    return sp.Matrix(rows, cols, lambda i, j: sp.Symbol(f"{name}_{i}_{j}", real=True))


def _staged_solution(stage: Stage, a: sp.Matrix, b: sp.Matrix, x: sp.Matrix,
                     values: dict[sp.Symbol, float]) -> np.ndarray:
    exprs = list(x)
    out = evaluate(stage.definitions_for(exprs), exprs, values)
    return np.array(out).reshape(x.rows, x.cols)


@pytest.mark.parametrize("n", [2, 3, 4, 5, 6])
def test_symmetric_solve_matches_a_dense_solve(n: int) -> None:
    """``Stage.solve`` (closed form up to 3 unknowns, LDLᵀ beyond) for a symmetric positive
    definite a with two right-hand sides."""
    rng = np.random.default_rng(100 + n)
    sym = _symbols("a", n, n)
    a = sp.Matrix(n, n, lambda i, j: sym[min(i, j), max(i, j)])  # symmetric by construction
    b = _symbols("b", n, 2)
    r = rng.normal(size=(n, n))
    a_num = r @ r.T + n * np.eye(n)
    b_num = rng.normal(size=(n, 2))
    values = {sym[i, j]: float(a_num[i, j]) for i in range(n) for j in range(i, n)}
    values |= {b[i, j]: float(b_num[i, j]) for i in range(n) for j in range(2)}
    stage = Stage()
    x = stage.solve(a, b)
    got = _staged_solution(stage, a, b, x, values)
    want = np.linalg.solve(a_num, b_num)
    np.testing.assert_allclose(got, want, rtol=RTOL, atol=RTOL * np.abs(want).max())
    if n > CLOSED_FORM_MAX:  # the LDLᵀ branch: n pivots, each a quantity, no determinant
        assert sum(1 for e in stage.definitions.values()
                   if isinstance(e, sp.Pow) and e.exp == -1) == n


@pytest.mark.parametrize("n", [2, 3, 4, 5])
def test_general_solve_matches_a_dense_solve(n: int) -> None:
    """``Stage.solve_general`` (closed form up to 3 unknowns, LU in the given order beyond)
    for a non-symmetric a, with structural zeros below the diagonal (the skipped
    eliminations) and a full one."""
    rng = np.random.default_rng(200 + n)
    full = _symbols("g", n, n)
    for zeros in (False, True):
        a = sp.Matrix(n, n, [0 if (zeros and i > j + 1) else full[i, j]
                             for i in range(n) for j in range(n)])
        b = _symbols("c", n, 1)
        a_num = rng.normal(size=(n, n)) + 3 * n * np.eye(n)  # diagonally dominant: no pivot
        if zeros:
            a_num = np.where(np.tril(np.ones((n, n)), -2) > 0, 0.0, a_num)
        b_num = rng.normal(size=(n, 1))
        values = {full[i, j]: float(a_num[i, j]) for i in range(n) for j in range(n)}
        values |= {b[i, 0]: float(b_num[i, 0]) for i in range(n)}
        stage = Stage()
        x = stage.solve_general(a, b)
        got = _staged_solution(stage, a, b, x, values)
        want = np.linalg.solve(a_num, b_num)
        np.testing.assert_allclose(got, want, rtol=RTOL, atol=RTOL * np.abs(want).max())


def test_general_solve_refuses_a_structurally_zero_pivot() -> None:
    """LU without pivoting needs the unknowns ordered: a zero on the diagonal is refused,
    never divided by."""
    n = CLOSED_FORM_MAX + 1
    full = _symbols("z", n, n)
    a = sp.Matrix(n, n, lambda i, j: 0 if i == j == 0 else full[i, j])
    with pytest.raises(ZeroDivisionError, match="zero pivot 0"):
        Stage().solve_general(a, _symbols("d", n, 1))
