"""Base inertial parameters: the few combinations of masses, inertias and centre-of-mass
offsets that the kinetic energy actually depends on.

T(q, q̇) = Σ_k c_k(p) φ_k(q, q̇), where the φ_k are products of velocities and of sines and
cosines of the coordinates and the c_k are polynomials in the physical parameters p (for a
tractor with a trailer: 24 of them, 11 distinct combinations). Each distinct coefficient,
up to a rational factor, becomes one base parameter β_j; T, and everything derived from it
((9)–(14), the minimal form), is then linear in β, and the generated code takes β at run
time. For the paper's robot this is exactly the step from the physical parameters to its
lumped m, I, K, I_w (``modeling.robots.drishti.model.lumped_relations``).

Coefficients are grouped by their primitive part (the polynomial divided by its rational
content, sign normalised), so c_k = s_k β_j with a rational s_k. A coefficient that is a
linear combination of others keeps its own β (not minimal in that case, but exact).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import sympy as sp


@dataclass(frozen=True)
class BaseParameter:
    """β = ``expression`` (in the physical parameters) = ``natural`` × the coefficient of
    ``monomial``, the first φ_k of T it multiplies (in the order T's terms are sorted)."""

    symbol: sp.Symbol
    expression: sp.Expr
    monomial: sp.Expr
    natural: int


@dataclass(frozen=True)
class BaseReduction:
    """T in base parameters, and how each base parameter follows from physical ones."""

    kinetic_energy: sp.Expr
    parameters: tuple[BaseParameter, ...]

    def relations(self) -> dict[sp.Symbol, sp.Expr]:
        return {b.symbol: b.expression for b in self.parameters}

    def values(self, physical: dict[sp.Symbol, float]) -> dict[sp.Symbol, float]:
        """β's numbers at the physical parameters' numbers."""
        return {b.symbol: float(b.expression.subs(physical)) for b in self.parameters}


def split_terms(expr: sp.Expr, variables: set[sp.Symbol]) -> dict[sp.Expr, sp.Expr]:
    """{φ: c(p)} with expr = Σ c φ, φ free of parameters, c free of ``variables``."""
    out: dict[sp.Expr, sp.Expr] = {}
    for term in sp.Add.make_args(sp.expand(expr)):
        coeff, dep = term.as_independent(*variables, as_Add=False)
        out[dep] = out.get(dep, sp.S.Zero) + coeff
    return out


def _primitive(poly: sp.Expr) -> tuple[sp.Rational, sp.Expr]:
    """(s, P) with poly = s P, P primitive with a positive leading term (canonical)."""
    content, prim = sp.expand(poly).as_content_primitive()
    terms = sorted(sp.Add.make_args(prim), key=sp.default_sort_key)
    if terms and terms[0].as_coeff_Mul()[0] < 0:
        content, prim = -content, sp.expand(-prim)
    return sp.Rational(content), prim


def _velocity_part(monomial: sp.Expr, velocities: dict[sp.Symbol, str]) -> list[sp.Symbol]:
    out: list[sp.Symbol] = []
    for factor in sp.Mul.make_args(monomial):
        base, exp = factor.as_base_exp()
        if base in velocities:
            out += [base] * int(exp)
    return out


def _name(monomial: sp.Expr, velocities: dict[sp.Symbol, str], taken: set[str]) -> str:
    """``J_<coordinate>`` for the coefficient of a squared rate (a generalised inertia),
    ``K_<coordinate>_<coordinate>`` for a product of two rates (a first moment), with a
    numeric suffix when that name is taken."""
    rates = sorted(_velocity_part(monomial, velocities), key=lambda v: velocities[v])
    if len(rates) == 2 and rates[0] == rates[1]:
        stem = f"J_{velocities[rates[0]]}"
    else:
        stem = "K_" + "_".join(velocities[v] for v in rates)
    name, k = stem, 2
    while name in taken:
        name, k = f"{stem}_{k}", k + 1
    return name


def reduce_to_base(
    kinetic_energy: sp.Expr,
    variables: Iterable[sp.Symbol],
    velocities: dict[sp.Symbol, str],
) -> BaseReduction:
    """Rewrite T in base parameters (see the module docstring).

    ``variables`` are the coordinates and velocities; every other symbol is a parameter.
    ``velocities`` maps each rate to its coordinate's name, for the parameter names: the
    coefficient c of ½ J q̇ᵢ² gives J = 2c (``J_<q_i>``, the generalised inertia, e.g. the
    total mass for a position rate), any other product of rates gives K = c
    (``K_<q_i>_<q_j>``). Coefficients that are plain rationals stay numbers.
    """
    variables = set(variables)
    pieces = split_terms(kinetic_energy, variables)
    order = sorted(pieces, key=sp.default_sort_key)
    groups: dict[sp.Expr, sp.Symbol] = {}
    scales: dict[sp.Expr, sp.Rational] = {}
    params: list[BaseParameter] = []
    t = sp.S.Zero
    for monomial in order:
        coeff = pieces[monomial]
        if coeff == 0:
            continue
        if not coeff.free_symbols:
            t += coeff * monomial
            continue
        scale, prim = _primitive(coeff)
        if prim not in groups:
            rates = _velocity_part(monomial, velocities)
            natural = 2 if len(rates) == 2 and rates[0] == rates[1] else 1
            name = _name(monomial, velocities, {str(p.symbol) for p in params})
            symbol = sp.Symbol(name, real=True)
            groups[prim] = symbol
            # β is the natural quantity (2c for ½ J q̇², c otherwise), not the primitive part.
            params.append(BaseParameter(symbol, sp.expand(natural * coeff), monomial, natural))
            scales[prim] = natural * scale
        t += scale / scales[prim] * groups[prim] * monomial
    return BaseReduction(t, tuple(params))
