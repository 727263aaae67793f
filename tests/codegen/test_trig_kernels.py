"""The ``_trig`` kernels: (17) and the TDC/TDROC laws with sin, cos of the angles M̂
depends on as inputs instead of q (a controller step computes them once and keeps them for
the next step's (17)). They must equal the q kernels at trig = (sin a, cos a), for every
robot that has them, in the generated NumPy (which the C and CasADi are checked against).
"""

from __future__ import annotations

import importlib
import math

import numpy as np
import pytest
from shipped_robots import derivable_robot_files

from codegen.robot_functions import law_specs, trig_angles
from modeling.robot_file import load_robot_model

ROBOTS = derivable_robot_files()  # laws derived here: not train5 (tests/shipped_robots.py)


def _laws(prefix: str, name: str) -> object:
    package = "generated.python" if name == "drishti" else f"generated.{name}.python"
    return importlib.import_module(f"{package}.{prefix}_laws")


@pytest.mark.parametrize("robot", sorted(ROBOTS))
def test_trig_kernels_equal_the_q_kernels(robot: str) -> None:
    model, spec_robot = load_robot_model(ROBOTS[robot])
    laws = _laws(model.prefix, robot)
    specs = {s.name: s for s in law_specs(model)}
    variants = [s for s in specs if s.endswith("_trig")]
    if model.staged:  # M-hat is evaluated through the stage's quantities: no trig inputs
        assert not variants and not trig_angles(model, "minimal"), robot
        return
    assert variants, f"{robot}: no _trig kernels"
    rng = np.random.default_rng(7)
    params = dict(spec_robot.lumped)
    for name in variants:
        base = specs[name.removesuffix("_trig")]
        formulation = name.split("_")[0]
        angles = trig_angles(model, formulation)  # type: ignore[arg-type]
        coords = next(a.name for a in base.inputs if a.name in ("q", "q_prev"))
        for _ in range(20):
            args = {a.name: rng.uniform(-3.0, 3.0, len(a.symbols))
                    for a in base.inputs if a.kind == "array"}
            q = args[coords]
            trig = [f(q[i]) for i in angles for f in (math.sin, math.cos)]
            want = getattr(laws, base.name)(*args.values(), params)
            got_args = [trig if k == coords else v for k, v in args.items()]
            got = getattr(laws, name)(*got_args, params)
            for w, g in zip(np.atleast_1d(want) if not isinstance(want, tuple) else want,
                            np.atleast_1d(got) if not isinstance(got, tuple) else got,
                            strict=True):
                np.testing.assert_allclose(g, w, rtol=1e-12, atol=1e-12, err_msg=name)


def test_drishti_paper_trig_is_the_heading_only() -> None:
    model, _ = load_robot_model(ROBOTS["drishti"])
    assert trig_angles(model, "paper") == (2,)  # θ: M̃ of (14) depends on it alone
    assert trig_angles(model, "minimal") == ()  # M̄ is constant


def test_tde_step_calls_the_trig_kernels() -> None:
    """The generated steps of TDC and TDROC compute sin/cos of q once and pass them on."""
    from codegen.generate import GENERATED_DIR

    for ctrl in ("tdc", "tdroc"):
        text = (GENERATED_DIR / "c" / f"wmr_{ctrl}.c").read_text()
        # the step's body: specialised per formulation, wmr_<ctrl>_step_as
        step = text[text.index(f"wmr_status_t wmr_{ctrl}_step_as("):]
        # once, through sincos_checked (q is checked against its bound before)
        assert step.count("wmr_sincos_checked(q[2], &trig[0], &trig[1]);") == 1, ctrl
        assert "WMR_SIN(" not in step and "WMR_COS(" not in step, ctrl
        assert step.index("wmr_check_step_inputs(") < step.index("wmr_sincos_checked("), ctrl
        # the shared kernels (wmr_kernels.h), reading the values _init kept
        assert (f"wmr_k_paper_{ctrl}_law_trig(kept_paper_{ctrl}_law_trig, trig,"
                in step), ctrl
        assert ("wmr_k_paper_tde_trig(kept_paper_tde_trig, state->trig_prev,"
                in step), ctrl
