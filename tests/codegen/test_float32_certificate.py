"""The float32 certificate (codegen.backends.c.certify): the bound holds against a search
at 113 bits, means something (within 100x of the largest error found), and bites when the
printing is loosened (an addition reordered so that it loses precision)."""

from __future__ import annotations

import mpmath
import numpy as np
import pytest
import sympy as sp

from codegen.backend import FunctionIR, function_ir
from codegen.backends.c.backend import config_for
from codegen.backends.c.certify.analysis import Analysis
from codegen.backends.c.certify.bound import Certificate, certify
from codegen.backends.c.certify.boxes import ENVELOPE, box_of, input_errors
from codegen.backends.c.certify.divisors import dependencies, derivatives, divisor_enclosures
from codegen.backends.c.certify.program import ExpressionParser, Program, parse_only, program_of
from codegen.backends.c.certify.robot import certify_robot, programs, robot_angles, robot_params
from codegen.backends.c.certify.search import (
    Exact,
    boundary_layers,
    boundary_points,
    errors_at,
    float32_eval,
    node_values,
    search,
)
from codegen.backends.c.config import CConfig
from codegen.backends.c.lowering import function_context
from codegen.certify import header
from codegen.certify.header import body_hash
from codegen.certify.stored import robot_results
from codegen.generate import robot_target
from codegen.printer_base import ExpressionPrinterMixin
from codegen.spec import Argument, FunctionSpec
from modeling.robot_file import load_robot_model

# Functions searched here (the command searches all): model, estimator, laws, gains.
SEARCHED = ("lyapunov_p", "mass_matrix", "kinematics", "minimal_tdc_law", "paper_tde_trig",
            "tdroc_weighted_gain")
# Searched for soundness only: the norm and normalised-vector rules (s/max(||s||, eps)),
# whose bound is looser (docs/FLOAT32.md says why).
SEARCHED_SOUND = ("minimal_tdroc_law", "minimal_omega_difference")
# Subdivision stopped at a box count, not a time: the same certificate on any machine.
BOXES = 200


@pytest.fixture(scope="module")
def drishti() -> list[tuple[FunctionIR, Program, dict[sp.Symbol, tuple[float, float]],
                            Certificate]]:
    model, robot = load_robot_model(None)
    target = robot_target(model, robot)
    return [(ir, prog, box, cert) for ir, prog, box, cert
            in certify_robot(target, seconds=600.0, only=SEARCHED + SEARCHED_SOUND,
                             max_boxes=BOXES)]


def test_search_never_beats_the_bound_and_the_bound_is_tight(
        drishti: list[tuple[FunctionIR, Program, dict[sp.Symbol, tuple[float, float]],
                            Certificate]]) -> None:
    seen = set()
    for ir, prog, box, cert in drishti:
        if ir.name not in SEARCHED:
            continue
        seen.add(ir.name)
        assert cert.proved, (ir.name, cert.reason)
        found = search(prog, ir, box, random_points=60, climbs=1, rounds=2)
        for out, bound, err in zip(cert.outputs, cert.bounds, found.errors, strict=True):
            assert err <= bound, f"{ir.name} {out}: found {err:.3g} > certified {bound:.3g}"
        assert max(cert.bounds) <= 100 * max(found.errors), ir.name
    assert seen == set(SEARCHED)


def test_norm_and_switching_rules_hold(
        drishti: list[tuple[FunctionIR, Program, dict[sp.Symbol, tuple[float, float]],
                            Certificate]]) -> None:
    """The 2-norm and normalised-vector rules: the search never beats them, including
    near ||s|| = eps where the switching term amplifies s's errors by gain/eps."""
    checked = 0
    for ir, prog, box, cert in drishti:
        if ir.name not in SEARCHED_SOUND:
            continue
        checked += 1
        assert cert.proved, (ir.name, cert.reason)
        near = dict(box)
        if "eps" in {str(s) for s in box}:  # small boundary layer, large gain
            for s in box:
                if str(s) == "eps":
                    near[s] = (box[s][0], box[s][0] * 1.01)
                if str(s) == "gain":
                    near[s] = (box[s][1] * 0.99, box[s][1])
        tight = certify(prog, near, seconds=600.0, max_boxes=BOXES)
        for b in (box, near):
            c = cert if b is box else tight
            found = search(prog, ir, b, random_points=60, climbs=1, rounds=2)
            for out, bound, err in zip(c.outputs, c.bounds, found.errors, strict=True):
                assert err <= bound, f"{ir.name} {out}: found {err:.3g} > {bound:.3g}"
    assert checked == len(SEARCHED_SOUND)


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
    cert = certify(printed, box, seconds=600.0, max_boxes=BOXES)
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
    assert certify(loosened, box, seconds=600.0, max_boxes=BOXES).bounds[0] > 10 * cert.bounds[0]


