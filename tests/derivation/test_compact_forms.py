"""The evaluation forms the code is generated from equal the canonical derivation.

``compact_forward_dynamics`` regroups Sᵀ M S and factors H̄, S and Ṡη so that CSE finds
shared factors (about 40 % fewer multiplications); it must not change a value.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from modeling.robots.drishti import model as wmr


@pytest.mark.parametrize("lateral", [False, True])
def test_compact_forward_dynamics_equals_the_derivation(lateral: bool) -> None:
    s = wmr.wmr_system(lateral)
    eta_c, qdd_c = s.compact_forward_dynamics(wmr.tau, wmr.compact_form)
    eta_ref = s.minimal_forward_dynamics(wmr.tau)
    qdd_ref = s.reduced_forward_dynamics(wmr.tau)
    params = wmr.PLANT_SYMBOLS if lateral else wmr.LUMPED_SYMBOLS
    args = (*params, *wmr.q, *wmr.qdot, *wmr.tau)
    f = sp.lambdify(args, [*eta_c, *qdd_c, *eta_ref, *qdd_ref], "math")
    rng = np.random.default_rng(3)
    nominal = {wmr.m: 36.0, wmr.I_z: 5.72, wmr.K: 0.34, wmr.K_lat: 0.3, wmr.I_w: 0.07,
               wmr.r: 0.096, wmr.b: 0.414, wmr.d: 0.12}
    for _ in range(200):
        p = [nominal[sym] * rng.uniform(0.7, 1.3) for sym in params]
        vals = np.array(f(*p, *rng.uniform(-3, 3, 10), *rng.uniform(-5, 5, 2)))
        compact, ref = vals[:7], vals[7:]
        assert np.linalg.norm(compact - ref) <= 1e-12 * max(np.linalg.norm(ref), 1.0)


def test_compact_form_groups_the_axle_inertia() -> None:
    s = wmr.wmr_system()
    entry = wmr.compact_form(s.minimal_mass_matrix[0, 0])
    axle = wmr.I_z - 2 * wmr.K * wmr.d + wmr.m * wmr.d**2
    assert sp.simplify(entry - (wmr.I_w + wmr.m * wmr.r**2 / 4
                                + wmr.r**2 / wmr.b**2 * axle)) == 0
    assert entry.has(sp.factor(axle)) or entry.has(axle)


def test_plane_accelerations_are_rotated_once_from_the_body_frame() -> None:
    """``forward_dynamics_forms``: ẍ, ÿ as R(θ) a with a free of θ (one rotation, which CSE
    keeps as two temporaries), equal to the reduced forward dynamics (9), (14)."""
    from codegen.robot_functions import forward_dynamics_forms
    from modeling.robots.drishti.model import robot_model

    model = robot_model()
    _, qdd = forward_dynamics_forms(model)
    theta = model.heading
    c, s = sp.cos(theta), sp.sin(theta)
    # the form as written (not expanded): two products each, of cos θ and sin θ with the
    # same two θ-free factors (a0, a1)
    a0, a1 = qdd[0].coeff(c), qdd[1].coeff(c)
    assert len(sp.Add.make_args(qdd[0])) == len(sp.Add.make_args(qdd[1])) == 2
    assert a0 != 0 and a1 != 0 and not a0.has(theta) and not a1.has(theta)
    assert qdd[0] == c * a0 - s * a1 and qdd[1] == s * a0 + c * a1
    ref = model.system.reduced_forward_dynamics(model.tau)
    params = tuple(p.symbol for p in model.params)
    args = (*params, *model.q, *model.qdot, *model.tau)
    f = sp.lambdify(args, [*qdd, *ref], "math")
    rng = np.random.default_rng(5)
    nominal = np.array([36.0, 5.72, 0.34, 0.07, 0.096, 0.414, 0.12])
    assert len(params) == len(nominal)
    for _ in range(100):
        p = nominal * rng.uniform(0.7, 1.3, len(nominal))
        vals = np.array(f(*p, *rng.uniform(-3, 3, 10), *rng.uniform(-5, 5, 2)))
        ours, want = vals[:5], vals[5:]
        assert np.linalg.norm(ours - want) <= 1e-12 * max(np.linalg.norm(want), 1.0)
