"""The rows of the history a step writes (issue 52): a formulation's step writes the rows its
steps read and no other. Drishti's paper formulation reads every row of q(t-h) (through its
sin and cos), qdot(t-h), qdot(t-2h), u(t-h), u(t-2h); the minimal one reads the controlled
rows 4-5 (0-based 3..4) of the rates and inputs and no row of q(t-h), and its H1hat and
sin/cos have no other rows. The rows no step of a formulation reads stay as ``_init`` left
them (zero): the formulation cannot change without ``_init``. Double and float32 builds,
every controller of each formulation it has.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from runtime.bindings import cbuild
from runtime.tooling.bad_input.cases import (
    BASE,
    CONTROLLER_FORMULATIONS,
    CONTROLLERS,
    FORMULATIONS,
)
from runtime.tooling.bad_input.runner import Controller, base_config, smooth_sequence

FORMS = [(n, f) for n in CONTROLLERS for f in FORMULATIONS if f in CONTROLLER_FORMULATIONS[n]]
CONTROLLED = {"paper": range(5), "minimal": range(3, 5)}  # rows of q each formulation controls
STEPS = 6


@pytest.fixture(scope="module", params=["double", "float32"])
def lib(request: pytest.FixtureRequest) -> cbuild.CLibrary:
    return cbuild.build(request.param == "float32")


def _rows(lib: cbuild.CLibrary, state: Any, field: str, n: int) -> list[float]:
    return [float(x) for x in lib.ffi.unpack(getattr(state, field), n)]


@pytest.mark.parametrize(("name", "form"), FORMS, ids=[f"{n}-{f}" for n, f in FORMS])
def test_a_step_writes_the_rows_its_formulation_reads(lib: cbuild.CLibrary, name: str,
                                                      form: str) -> None:
    real = np.float32 if lib.float32 else np.float64
    ctl = Controller(lib, name, base_config(lib, name, form))
    seq = smooth_sequence(STEPS, float(BASE["h"]))
    taus = []
    for inputs in seq:
        status, tau = ctl.step(inputs)
        assert status >= 0, status
        taus.append(tau)
    st = ctl.state
    fields = {f for f, _ in lib.ffi.typeof(st).item.fields}
    rows = CONTROLLED[form]
    q, qdot, qdot_before = (np.asarray(v, dtype=real) for v in (seq[-1][0], seq[-1][1],
                                                                seq[-2][1]))
    assert np.any(qdot[:3] != 0.0) and np.any(q[:3] != 0.0)  # rows a push would change
    expected = {
        "qdot_prev": qdot, "qdot_prev2": qdot_before,
        "u_prev": np.array([0.0, 0.0, 0.0, *taus[-1]], dtype=real),
        "u_prev2": np.array([0.0, 0.0, 0.0, *taus[-2]], dtype=real),
    }
    for field, value in expected.items():
        got = _rows(lib, st, field, 5)
        for i in range(5):
            want = float(value[i]) if i in rows else 0.0  # as _init left it
            assert got[i] == want, (field, i)
    if "q_prev" in fields:  # the paper form's sin/cos are of q(t-h); the minimal (17) reads none
        want_q = [float(x) for x in q] if form == "paper" else [0.0] * 5
        assert _rows(lib, st, "q_prev", 5) == want_q
    if form == "minimal" and "H1hat" in fields:  # the estimate's rows beyond the controlled two
        assert _rows(lib, st, "H1hat", 5)[2:] == [0.0, 0.0, 0.0]
    if form == "minimal" and "trig_prev" in fields:  # Drishti's minimal M-hat has no angle
        assert all(x == 0.0 for x in _rows(lib, st, "trig_prev", len(st.trig_prev)))
