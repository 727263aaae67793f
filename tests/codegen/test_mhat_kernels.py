"""The ``_mhat`` kernels of a robot whose M̂ depends on q (``robot_functions.mhat_kernels``):
the step evaluates M̂(q) once (``minimal_mhat``), passes it to ‖M̂⁻¹‖ of (25) and to the
law, and keeps it for the next step's (17), which needs M̂(q(t − h)). Each ``_mhat``
kernel fed ``minimal_mhat``'s M̂ must give its kernel of q's results (the generated
Python; C = Python for every law kernel is tests/generated/test_crosscheck.py's), and the step must
call the M̂ kernel once and the kernels of q never."""

from __future__ import annotations

import random
import re

import numpy as np
import pytest

from codegen.robot_functions import mhat_kernels
from modeling.robot_file import load_robot_model
from modeling.robot_io import shipped_robot_file
from runtime.bindings.generated import load_robot_code


@pytest.mark.parametrize("robot", ["trailer", "trailer2"])
def test_mhat_kernels_equal_the_kernels_of_q(robot: str) -> None:
    code = load_robot_code(robot)
    laws, n = code.laws, code.nq
    rng = random.Random(5)
    p = {k: v * rng.uniform(0.9, 1.1) for k, v in code.params.items()}
    for _ in range(5):
        q = [rng.uniform(-3.0, 3.0) for _ in range(n)]
        q_prev = [x + rng.uniform(-0.05, 0.05) for x in q]
        two = [[rng.uniform(-2.0, 2.0) for _ in range(2)] for _ in range(9)]
        mhat, mhat_prev = laws.minimal_mhat(q, p), laws.minimal_mhat(q_prev, p)
        pairs = [
            (laws.minimal_tde(q_prev, two[0], two[1], two[2], [0.01], p),
             laws.minimal_tde_mhat(mhat_prev, two[0], two[1], two[2], [0.01], p)),
            (laws.minimal_minv_norm(q, p), laws.minimal_minv_norm_mhat(mhat, p)),
        ]
        args = (two[3], two[4], two[5], [4.0, 5.0], [3.0, 2.0], [0.5, 0.7], [0.2, 0.3],
                two[6], [1.5], [0.1])
        pairs += list(zip(laws.minimal_tdroc_law(q, *args, p),
                          laws.minimal_tdroc_law_mhat(mhat, *args, p), strict=True))
        for a, b in pairs:
            a, b = np.ravel(a), np.ravel(b)
            assert np.allclose(a, b, rtol=1e-12, atol=1e-12 * max(1.0, *np.abs(a))), (a, b)


def test_only_robots_whose_mhat_depends_on_q_get_them() -> None:
    for robot, expected in (("drishti", False), ("trailer", True), ("trailer3", True)):
        model, _ = load_robot_model(shipped_robot_file(robot))
        assert mhat_kernels(model, "minimal") == expected, robot


@pytest.mark.parametrize("robot", ["trailer", "trailer3"])
def test_the_step_evaluates_mhat_once(robot: str) -> None:
    """The TDROC and TDC steps call ``minimal_mhat`` once and no kernel of q; (17) reads
    the M̂ the state kept, which the commit writes."""
    code = load_robot_code(robot)
    pre = code.prefix
    for ctrl in ("tdroc", "tdc"):
        text = (code.c_dir / f"{pre}_{ctrl}.c").read_text()
        body = text[text.index(f"{pre}_status_t {pre}_{ctrl}_step_of("):]
        assert len(re.findall(rf"{pre}_k_minimal_mhat\(", body)) == 1
        assert re.search(rf"{pre}_k_minimal_tde_mhat\([^;]*state->mhat_prev", body)
        assert re.search(rf"{pre}_k_minimal_{ctrl}_law_mhat\(", body)
        assert not re.search(rf"{pre}_k_minimal_(tde|{ctrl}_law|minv_norm)\(", body)
        assert "state->mhat_prev[i] = mhat[i];" in body
