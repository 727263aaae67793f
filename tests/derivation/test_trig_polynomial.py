"""M̂(q) as a trigonometric polynomial of the hitch angles (``modeling.trig_polynomial``):
equal to the staged M̂ it is built from at random configurations and parameters, in the
reduced basis (no sine squared, coefficients free of q), refused where q enters otherwise;
and ``minimal_mhat`` takes it only where it saves step operations within the code bound."""

from __future__ import annotations

import random

import pytest
import sympy as sp

from codegen import robot_functions as rf
from modeling import controllers as ctl
from modeling.robot_model import described_model
from modeling.trig_polynomial import trig_polynomial

x, y, a, b = sp.symbols("x y a b", real=True)


def _robot(name: str):  # type: ignore[no-untyped-def]
    return described_model(f"modeling/robots/{name}/{name}.toml")


@pytest.mark.parametrize("name", ["trailer", "trailer2"])
def test_polynomial_equals_the_staged_mass_matrix(name: str) -> None:
    """At random q and parameters, every entry of the polynomial equals the staged M̂
    (definitions evaluated in order): the coefficients are not fitted to the shipped
    parameters."""
    model = _robot(name)
    cm = ctl.control_model("minimal", model)
    defs = cm.definitions(list(cm.mass))
    poly = trig_polynomial(list(cm.mass), model.q, defs)
    assert poly is not None
    rng = random.Random(7)
    params = sorted({s for e in poly for s in e.free_symbols} - set(model.q), key=str)
    for _ in range(5):
        point: dict[sp.Basic, sp.Expr] = {s: sp.Float(rng.uniform(0.3, 2.0)) for s in params}
        point.update({s: sp.Float(rng.uniform(-3.0, 3.0)) for s in model.q})
        value = dict(point)
        for sym, e in defs:
            value[sym] = e.xreplace(value).evalf()
        for staged, p in zip(cm.mass, poly, strict=True):
            want = float(sp.sympify(staged).xreplace(value).evalf())
            got = float(p.xreplace(point).evalf())
            assert got == pytest.approx(want, rel=1e-9, abs=1e-9)


def test_one_trailer_has_three_monomials_per_entry() -> None:
    """One trailer: each entry is m0 + m1 cos²ψ + m2 sin ψ cos ψ (ψ the hitch angle),
    the form a hand-written step uses (as m0' + mc cos 2ψ + ms sin 2ψ)."""
    model = _robot("trailer")
    cm = ctl.control_model("minimal", model)
    poly = trig_polynomial(list(cm.mass), model.q, cm.definitions(list(cm.mass)))
    assert poly is not None
    (angle,) = {f.args[0] for e in poly for f in e.atoms(sp.sin, sp.cos)}
    sin, cos = sp.symbols("sin cos")
    for entry in poly:
        p = sp.Poly(entry.xreplace({sp.sin(angle): sin, sp.cos(angle): cos}), sin, cos)
        assert set(p.monoms()) == {(0, 0), (0, 2), (1, 1)}
        assert not any(c.free_symbols & set(model.q) for c in p.coeffs())


def test_sine_squared_is_reduced_and_equal_polynomials_match() -> None:
    """sin² = 1 − cos²: a·sin²x + a·cos²x is a; the basis is unique, so an identity
    that only trigonometry proves becomes structural equality."""
    assert trig_polynomial([a * sp.sin(x) ** 2 + a * sp.cos(x) ** 2], [x]) == [a]
    (p,) = trig_polynomial([sp.sin(x) ** 3 * b], [x]) or [None]
    assert p is not None
    assert sp.expand(p - (b * sp.sin(x) - b * sp.sin(x) * sp.cos(x) ** 2)) == 0
    two = trig_polynomial([sp.sin(x) * sp.cos(y) + sp.sin(y) ** 2], [x, y])
    assert two is not None
    assert sp.expand(two[0] - (sp.sin(x) * sp.cos(y) + 1 - sp.cos(y) ** 2)) == 0


def test_definitions_are_read_through() -> None:
    """A quantity defined once (a staged definition) is expanded into the coefficients."""
    d, e = sp.symbols("_d _e", real=True)
    poly = trig_polynomial([e * 2], [x], [(d, a * sp.cos(x)), (e, d * d + b)])
    assert poly == [2 * b + 2 * a**2 * sp.cos(x) ** 2]


@pytest.mark.parametrize("expr", [x * sp.sin(x), sp.sin(x) / (1 + sp.cos(x)),
                                  sp.sqrt(sp.cos(x) + 2), sp.exp(sp.sin(x))])
def test_refused_where_q_enters_otherwise(expr: sp.Expr) -> None:
    assert trig_polynomial([expr], [x]) is None


def test_budget_stops_the_expansion() -> None:
    """(sin x + cos x + 1)^4 has 8 monomials after the reduction (s c³ cancels): a
    budget of 7 refuses it."""
    e = (sp.sin(x) + sp.cos(x) + 1) ** 4
    assert trig_polynomial([e], [x], budget=7) is None
    (p,) = trig_polynomial([e], [x], budget=8) or [None]
    assert p is not None and len(sp.Add.make_args(p)) == 8
    assert float((p - e).subs(x, 0.7)) == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize(("name", "polynomial"),
                         [("trailer", True), ("trailer2", False), ("trailer3", False)])
def test_minimal_mhat_takes_the_polynomial_where_it_pays(name: str, polynomial: bool) -> None:
    """One trailer: the polynomial (fewer step operations, code within the bound); two and
    three: the staged form (two: fewer step operations at 3.6x the code; three: more step
    operations)."""
    spec = rf._mhat_spec(_robot(name), "minimal")
    assert (not spec.definitions) == polynomial
    if polynomial:
        step, kept = rf._split_ops(spec)
        assert step <= 20 and kept > 0
