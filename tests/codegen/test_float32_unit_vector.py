"""The float32 certificate's unit-vector rule (codegen/backends/c/certify/unitvector.py):
the robust laws' g s/max(||s||, eps) as one operation. At points built to be worst
(s's entries cancelling, ||s|| inside the boundary layer and just outside it, gain
largest, eps smallest) the error at 113 bits never exceeds the rule's bound and is within
100x of it; the rule with the norm's part of the error dropped is beaten there."""

from __future__ import annotations

import mpmath
import numpy as np
import numpy.typing as npt
import pytest
import sympy as sp

from codegen.backends.c.certify import unitvector
from codegen.backends.c.certify.analysis import Analysis
from codegen.backends.c.certify.bound import certify
from codegen.backends.c.certify.program import ExpressionParser, Program, parse_only
from codegen.backends.c.certify.search import cancelling_points, float32_eval
from codegen.backends.c.config import CConfig

NAMES = ["a", "b", "c", "d", "e", "g", "eps"]
BOX = {"a": (0.25, 0.5), "b": (1.0, 2.0), "c": (1.0, 2.0), "d": (0.1, 4.0),
       "e": (-0.04, 0.04), "g": (90.0, 100.0), "eps": (0.02, 0.021)}
BOXES = 200


def _program() -> Program:
    """s = (e, a*b - c*d) (s_1 cancelling: a*b <= 1 while c*d reaches 8, so where s_1 is
    small its rounding is that of terms <= 1, not of c*d's range), then
    s_i * (g / fmax(||s||, eps)) as the robust laws print it."""
    config = CConfig()
    prog = parse_only("a", NAMES, config)
    prog.outputs.clear()
    scope = {n: prog.inputs[sp.Symbol(n)] for n in NAMES}
    parser = ExpressionParser(prog, scope, config)
    scope["s1"] = parser.parse("a*b - c*d")
    scope["t"] = parser.parse("g/WMR_FMAX(wmr_norm2(e, s1), eps)")
    prog.outputs.append(("out0", parser.parse("e*t")))
    prog.outputs.append(("out1", parser.parse("s1*t")))
    return prog


def _box(prog: Program) -> dict[sp.Symbol, tuple[float, float]]:
    return {s: BOX[str(s)] for s in prog.inputs}


def _worst_points(count: int = 3000) -> dict[str, npt.NDArray[np.float32]]:
    """a, b, c anywhere, d solved so that s_1 = r e (|r| in [0.5, 2]: both entries
    alike, where the norm's error moves the other entry most), ||s|| between 0 and
    ~2 eps; gain and eps at their worst ends."""
    rng = np.random.default_rng(7)
    f32 = np.float32
    a = rng.uniform(0.25, 0.5, count).astype(f32)
    b, c = (rng.uniform(1.0, 2.0, count).astype(f32) for _ in range(2))
    e = rng.uniform(-0.04, 0.04, count).astype(f32)
    r = rng.choice([-1.0, 1.0], count) * rng.uniform(0.5, 2.0, count)
    d = ((a.astype(float) * b - r * e) / c).astype(f32)
    ok = (d >= 0.1) & (d <= 4.0)
    g = np.full(count, 100.0, f32)
    eps = np.full(count, f32(0.02), f32)
    eps = np.where(eps < 0.02, np.nextafter(eps, f32(1.0)), eps)
    return {k: v[ok] for k, v in dict(a=a, b=b, c=c, d=d, e=e, g=g, eps=eps).items()}


def _errors(prog: Program, pts: dict[str, npt.NDArray[np.float32]]
            ) -> npt.NDArray[np.float64]:
    """|float32 - exact| per point and output, exact at 113 bits."""
    got = float32_eval(prog, {s: pts[str(s)] for s in prog.inputs})
    out = np.empty((len(pts["a"]), 2))
    with mpmath.workprec(113):
        for k in range(len(pts["a"])):
            v = {n: mpmath.mpf(float(pts[n][k])) for n in NAMES}
            s1 = v["a"] * v["b"] - v["c"] * v["d"]
            t = v["g"] / max(mpmath.sqrt(v["e"] ** 2 + s1 * s1), v["eps"])
            for j, x in enumerate((v["e"] * t, s1 * t)):
                out[k, j] = float(abs(mpmath.mpf(float(got[j][k])) - x))
    return out


