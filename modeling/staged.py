"""Expressions evaluated through named intermediate quantities: how the derivation stays
small as a robot grows.

A closed form of a bigger robot's dynamics grows combinatorially: SᵀMS of a tractor with
two trailers, multiplied out, has tens of thousands of operations, and its inverse and
Jacobian more. Rigid-body libraries (Featherstone's algorithms, Pinocchio) and code
generators (CasADi) instead keep products and solves as steps of the evaluation. A
:class:`Stage` does that symbolically: it names each intermediate quantity (the entries
of M, S, SᵀMS, the factors of a solve, the derivatives of a quantity) by a symbol
defined from the inputs and from earlier quantities. Generated code evaluates the
definitions in order (``codegen.spec.FunctionSpec.definitions``), so a product costs a
product and a solve a solve, at the robot's numbers, never a multiplied-out expression.

What stays symbolic is what is cheap: the kinetic energy's M and H, the constraints' S,
each entry CSE'd. The solves are written over entry symbols: a closed form for up to
``CLOSED_FORM_MAX`` unknowns (one determinant, one reciprocal), an unrolled LDLᵀ beyond.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping

import sympy as sp

CLOSED_FORM_MAX = 3  # a solve with more unknowns is an unrolled LDLᵀ factorisation


class Stage:
    """Intermediate quantities of a generated function, in definition order.

    ``define`` names an expression (numbers and symbols are returned as they are);
    ``derivative`` differentiates through the definitions (forward mode, each derivative
    of a quantity itself a quantity); ``definitions_for`` lists what some expressions need.
    Symbols are ``<prefix><k>``: the prefix keeps two stages of one function apart.
    """

    def __init__(self, prefix: str = "_s") -> None:
        self.prefix = prefix
        self.definitions: dict[sp.Symbol, sp.Expr] = {}
        self._by_expr: dict[sp.Expr, sp.Symbol] = {}
        self._derivatives: dict[tuple[sp.Symbol, sp.Symbol], sp.Expr] = {}

    # --- naming ------------------------------------------------------------------------
    def define(self, expr: sp.Expr) -> sp.Expr:
        """A symbol standing for ``expr`` (the same symbol for the same expression, its
        negation for the negated one), or ``expr`` itself when it is a number or a
        symbol."""
        expr = sp.sympify(expr)
        if expr.is_Number or expr.is_Symbol or not expr.free_symbols or (-expr).is_Symbol:
            return expr  # a number, a symbol or a negated symbol: nothing to name
        hit = self._by_expr.get(expr)
        if hit is not None:
            return hit
        hit = self._by_expr.get(-expr)  # a negation is exact: no second quantity for it
        if hit is not None:
            return -hit
        sym = sp.Symbol(f"{self.prefix}{len(self.definitions)}", real=True)
        self.definitions[sym] = expr
        self._by_expr[expr] = sym
        return sym

    def matrix(self, m: sp.MatrixBase) -> sp.Matrix:
        """``m`` with every entry defined."""
        return sp.Matrix(m.rows, m.cols, [self.define(e) for e in m])

    def is_quantity(self, s: sp.Basic) -> bool:
        return isinstance(s, sp.Symbol) and s in self.definitions

    def _is_leaf(self, e: sp.Expr) -> bool:
        """Whether ``e`` is a number, an input, or a quantity defined from inputs only (or
        the negation of one: ``define`` returns −s for a negated definition)."""
        if e.could_extract_minus_sign():
            e = -e
        if not self.is_quantity(e):
            return not (e.free_symbols & self.definitions.keys())
        return not (self.definitions[e].free_symbols & self.definitions.keys())

    # --- solves ------------------------------------------------------------------------
    def solve(self, a: sp.MatrixBase, b: sp.MatrixBase) -> sp.Matrix:
        """x with a x = b for a symmetric positive definite ``a`` (entries defined first).

        Up to ``CLOSED_FORM_MAX`` unknowns: adj(a) b / det(a), the reciprocal of the
        determinant computed once. Beyond: a = L D Lᵀ, unrolled (no pivoting: a is
        positive definite), then the two triangular solves; every factor a quantity."""
        a, b = self.matrix(a), self.matrix(b)
        n = a.rows
        if n <= CLOSED_FORM_MAX:
            inv_det = self.define(1 / self.define(a.det(method="berkowitz")))
            adj = a.adjugate()
            return sp.Matrix(n, b.cols, lambda i, j: self.define(
                sum((adj[i, k] * b[k, j] for k in range(n)), sp.S.Zero) * inv_det))
        lower = sp.eye(n)
        diag: list[sp.Expr] = []
        for j in range(n):
            dj = a[j, j] - sum((lower[j, k] ** 2 * diag[k] for k in range(j)), sp.S.Zero)
            diag.append(self.define(dj))
            inv = self.define(1 / diag[j])
            for i in range(j + 1, n):
                lij = a[i, j] - sum((lower[i, k] * lower[j, k] * diag[k] for k in range(j)),
                                    sp.S.Zero)
                lower[i, j] = self.define(lij * inv)
        x = sp.zeros(n, b.cols)
        for col in range(b.cols):
            y: list[sp.Expr] = []
            for i in range(n):
                y.append(self.define(b[i, col] - sum((lower[i, k] * y[k] for k in range(i)),
                                                     sp.S.Zero)))
            z = [self.define(y[i] / diag[i]) for i in range(n)]
            for i in reversed(range(n)):
                x[i, col] = self.define(z[i] - sum((lower[k, i] * x[k, col]
                                                    for k in range(i + 1, n)), sp.S.Zero))
        return x

    def solve_general(self, a: sp.MatrixBase, b: sp.MatrixBase,
                      simplify: Callable[[sp.Expr], sp.Expr] | None = None) -> sp.Matrix:
        """x with a x = b for a square ``a`` that need not be symmetric (a constraint
        block): adj(a) b / det(a) up to ``CLOSED_FORM_MAX`` unknowns, else an unrolled
        LU factorisation in the given order (ZeroDivisionError on a structurally zero
        pivot: order the unknowns first, as ``block_triangular_solve`` does).
        ``simplify``: applied to the determinant written in the inputs when a's entries
        read inputs only (a constraint block's sin² + cos² folds to 1)."""
        a, b = self.matrix(a), self.matrix(b)
        n = a.rows
        if n <= CLOSED_FORM_MAX:
            if simplify is not None and all(self._is_leaf(e) for e in a):
                written = a.applyfunc(self.expand)  # in the inputs: small, simplifiable
                det = simplify(sp.expand(written.det(method="berkowitz")))
                adj = written.adjugate().applyfunc(lambda e: self.define(simplify(e)))
            else:
                det, adj = a.det(method="berkowitz"), a.adjugate()
            inv_det = self.define(1 / self.define(det))
            return sp.Matrix(n, b.cols, lambda i, j: self.define(
                sum((adj[i, k] * b[k, j] for k in range(n)), sp.S.Zero) * inv_det))
        lu = sp.Matrix(a)
        for j in range(n):
            if lu[j, j] == 0:
                raise ZeroDivisionError(f"zero pivot {j} in a staged LU solve")
            inv = self.define(1 / lu[j, j])
            for i in range(j + 1, n):
                if lu[i, j] == 0:
                    continue
                factor = self.define(lu[i, j] * inv)
                lu[i, j] = factor
                for k in range(j + 1, n):
                    if lu[j, k] != 0:
                        lu[i, k] = self.define(lu[i, k] - factor * lu[j, k])
        x = sp.zeros(n, b.cols)
        for col in range(b.cols):
            y = [sp.S.Zero] * n
            for i in range(n):
                y[i] = self.define(b[i, col] - sum((lu[i, k] * y[k] for k in range(i)),
                                                   sp.S.Zero))
            for i in reversed(range(n)):
                x[i, col] = self.define((y[i] - sum((lu[i, k] * x[k, col]
                                                     for k in range(i + 1, n)), sp.S.Zero))
                                        / lu[i, i])
        return x

    # --- derivatives -------------------------------------------------------------------
    def derivative(self, expr: sp.Expr, var: sp.Symbol) -> sp.Expr:
        """d expr / d var through the quantities: ∂expr/∂var with quantities held, plus
        Σ ∂expr/∂s · ds/dvar over the quantities s it reads (each ds/dvar a quantity)."""
        expr = sp.sympify(expr)
        out = sp.diff(expr, var)
        for s in sorted(expr.free_symbols & self.definitions.keys(), key=sp.default_sort_key):
            ds = self._quantity_derivative(s, var)
            if ds != 0:
                out += sp.diff(expr, s) * ds
        return out

    def _quantity_derivative(self, s: sp.Symbol, var: sp.Symbol) -> sp.Expr:
        key = (s, var)
        if key not in self._derivatives:
            self._derivatives[key] = self.define(self.derivative(self.definitions[s], var))
        return self._derivatives[key]

    # --- substitution ------------------------------------------------------------------
    def substituted(self, exprs: Iterable[sp.Expr], mapping: Mapping[sp.Symbol, sp.Expr]
                    ) -> list[sp.Expr]:
        """``exprs`` with inputs replaced by ``mapping``: every quantity that depends on a
        replaced input is defined again (a new symbol) with the replacement, so that, say,
        M̂(q) and M̂(q(t − h)) are both evaluated in one function."""
        exprs = [sp.sympify(e) for e in exprs]
        renamed: dict[sp.Basic, sp.Expr] = dict(mapping)
        for sym, e in self.definitions_for(exprs):  # only what exprs read, in order
            if e.free_symbols & renamed.keys():
                renamed[sym] = self.define(e.xreplace(renamed))
        return [e.xreplace(renamed) for e in exprs]

    # --- what generated code needs ----------------------------------------------------
    def definitions_for(self, exprs: Iterable[sp.Expr]) -> tuple[tuple[sp.Symbol, sp.Expr], ...]:
        """The quantities ``exprs`` read, directly or through other quantities, in
        definition order."""
        return definitions_read(self.definitions, exprs)

    def expand(self, expr: sp.Expr, at: Mapping[sp.Symbol, sp.Expr] | None = None) -> sp.Expr:
        """``expr`` with every quantity it reads replaced by its definition, inputs replaced
        by ``at`` first: the closed form a stage avoids building (for tests, and at a
        point such as q = 0 where it is small). The stage is left as it is."""
        subs: dict[sp.Basic, sp.Expr] = dict(at or {})
        for s, e in self.definitions_for([expr]):
            subs[s] = e.xreplace(subs)
        return sp.sympify(expr).xreplace(subs)


def definitions_read(definitions: Mapping[sp.Symbol, sp.Expr], exprs: Iterable[sp.Expr]
                     ) -> tuple[tuple[sp.Symbol, sp.Expr], ...]:
    """The ``definitions`` (in their order) that ``exprs`` read, directly or through other
    definitions: a stage's (``Stage.definitions_for``), or a function spec's after a
    rewrite."""
    needed: set[sp.Symbol] = set()
    todo = [s for e in exprs for s in sp.sympify(e).free_symbols if s in definitions]
    while todo:
        s = todo.pop()
        if s in needed:
            continue
        needed.add(s)
        todo += [t for t in definitions[s].free_symbols if t in definitions and t not in needed]
    return tuple((s, e) for s, e in definitions.items() if s in needed)


def evaluate(definitions: Iterable[tuple[sp.Symbol, sp.Expr]], exprs: Iterable[sp.Expr],
             values: Mapping[sp.Symbol, float]) -> list[float]:
    """``exprs`` at ``values`` (floats for every input symbol), the definitions evaluated in
    order: the numeric meaning of a staged function, for tests."""
    env: dict[sp.Basic, sp.Expr] = {k: sp.Float(v, 17) for k, v in values.items()}
    for s, e in definitions:
        env[s] = sp.Float(e.xreplace(env).evalf(17), 17)
    return [float(sp.sympify(e).xreplace(env).evalf(17)) for e in exprs]