def test_float32_eval_rounds_every_operation() -> None:
    """The search's float32 evaluation rounds per operation: (1 + 2^-24) + 2^-24 is 1."""
    prog = parse_only("a + b + b", ["a", "b"], CConfig())
    out = float32_eval(prog, {sp.Symbol("a"): np.array([1.0], np.float32),
                              sp.Symbol("b"): np.array([2.0**-24], np.float32)})
    assert out[0][0] == np.float32(1.0)


def _switching_program() -> Program:
    """s0 = a*b - c*d (cancelling: its error is large next to it), s1 = e, then the
    switching term s0 * (g / fmax(||s||, eps)) as the laws print it."""
    config = CConfig()
    names = ["a", "b", "c", "d", "e", "g", "eps"]
    prog = parse_only("a", names, config)
    prog.outputs.clear()
    scope = {n: prog.inputs[sp.Symbol(n)] for n in names}
    parser = ExpressionParser(prog, scope, config)
    scope["s0"] = parser.parse("a*b - c*d")
    scope["t"] = parser.parse("g/WMR_FMAX(wmr_norm2(s0, e), eps)")
    prog.outputs.append(("out", parser.parse("s0*t")))
    return prog


def test_switching_rule_holds_near_the_boundary_layer() -> None:
    """Where ||s|| is near eps and s0 cancels, the switching term amplifies s0's rounding
    by g/eps: random points there never beat the certificate's normalised-vector rule."""
    prog = _switching_program()
    syms = {str(s): s for s in prog.inputs}
    box = {syms["a"]: (100.0, 100.01), syms["b"]: (100.0, 100.01),
           syms["c"]: (100.0, 100.01), syms["d"]: (100.0, 100.01),
           syms["e"]: (0.0, 1e-3), syms["g"]: (90.0, 100.0), syms["eps"]: (0.02, 0.021)}
    cert = certify(prog, box, seconds=600.0, max_boxes=BOXES)
    assert cert.proved
    rng = np.random.default_rng(1)
    pts = {s: rng.uniform(lo, hi, 400).astype(np.float32) for s, (lo, hi) in box.items()}
    got = float32_eval(prog, pts)[0]
    worst = 0.0
    with mpmath.workprec(113):
        for k in range(400):
            v = {str(s): mpmath.mpf(float(pts[s][k])) for s in box}
            s0 = v["a"] * v["b"] - v["c"] * v["d"]
            exact = s0 * v["g"] / max(mpmath.sqrt(s0 * s0 + v["e"] ** 2), v["eps"])
            worst = max(worst, float(abs(mpmath.mpf(float(got[k])) - exact)))
    assert worst <= cert.bounds[0], (worst, cert.bounds[0])
    assert cert.bounds[0] <= 100 * worst


def test_header_lines_follow_the_printed_body(monkeypatch: pytest.MonkeyPatch) -> None:
    """A result whose hash matches the printed body is stated with its bounds; any other
    body (the printing changed) is stated as having no current certificate."""
    body = ["decl x = a*b", "store out[0] = x"]
    row = {"function": "f", "hash": body_hash(body), "proved": True, "reason": "",
           "open_guards": [], "outputs": [{"output": "out[0]", "bound": 1.5e-6}]}
    monkeypatch.setattr(header, "robot_results", lambda prefix: {"functions": [row]})
    text = " ".join(header.certificate_doc("f", body, "wmr"))
    assert "out 1.5e-06" in text and "no intermediate overflows" in text
    stale = " ".join(header.certificate_doc("f", [*body, "store out[1] = x"], "wmr"))
    assert "no current certificate" in stale and "1.5e-06" not in stale


def test_committed_results_are_current_and_hold() -> None:
    """codegen/certify/results/drishti.json was computed from the code printed now, and
    its search never beat its bounds."""
    data = robot_results("wmr")
    if not data:
        pytest.fail("no committed results: run `python -m codegen.backends.c.certify`")
    model, robot = load_robot_model(None)
    target = robot_target(model, robot)
    config = config_for(target.layout)
    rows = {row["function"]: row for row in data["functions"]}
    for ir in target.functions():
        row = rows[ir.name]
        assert row["hash"] == body_hash(function_context(ir, config, "")["body"]), ir.name
        assert not row["found_above_bound"], ir.name


def _drishti_program(name: str) -> tuple[FunctionIR, Program, dict[sp.Symbol, tuple[float, float]]]:
    model, robot = load_robot_model(None)
    target = robot_target(model, robot)
    angles, params = robot_angles(target), robot_params(target, ENVELOPE)
    for ir, prog in programs(target):
        if ir.name == name:
            return ir, prog, box_of(prog, angles, params, {}, ENVELOPE)
    raise AssertionError(name)