@pytest.fixture(scope="module")
def found() -> npt.NDArray[np.float64]:
    return _errors(_program(), _worst_points())


def test_worst_points_never_beat_the_rule_and_the_rule_is_tight(
        found: npt.NDArray[np.float64]) -> None:
    prog = _program()
    cert = certify(prog, _box(prog), seconds=600.0, max_boxes=BOXES)
    assert cert.proved, cert.reason
    worst = found.max(axis=0)
    for out, bound, err in zip(cert.outputs, cert.bounds, worst, strict=True):
        assert err <= bound, f"{out}: found {err:.3g} > certified {bound:.3g}"
        assert bound <= 100 * err, f"{out}: bound {bound:.3g} vs found {err:.3g}"


def _dropped_norm(a_i: npt.NDArray[np.float64], b_i: npt.NDArray[np.float64],
                  a_norm: npt.NDArray[np.float64], b_max: npt.NDArray[np.float64],
                  m_lo: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    return a_i / m_lo + b_i + b_max  # the norm's error (||A||) left out


def test_a_rule_too_tight_is_beaten(found: npt.NDArray[np.float64],
                                     monkeypatch: pytest.MonkeyPatch) -> None:
    """Dropping the norm's part of the rule (||A||: s_1's rounding moves ||s||, hence
    the other entry e/||s||, outside the layer) gives a bound the worst points beat."""
    prog = _program()
    monkeypatch.setattr(unitvector, "entry_error", _dropped_norm)
    cert = certify(prog, _box(prog), seconds=600.0, max_boxes=BOXES)
    assert any(err > bound for bound, err in zip(cert.bounds, found.max(axis=0), strict=True)
               ), (cert.bounds, found.max(axis=0))


def test_the_rule_replaces_the_per_operation_one() -> None:
    """On the whole box the unit-vector rule is several times tighter than the
    per-operation rule it is intersected with (|u_i| <= 1 with g's error over eps)."""
    prog = _program()
    box = _box(prog)
    lo = {prog.inputs[s]: np.array([b[0]]) for s, b in box.items()}
    hi = {prog.inputs[s]: np.array([b[1]]) for s, b in box.items()}
    analysis = Analysis(prog)
    new = [v.err[0] for v in analysis.run(lo, hi)[0]]
    original = Analysis._unit_vector
    try:
        Analysis._unit_vector = lambda self, old, *args: old  # type: ignore[method-assign]
        old = [v.err[0] for v in Analysis(prog).run(lo, hi)[0]]
    finally:
        Analysis._unit_vector = original  # type: ignore[method-assign]
    assert all(n * 3 < o for n, o in zip(new, old, strict=True)), (new, old)


def test_search_finds_the_cancelling_points(found: npt.NDArray[np.float64]) -> None:
    """The search's cancelling points (every input at an end of its range but one per
    entry, solved so that the entries cancel near the layer) reach within 10x of the
    worst error the constructed points find, without being told the structure, and
    never beat the rule's bound."""
    prog = _program()
    box = _box(prog)
    symbols = sorted(prog.inputs, key=lambda s: prog.inputs[s])
    lo = np.array([box[s][0] for s in symbols])
    hi = np.array([box[s][1] for s in symbols])
    pts = cancelling_points(prog, symbols, lo, hi, 200, np.random.default_rng(2))
    assert len(pts)
    err = _errors(prog, {str(s): pts[:, k].astype(np.float32) for k, s in enumerate(symbols)})
    assert np.all(err.max(axis=0) * 10 >= found.max(axis=0)), (err.max(axis=0),
                                                               found.max(axis=0))
    cert = certify(prog, box, seconds=600.0, max_boxes=BOXES)  # and never beat the rule
    assert np.all(err.max(axis=0) <= np.array(cert.bounds)), (err.max(axis=0), cert.bounds)
