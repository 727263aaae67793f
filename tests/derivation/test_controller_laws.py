"""The symbolic controller laws (modeling/controllers/) — facts the generated code uses."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from modeling import controllers as ctl
from modeling.robots.drishti import model as wmr

DRISHTI = wmr.robot_model()


@pytest.mark.parametrize("formulation", ctl.FORMULATIONS)
def test_model_is_heading_invariant(formulation: ctl.Formulation) -> None:
    """M̂(θ) = T M̂(0) Tᵀ, which makes ‖M̂⁻¹‖ of (25) a function of the parameters only."""
    shape = ctl.control_model(formulation, DRISHTI).mass.shape
    assert ctl.rotation_residual(formulation, DRISHTI) == sp.zeros(*shape)


def test_mass_inverse_norm_matches_numpy_at_any_heading() -> None:
    cm = ctl.control_model("paper", DRISHTI)
    values = {wmr.m: 36.0, wmr.I_z: 5.72, wmr.K: 0.34, wmr.I_w: 0.07, wmr.r: 0.096,
              wmr.b: 0.414, wmr.d: 0.12}
    norm = float(ctl.mass_inverse_norm("paper", DRISHTI).subs(values))
    f = sp.lambdify(wmr.theta, cm.mass.subs(values), "numpy")
    for theta in np.linspace(-3.0, 3.0, 7):
        assert abs(np.linalg.norm(np.linalg.inv(f(theta))) - norm) < 1e-12 * norm


def test_lyapunov_solution_solves_the_equation_and_is_positive_definite() -> None:
    k1, k2, q1, q2 = sp.symbols("k1 k2 q1 q2", positive=True)
    p11, p12, p22 = ctl.lyapunov_p(k1, k2, q1, q2)
    a = sp.Matrix([[0, 1], [-k1, -k2]])
    p = sp.Matrix([[p11, p12], [p12, p22]])
    assert sp.simplify(a.T * p + p * a + sp.diag(q1, q2)) == sp.zeros(2, 2)
    rng = np.random.default_rng(1)
    for _ in range(50):
        vals = dict(zip((k1, k2, q1, q2), rng.uniform(0.1, 10.0, 4), strict=True))
        pn = np.array(p.subs(vals), dtype=float)
        assert np.all(np.linalg.eigvalsh(pn) > 0)
    # The paper's gains: K1 = K2 = 4, Q = I.
    assert (p12.subs({k1: 4, k2: 4, q1: 1, q2: 1}), p22.subs({k1: 4, k2: 4, q1: 1, q2: 1})) == (
        sp.Rational(1, 8), sp.Rational(5, 32))


def test_switching_term_is_continuous_at_the_boundary_layer() -> None:
    law, ls = ctl.tde_law("minimal", switching=True, model=DRISHTI)
    s = ctl.sliding_variable(ls)
    direction, s_norm = ctl.switching_direction(ls)
    du = direction * ls.gain
    # On ‖s‖ = ε both branches of (25) give k s/ε.
    vals = {ls.e[0]: 0.3, ls.e[1]: -0.1, ls.edot[0]: 0.2, ls.edot[1]: 0.05,
            ls.p12[0]: 0.125, ls.p12[1]: 0.125, ls.p22[0]: 0.15625, ls.p22[1]: 0.15625,
            ls.gain: 2.0}
    eps = float(s_norm.subs(vals))
    inside = du.subs({**vals, ls.eps: eps * (1 + 1e-12)})
    outside = du.subs({**vals, ls.eps: eps * (1 - 1e-12)})
    assert float((inside - outside).norm()) < 1e-9
    del law, s


@pytest.mark.parametrize("formulation", ["paper", "minimal"])
def test_the_law_is_mhat_times_ua_plus_the_switching_term_plus_h1(formulation: str) -> None:
    """(22), (24): u = M̂ (u_a + k s / max(‖s‖, ε)) + Ĥ1 as printed in the paper; the law
    is written (M̂ u_a + Ĥ1) + k M̂ s / max(‖s‖, ε) for the step's latency: the same value
    at random inputs, inside and outside the boundary layer."""
    law, ls = ctl.tde_law(formulation, switching=True, model=DRISHTI)  # type: ignore[arg-type]
    cm = ctl.control_model(formulation, DRISHTI)  # type: ignore[arg-type]
    s = ctl.sliding_variable(ls)
    ua = ctl.nominal_acceleration(ls) + s * ls.gain / sp.Max(sp.sqrt(sum(x**2 for x in s)),
                                                               ls.eps)
    printed = cm.mass * ua + ls.h1
    rng = np.random.default_rng(3)
    free = sorted((law.u.free_symbols | printed.free_symbols), key=str)
    for eps in (1e-3, 50.0):  # outside, inside the boundary layer
        vals = {x: float(rng.uniform(0.1, 2.0)) for x in free}
        vals[ls.eps] = eps
        got = np.array(law.u.subs(vals), dtype=float)
        want = np.array(printed.subs(vals), dtype=float)
        assert np.allclose(got, want, rtol=1e-12, atol=1e-12)


def test_tde_is_exact_for_a_constant_h1_under_zero_order_hold() -> None:
    """With q̈ constant over the period (ZOH) the backward quotient recovers it exactly."""
    h1, ts = ctl.tde_estimate("minimal", DRISHTI)
    cm = ctl.control_model("minimal", DRISHTI)
    qdd = sp.Matrix([0.7, -0.2])
    vals = {wmr.m: 36.0, wmr.I_z: 5.72, wmr.K: 0.34, wmr.I_w: 0.07, wmr.r: 0.096,
            wmr.b: 0.414, wmr.d: 0.12, ts.span: 0.1}
    u_prev = cm.mass.subs(vals) * qdd + sp.Matrix([0.3, 0.4])  # true H1 = (0.3, 0.4)
    sub = {**vals, **dict(zip(ts.u_prev, u_prev, strict=True)),
           **dict(zip(ts.qdot_now, [1.0 + 0.07, 2.0 - 0.02], strict=True)),
           **dict(zip(ts.qdot_then, [1.0, 2.0], strict=True))}
    est = h1.subs(sub)
    assert float((est - sp.Matrix([0.3, 0.4])).norm()) < 1e-12


def test_minimal_mass_inverse_norm_through_the_adjugate_matches_numpy() -> None:
    """The minimal form's ‖M̂⁻¹‖_F, built from M̂'s entries (adj M̂ / det M̂), equals the
    norm of NumPy's inverse of the same M̂ at random parameters, and needs fewer
    operations than the expanded inverse (Drishti: closed forms)."""
    from modeling.robot_file import load_robot_model

    model = load_robot_model(None)[0]
    cm = ctl.control_model("minimal", model)
    assert cm.size <= ctl.ADJUGATE_NORM_MAX_SIZE and cm.stage is None
    norm = ctl.mass_inverse_norm("minimal", model)
    symbols = sorted(cm.mass.free_symbols | norm.free_symbols, key=str)
    assert norm.free_symbols <= cm.mass.free_symbols
    f_norm = sp.lambdify(symbols, norm, "numpy")
    f_mass = sp.lambdify(symbols, cm.mass, "numpy")
    rng = np.random.default_rng(3)
    defaults = {p.symbol: float(model.values[p.key]) for p in model.params}
    for _ in range(20):
        values = [defaults[s] * rng.uniform(0.5, 2.0) if s in defaults else rng.uniform(-1.2, 1.2)
                  for s in symbols]
        expected = np.linalg.norm(np.linalg.inv(np.asarray(f_mass(*values), dtype=float)))
        assert abs(float(f_norm(*values)) - expected) < 1e-11 * expected
    expanded = sp.sqrt(sum((x**2 for x in cm.mass_inverse), sp.S.Zero))
    assert sp.count_ops(sp.cse([norm])) < sp.count_ops(sp.cse([expanded]))


def test_staged_mass_and_its_inverse_norm_match_the_closed_form() -> None:
    """The trailer's staged M̂ (modeling.staged: S solved block by block, Sᵀ M S entry by
    entry) equals the closed-form Sᵀ M S of ConstrainedSystem at random parameters and
    hitch angles, and its ‖M̂⁻¹‖_F equals NumPy's norm of that closed form's inverse."""
    from modeling.robot_file import load_robot_model
    from modeling.staged import evaluate

    model = load_robot_model("modeling/robots/trailer/trailer.toml")[0]
    cm = ctl.control_model("minimal", model)
    assert cm.stage is not None
    norm = ctl.mass_inverse_norm("minimal", model)
    closed = model.system.minimal_mass_matrix
    exprs = [*cm.mass, norm]
    definitions = cm.definitions(exprs)
    rng = np.random.default_rng(3)
    defaults = {p.symbol: float(model.values[p.key]) for p in model.params}
    for _ in range(10):
        values = {s: v * rng.uniform(0.5, 2.0) for s, v in defaults.items()}
        values.update({q: rng.uniform(-1.2, 1.2) for q in model.q})
        *mass, got_norm = evaluate(definitions, exprs, values)
        want = np.array(closed.evalf(17, subs=values), dtype=float)
        np.testing.assert_allclose(np.reshape(mass, want.shape), want, rtol=1e-12)
        assert abs(got_norm - np.linalg.norm(np.linalg.inv(want))) < 1e-11 * got_norm


def test_generated_law_reads_every_input_before_writing_an_output() -> None:
    """A function without input checks reads each input just before its first use
    (codegen/backends/c/lowering.py, LazyLoads), yet every read before the first store: the
    TDROC law writing u one entry ahead over H1hat (u[k] is H1hat[k + 1]) and s over e gives
    what it gives into fresh arrays (a read of H1hat[1] after the store of u[0] would not)."""
    from runtime.bindings import cbuild

    lib = cbuild.build(False)
    ffi = lib.ffi
    rng = np.random.default_rng(5)
    p = ffi.new("wmr_params_t *")
    p.m, p.Iz, p.K, p.Iw, p.r, p.b, p.d = 36.0, 5.72, 0.34, 0.07, 0.096, 0.414, 0.12

    def vec(n: int, lo: float = -1.0, hi: float = 1.0) -> list[float]:
        return [float(v) for v in rng.uniform(lo, hi, n)]

    args = {"trig": [0.6, 0.8], "e": vec(5), "edot": vec(5), "qdd": vec(5),
            "k1": vec(5, 1, 5), "k2": vec(5, 1, 5), "p12": vec(5, 0.1, 1),
            "p22": vec(5, 0.1, 1), "H1hat": vec(5, -3, 3)}

    def call(alias: bool) -> tuple[list[float], list[float], float]:
        a = {k: ffi.new("wmr_real_t[6]", v) for k, v in args.items()}
        gain, eps, s_norm = (ffi.new("wmr_real_t *", 2.0), ffi.new("wmr_real_t *", 0.05),
                             ffi.new("wmr_real_t *"))
        u = a["H1hat"] + 1 if alias else ffi.new("wmr_real_t[5]")
        s = a["e"] + 1 if alias else ffi.new("wmr_real_t[5]")
        lib.lib.wmr_paper_tdroc_law_trig(p, a["trig"], a["e"], a["edot"], a["qdd"], a["k1"],
                                         a["k2"], a["p12"], a["p22"], a["H1hat"], gain, eps,
                                         u, s, s_norm)
        return [u[k] for k in range(5)], [s[k] for k in range(5)], s_norm[0]

    fresh, aliased = call(False), call(True)
    assert fresh == aliased
    assert fresh[0][1:] != args["H1hat"][2:]  # u was written where H1hat was
