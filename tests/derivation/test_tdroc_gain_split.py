"""(25) evaluated incrementally (issue 12): the step keeps the window's difference norms
‖Ω(i) − Ω(i+1)‖, each computed once by ``omega_difference_norm`` when its newer row joins,
and ``tdroc_weighted_gain`` weighs them. Composed, they are ``tdroc_gain`` exactly."""

from __future__ import annotations

import pytest
import sympy as sp

from codegen.robot_functions import MAX_WINDOW, law_specs
from modeling import controllers as ctl
from modeling.robots.drishti import model as wmr

DRISHTI = wmr.robot_model()


@pytest.mark.parametrize("formulation", ["paper", "minimal"])
def test_weighted_gain_of_difference_norms_is_tdroc_gain(formulation: ctl.Formulation) -> None:
    gain, omega, w = ctl.tdroc_gain(formulation, MAX_WINDOW, DRISHTI)
    norm, newer, older = ctl.omega_difference_norm(formulation, DRISHTI)
    split, dn, w2 = ctl.tdroc_weighted_gain(MAX_WINDOW)
    norms = {
        dn[i]: norm.xreplace({**dict(zip(newer, omega[i, :], strict=True)),
                              **dict(zip(older, omega[i + 1, :], strict=True))})
        for i in range(MAX_WINDOW)
    }
    composed = split.xreplace(norms).xreplace(dict(zip(w2, w, strict=True)))
    assert sp.expand(composed - gain) == 0


def test_generated_weighted_gain_adds_the_newest_norm_last() -> None:
    """The kernel's staging (the older norms' sum, then the newest norm's term: one add
    waits for this step's norm) is (25)'s weighted sum, rearranged only."""
    spec = next(s for s in law_specs(DRISHTI) if s.name == "tdroc_weighted_gain")
    (older, older_sum), = spec.definitions
    gain = spec.outputs[0].exprs[0]
    split, dn, _ = ctl.tdroc_weighted_gain(MAX_WINDOW)
    assert dn[0] not in older_sum.free_symbols and older in gain.free_symbols
    assert sp.expand(gain.xreplace({older: older_sum}) - split) == 0
