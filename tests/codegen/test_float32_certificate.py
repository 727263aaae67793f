"""The float32 certificate (codegen.certify): the bound holds against a search at 113 bits,
means something (within 100x of the largest error found), and bites when the printing is
loosened (an addition reordered so that it loses precision)."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from codegen.backend import FunctionIR, function_ir
from codegen.backends.c.config import CConfig
from codegen.certify.bound import Certificate, certify
from codegen.certify.program import Program, parse_only, program_of
from codegen.certify.robot import certify_robot
from codegen.certify.search import float32_eval, search
from codegen.generate import robot_target
from codegen.printer_base import ExpressionPrinterMixin
from codegen.spec import Argument, FunctionSpec
from modeling.robot_file import load_robot_model

# Functions searched here (the command searches all): model, estimator, laws, gains.
SEARCHED = ("lyapunov_p", "mass_matrix", "kinematics", "minimal_tdc_law", "paper_tde_trig",
            "tdroc_weighted_gain")


@pytest.fixture(scope="module")
def drishti() -> list[tuple[FunctionIR, Program, dict[sp.Symbol, tuple[float, float]],
                            Certificate]]:
    model, robot = load_robot_model(None)
    target = robot_target(model, robot)
    return [(ir, prog, box, cert) for ir, prog, box, cert
            in certify_robot(target, seconds=1.0, only=SEARCHED)]


def test_search_never_beats_the_bound_and_the_bound_is_tight(
        drishti: list[tuple[FunctionIR, Program, dict[sp.Symbol, tuple[float, float]],
                            Certificate]]) -> None:
    seen = set()
    for ir, prog, box, cert in drishti:
        seen.add(ir.name)
        assert cert.proved, (ir.name, cert.reason)
        found = search(prog, ir, box, random_points=60, climbs=1, rounds=2)
        for out, bound, err in zip(cert.outputs, cert.bounds, found.errors, strict=True):
            assert err <= bound, f"{ir.name} {out}: found {err:.3g} > certified {bound:.3g}"
        assert max(cert.bounds) <= 100 * max(found.errors), ir.name
    assert seen == set(SEARCHED)


def test_parsed_order_is_c_order() -> None:
    """``a - b + c`` is ``(a - b) + c`` and ``a/b*c`` is ``(a/b)*c``, as C evaluates them."""
    prog = parse_only("a - b + c*d/e", ["a", "b", "c", "d", "e"], CConfig())
    ops = [n.op for n in prog.nodes if n.op != "in"]
    assert ops == ["sub", "mul", "div", "add"]


def _cancel_spec() -> FunctionSpec:
    x, y, w = sp.symbols("x y w", real=True)
    return FunctionSpec("cancel", "x - w + y", (Argument("v", "array", (3, 1), (x, y, w)),),
                        (Argument("out", "array", (1, 1), exprs=(x - w + y,)),))


def test_loosened_printing_fails_the_bound(monkeypatch: pytest.MonkeyPatch) -> None:
    """Reordering the printed sum (the large terms apart) loses the small one: the search
    over the reordered printing finds an error above the certificate of the printed one."""
    spec = _cancel_spec()
    x, y, w = spec.inputs[0].symbols
    box = {x: (1.0e4, 1.0e4 + 1.0), w: (1.0e4, 1.0e4 + 1.0), y: (0.0, 1.0e-3)}
    config = CConfig()
    ir = function_ir(spec)
    printed = program_of(ir, config)
    cert = certify(printed, box, seconds=0.5)
    assert cert.proved
    honest = search(printed, ir, box, random_points=40, climbs=1, rounds=1)
    assert honest.errors[0] <= cert.bounds[0]

    def reversed_add(self: ExpressionPrinterMixin, expr: sp.Add) -> str:
        terms = expr.as_ordered_terms()[::-1]  # the printer's _add, terms reversed
        out = self._print(terms[0])
        for term in terms[1:]:
            text = self._print(term)
            out += f" - {text[1:]}" if text.startswith("-") else f" + {text}"
        return out

    monkeypatch.setattr(ExpressionPrinterMixin, "_add", reversed_add)
    loosened = program_of(ir, config)
    assert [n.op for n in loosened.nodes] != [n.op for n in printed.nodes] or any(
        a.args != b.args for a, b in zip(loosened.nodes, printed.nodes, strict=True))
    found = search(loosened, ir, box, random_points=40, climbs=1, rounds=1)
    assert found.errors[0] > cert.bounds[0], (found.errors, cert.bounds)
    # and the certificate of the loosened printing itself says so
    assert certify(loosened, box, seconds=0.5).bounds[0] > 10 * cert.bounds[0]


def test_float32_eval_rounds_every_operation() -> None:
    """The search's float32 evaluation rounds per operation: (1 + 2^-24) + 2^-24 is 1."""
    prog = parse_only("a + b + b", ["a", "b"], CConfig())
    out = float32_eval(prog, {sp.Symbol("a"): np.array([1.0], np.float32),
                              sp.Symbol("b"): np.array([2.0**-24], np.float32)})
    assert out[0][0] == np.float32(1.0)