def test_divisor_enclosure_holds_where_the_box_enclosure_fails() -> None:
    """wheel_contact_forces divides by det(S^T M S) in rotated entries: over two turns of
    theta and ±10 % parameters the whole box's enclosure contains 0; the branch and bound
    over the determinant's own 8 inputs (mean value in the parameters) excludes it, the
    determinant at random points of the box (double) lies inside the proved enclosure, and
    the certificate is proved with it."""
    _, prog, box = _drishti_program("wheel_contact_forces")
    lo = {prog.inputs[s]: b[0] for s, b in box.items()}
    hi = {prog.inputs[s]: b[1] for s, b in box.items()}
    known, failed = divisor_enclosures(prog, lo, hi, seconds=120.0)
    assert not failed and len(known) == 1
    (node, (dlo, dhi)), = known.items()
    assert dlo > 0 and len(dependencies(prog)[node]) == 8
    rng = np.random.default_rng(3)
    pts = {s: rng.uniform(b[0], b[1], 2000) for s, b in box.items()}
    det = node_values(prog, pts, np.float64)[node]
    assert dlo <= det.min() and det.max() <= dhi, (dlo, det.min(), det.max(), dhi)
    assert det.min() < 4 * dlo  # a bound that means something
    # and the certificate, which proves it when its subdivision alone does not
    cert = certify(prog, box, input_errors(prog), seconds=600.0, max_boxes=BOXES)
    assert cert.proved and cert.divisors, cert.reason


def test_derivative_enclosures_contain_the_slopes() -> None:
    """The forward-mode interval derivatives the mean-value form rests on: over a small box
    around random points they contain the finite-difference slope of the determinant."""
    _, prog, box = _drishti_program("wheel_contact_forces")
    node = next(n.args[1] for n in prog.nodes if n.op == "div"
                and len(dependencies(prog)[n.args[1]]) == 8)
    sub = Program(prog.function, prog.nodes[:node + 1],
                  {s: n for s, n in prog.inputs.items() if n <= node})
    sub.outputs.append(("d", node))
    syms = sorted(sub.inputs, key=lambda s: sub.inputs[s])
    wrt = [sub.inputs[s] for s in syms]
    rng = np.random.default_rng(4)
    centre = {s: rng.uniform(box[s][0], box[s][1], 50) for s in syms}
    half = {s: 1e-3 * (box[s][1] - box[s][0]) for s in syms}
    analysis = Analysis(sub)
    analysis.run({sub.inputs[s]: centre[s] - half[s] for s in syms},
                 {sub.inputs[s]: centre[s] + half[s] for s in syms})
    glo, ghi = derivatives(sub, analysis.values, wrt)
    for k, s in enumerate(syms):
        step = {t: centre[t] + (half[s] if t == s else 0.0) for t in syms}
        back = {t: centre[t] - (half[s] if t == s else 0.0) for t in syms}
        slope = (node_values(sub, step, np.float64)[node]
                 - node_values(sub, back, np.float64)[node]) / (2 * half[s])
        assert np.all(glo[:, k] - 1e-9 <= slope) and np.all(slope <= ghi[:, k] + 1e-9), s


def test_search_reaches_the_boundary_layer() -> None:
    """The search's boundary points put ||s|| within 1 % of (1 + d) eps (|d| <= 5 %), and
    there the law's float32 error is above what as many uniform points of the box find."""
    model, robot = load_robot_model(None)
    ((ir, prog, box, _),) = certify_robot(robot_target(model, robot), seconds=600.0,
                                          only=("minimal_tdroc_law",), max_boxes=BOXES)
    symbols = sorted(prog.inputs, key=lambda s: prog.inputs[s])
    lo = np.array([box[s][0] for s in symbols])
    hi = np.array([box[s][1] for s in symbols])
    rng = np.random.default_rng(5)
    pts = boundary_points(prog, symbols, lo, hi, 40, rng)
    assert len(pts) >= 30
    (n, c), = boundary_layers(prog)
    v = node_values(prog, {s: pts[:, k] for k, s in enumerate(symbols)}, np.float64)
    assert np.all(np.abs(v[n] / v[c] - 1) <= 0.07)
    exact = Exact(ir, symbols)
    near = errors_at(prog, exact, pts.astype(np.float32)).max()
    uniform = errors_at(prog, exact, (lo + (hi - lo) * rng.random((40, len(symbols))))
                        .astype(np.float32)).max()
    assert near > uniform, (near, uniform)
