"""The generated code under bad input: exact status codes, state and outputs unchanged, the
next valid step equal to that of a twin that never saw the bad input; uninitialised states
and NULL pointers; saturation; the forward-dynamics guards (non-finite input, bad or
indefinite parameters).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from generated_code_support import (
    CONTROLLER_CASES,
    CONTROLLER_IDS,
    DRISHTI,
    FORMULATIONS,
    INFO,
    PARAM_SYMBOLS,
    PY_CLASSES,
    RTOL_CONTROLLER,
    STATUS,
    CBuild,
    CController,
    _c_config,
    _c_params,
    _close,
    _config,
    _smooth_sequence,
)

from codegen.layout import argument_size
from codegen.robot_functions import MAX_WINDOW, model_specs
from modeling.controllers import ControllerSpec
from modeling.robots.drishti.model import PARAM_KEYS, robot_model
from runtime.bindings.generated import controllers as pyctl
from runtime.bindings.generated import wmr_model as py_model

K2_OVER_M = DRISHTI["K"] ** 2 / DRISHTI["m"]


@dataclass(frozen=True)
class BadCase:
    id: str
    status: str
    inputs: tuple[int, int, float] | None = None  # (which input, index, value)
    config: dict[str, Any] | None = None
    applies: Callable[[ControllerSpec], bool] = lambda info: True


def _bad_cases() -> list[BadCase]:
    cases = []
    names = ("q", "qdot", "q_des", "qdot_des", "qddot_des")
    for which, label in enumerate(names):
        status = "WMR_ERR_BAD_MEASUREMENT" if which < 2 else "WMR_ERR_BAD_REFERENCE"
        for index, value in ((0, math.nan), (4, math.inf), (2, -math.inf), (1, 1e9)):
            cases.append(BadCase(f"{label}[{index}]={value:g}", status, (which, index, value)))
    nominal = lambda **kw: {"nominal": {**DRISHTI, **kw}}  # noqa: E731
    for cid, status, change, applies in (
        ("eps=0", "WMR_ERR_BAD_EPS", {"eps": 0.0}, lambda i: i.switching),
        ("eps<0", "WMR_ERR_BAD_EPS", {"eps": -0.1}, lambda i: i.switching),
        ("eps=nan", "WMR_ERR_BAD_EPS", {"eps": math.nan}, lambda i: i.switching),
        ("n=1", "WMR_ERR_BAD_WINDOW", {"n": 1}, lambda i: i.window),
        ("n=max+1", "WMR_ERR_BAD_WINDOW", {"n": MAX_WINDOW + 1}, lambda i: i.window),
        ("a=0", "WMR_ERR_BAD_DISCOUNT", {"a": 0.0}, lambda i: i.window),
        ("a=1.5", "WMR_ERR_BAD_DISCOUNT", {"a": 1.5}, lambda i: i.window),
        ("h=0", "WMR_ERR_BAD_SAMPLE_TIME", {"h": 0.0}, None),
        ("h<0", "WMR_ERR_BAD_SAMPLE_TIME", {"h": -0.01}, None),
        ("k1=0", "WMR_ERR_BAD_GAINS", {"k1": [4.0, 0.0, 6.0, 7.0, 8.0]},
         lambda i: i.error_dynamics),
        ("k2<0", "WMR_ERR_BAD_GAINS", {"k2": [3.0, 3.5, 4.0, 4.5, -5.0]},
         lambda i: i.error_dynamics),
        ("q_pos=0", "WMR_ERR_BAD_GAINS", {"q_pos": 0.0}, lambda i: i.error_dynamics),
        ("kp=0", "WMR_ERR_BAD_GAINS", {"kp": 0.0}, lambda i: i.integrator),
        ("ki<0", "WMR_ERR_BAD_GAINS", {"ki": -1.0}, lambda i: i.integrator),
        ("ky=nan", "WMR_ERR_BAD_GAINS", {"ky": math.nan}, lambda i: i.integrator),
        ("formulation=paper", "WMR_ERR_BAD_FORMULATION", {"formulation": 0},
         lambda i: "paper" not in i.formulations),
        ("m=0", "WMR_ERR_BAD_NOMINAL", nominal(m=0.0), None),
        ("I=K2/m", "WMR_ERR_BAD_NOMINAL", nominal(I=K2_OVER_M), None),
        ("I<K2/m", "WMR_ERR_BAD_NOMINAL", nominal(I=0.5 * K2_OVER_M), None),
        ("K=nan", "WMR_ERR_BAD_NOMINAL", nominal(K=math.nan), None),
        ("b=0", "WMR_ERR_BAD_NOMINAL", nominal(b=0.0), None),
        ("tau_max=0", "WMR_ERR_BAD_TORQUE_LIMIT", {"tau_max": 0.0}, None),
        ("tau_max<0", "WMR_ERR_BAD_TORQUE_LIMIT", {"tau_max": -5.0}, None),
        ("tau_max=nan", "WMR_ERR_BAD_TORQUE_LIMIT", {"tau_max": math.nan}, None),
        ("formulation=2", "WMR_ERR_BAD_FORMULATION", {"formulation": 2}, None),
        ("formulation=-1", "WMR_ERR_BAD_FORMULATION", {"formulation": -1}, None),
        ("estimator=3", "WMR_ERR_BAD_ESTIMATOR", {"accel_estimator": 3}, lambda i: i.tde),
        ("alpha=1", "WMR_ERR_BAD_BOUNDS", {"alpha": 1.0}, lambda i: i.bounds),
        ("phi<0", "WMR_ERR_BAD_BOUNDS", {"phi": -1.0}, lambda i: i.bounds),
        ("gamma<0", "WMR_ERR_BAD_BOUNDS", {"gamma": -1.0}, lambda i: i.adaptive),
        ("gain0<0", "WMR_ERR_BAD_BOUNDS", {"gain0": -1.0}, lambda i: i.adaptive),
    ):
        cases.append(BadCase(cid, status, config=change, applies=applies or (lambda i: True)))
    return cases


BAD_CASES = _bad_cases()
BAD_PARAMS = [
    pytest.param(name, form, case, id=f"{name}-{form}-{case.id}")
    for name in INFO
    for form in FORMULATIONS
    for case in BAD_CASES
    if case.applies(INFO[name]) and form in INFO[name].formulations
]
WARMUP = 4


def _same_py_state(a: dict[str, Any], b: dict[str, Any]) -> bool:
    if a.keys() != b.keys():
        return False
    for k in a:
        if isinstance(a[k], np.ndarray) or isinstance(b[k], np.ndarray):
            if not np.array_equal(a[k], b[k], equal_nan=True):
                return False
        elif a[k] != b[k]:
            return False
    return True


def _same_c_fields(a: dict[str, Any], b: dict[str, Any]) -> bool:
    return _same_py_state(
        {k: v for k, v in a.items() if not isinstance(v, dict)},
        {k: v for k, v in b.items() if not isinstance(v, dict)},
    ) and all(_same_c_fields(a[k], b[k]) for k in a if isinstance(a[k], dict))


@pytest.mark.parametrize(("name", "form", "case"), BAD_PARAMS)
def test_bad_input_is_rejected_without_side_effects(
    c_builds: dict[str, CBuild], name: str, form: str, case: BadCase
) -> None:
    build = c_builds["double"]
    ffi = build.ffi
    config = _config(name, FORMULATIONS[form])
    seq = _smooth_sequence(3, WARMUP + 1, config.h)
    c_bad, c_twin = CController(build, name, config), CController(build, name, config)
    py_bad, py_twin = PY_CLASSES[name](config), PY_CLASSES[name](config)
    for inputs in seq[:WARMUP]:
        for ctrl in (c_bad, c_twin, py_bad, py_twin):
            ctrl.step(*inputs)
    inputs = [np.array(v, dtype=float) for v in seq[WARMUP]]
    bad_inputs = [v.copy() for v in inputs]
    step_config: dict[str, Any] = {}
    bad_config = config
    if case.inputs is not None:
        which, index, value = case.inputs
        bad_inputs[which][index] = value
    if case.config is not None:
        bad_config = dataclasses.replace(config, **case.config)
        step_config = {"config": _c_config(build, name, bad_config)}
    code = STATUS[case.status]

    # C: the code, no change to the state (bytes) or to tau.
    before = c_bad.raw()
    tau = ffi.new("wmr_real_t[2]", [111.0, -222.0])
    status, _ = c_bad.step(*bad_inputs, tau=tau, **step_config)
    assert status == code, (status, code)
    assert c_bad.raw() == before
    assert list(tau) == [111.0, -222.0]
    if case.config is not None:  # init and check_config reject it too, state untouched
        fresh = ffi.new(f"wmr_{name}_state_t *")
        ffi.memmove(fresh, b"\xab" * ffi.sizeof(fresh[0]), ffi.sizeof(fresh[0]))
        pattern = bytes(ffi.buffer(fresh))
        init = getattr(build.lib, f"wmr_{name}_init")
        assert init(fresh, step_config["config"]) == code
        assert bytes(ffi.buffer(fresh)) == pattern
        assert getattr(build.lib, f"wmr_{name}_check_config")(step_config["config"]) == code

    # Python: the same code, state() unchanged; the constructor rejects a bad config.
    snapshot = py_bad.state()
    with pytest.raises(pyctl.ControllerError) as exc_info:
        py_bad.step(*bad_inputs, config=bad_config)
    assert exc_info.value.code == code and exc_info.value.status == case.status
    assert _same_py_state(py_bad.state(), snapshot)
    if case.config is not None:
        with pytest.raises(pyctl.ControllerError) as exc_info:
            PY_CLASSES[name](bad_config)
        assert exc_info.value.code == code

    # The next valid step is that of a twin that never saw the bad input.
    s_bad, tau_bad = c_bad.step(*inputs)
    s_twin, tau_twin = c_twin.step(*inputs)
    assert (s_bad, list(tau_bad)) == (s_twin, list(tau_twin))
    assert _same_c_fields(c_bad.fields(), c_twin.fields())
    np.testing.assert_array_equal(py_bad.step(*inputs), py_twin.step(*inputs))
    assert _same_py_state(py_bad.state(), py_twin.state())
    assert _close(list(tau_bad), py_twin.tau, RTOL_CONTROLLER)


@pytest.mark.parametrize("name", list(INFO))
def test_c_uninitialised_state_and_null_pointers(c_builds: dict[str, CBuild], name: str) -> None:
    build = c_builds["double"]
    ffi, lib = build.ffi, build.lib
    config = _config(name, FORMULATIONS[INFO[name].formulations[0]])
    inputs = _smooth_sequence(5, 1, config.h)[0]
    step = getattr(lib, f"wmr_{name}_step")
    init = getattr(lib, f"wmr_{name}_init")
    # Never initialised: zeroed and garbage states.
    for fill in (b"\x00", b"\x5a"):
        ctrl = CController(build, name, config)
        ffi.memmove(ctrl.state, fill * ffi.sizeof(ctrl.state[0]), ffi.sizeof(ctrl.state[0]))
        before = ctrl.raw()
        tau = ffi.new("wmr_real_t[2]", [7.0, 8.0])
        status, _ = ctrl.step(*inputs, tau=tau)
        assert status == STATUS["WMR_ERR_NOT_INITIALISED"]
        assert ctrl.raw() == before and list(tau) == [7.0, 8.0]
    # NULL in each pointer argument of step, init and check_config.
    ctrl = CController(build, name, config)
    ctrl.step(*inputs)
    before = ctrl.raw()
    args = [ctrl.state, ctrl.config, *[ffi.new("wmr_real_t[5]", list(v)) for v in inputs]]
    tau = ffi.new("wmr_real_t[2]", [7.0, 8.0])
    args.append(tau)
    for i in range(len(args)):
        call = [ffi.NULL if j == i else a for j, a in enumerate(args)]
        assert step(*call) == STATUS["WMR_ERR_NULL_POINTER"], i
        assert ctrl.raw() == before and list(tau) == [7.0, 8.0]
    assert init(ffi.NULL, ctrl.config) == STATUS["WMR_ERR_NULL_POINTER"]
    assert init(ctrl.state, ffi.NULL) == STATUS["WMR_ERR_NULL_POINTER"]
    assert ctrl.raw() == before
    check = getattr(lib, f"wmr_{name}_check_config")
    assert check(ffi.NULL) == STATUS["WMR_ERR_NULL_POINTER"]


@pytest.mark.parametrize(("name", "form"), CONTROLLER_CASES, ids=CONTROLLER_IDS)
def test_saturation_is_clipped_and_reported(
    c_builds: dict[str, CBuild], name: str, form: str
) -> None:
    build = c_builds["double"]
    limit = 0.5
    free = _config(name, FORMULATIONS[form], tau_max=1e5)
    clipped = dataclasses.replace(free, tau_max=limit)
    q = np.zeros(5)
    inputs = (q, np.zeros(5), q + 0.8, np.full(5, 1.0), np.full(5, 2.0))  # large errors
    status_free, tau_free = CController(build, name, free).step(*inputs)
    assert status_free == STATUS["WMR_OK"]
    assert np.max(np.abs(list(tau_free))) > limit
    c_ctl = CController(build, name, clipped)
    status, tau = c_ctl.step(*inputs)
    assert status == STATUS["WMR_WARN_SATURATED"] == 1
    np.testing.assert_array_equal(list(tau), np.clip(list(tau_free), -limit, limit))
    assert list(c_ctl.state.tau) == list(tau)
    py_ctl = PY_CLASSES[name](clipped)
    np.testing.assert_array_equal(py_ctl.step(*inputs), list(tau))
    assert py_ctl.last_status == "WMR_WARN_SATURATED"
    # Well inside the limit: WMR_OK again.
    relaxed = CController(build, name, dataclasses.replace(free, tau_max=1e5))
    assert relaxed.step(*inputs)[0] == STATUS["WMR_OK"]


@pytest.mark.parametrize("precision", ["double", "float"])
@pytest.mark.parametrize("function", ["forward_dynamics", "minimal_forward_dynamics"])
def test_forward_dynamics_guards(
    c_builds: dict[str, CBuild], precision: str, function: str
) -> None:
    """NaN/Inf in any input the function reads: WMR_ERR_NONFINITE_INPUT; b = 0, r = 0, b < 0:
    WMR_ERR_BAD_PARAMS; the output buffer is untouched. Python raises ValueError naming
    the same status."""
    build = c_builds[precision]
    ffi, lib = build.ffi, build.lib
    spec = next(s for s in model_specs(robot_model()) if s.name == function)
    paper = function == "forward_dynamics"
    good = {
        "q": [0.3, -0.2, 0.4, 1.0, -1.0],
        "rates": [0.0, 0.0, 0.0, 1.5, -0.5] if paper else [1.5, -0.5],
        "tau": [2.0, -1.0],
    }
    # The entries the function reads (the others, e.g. x_c, are documented as unused).
    used = set().union(*(e.free_symbols for g in spec.checked_spec().outputs for e in g.exprs))
    read = {
        key: [i for i, s in enumerate(arg.symbols) if s in used]
        for key, arg in zip(("q", "rates", "tau"), spec.inputs[1:], strict=True)
    }
    assert read["tau"] == [0, 1] and len(read["rates"]) == 2
    n_out = argument_size(spec.outputs[0])

    def call(values: dict[str, list[float]], params: dict[str, float]) -> tuple[int, list[float]]:
        out = ffi.new(f"wmr_real_t[{n_out}]", [123.0] * n_out)
        arrays = [ffi.new("wmr_real_t[]", values[k]) for k in ("q", "rates", "tau")]
        status = getattr(lib, f"wmr_{function}")(_c_params(ffi, params), *arrays, out)
        return int(status), list(out)

    def py_call(values: dict[str, list[float]], params: dict[str, float]) -> Any:
        return getattr(py_model, function)(values["q"], values["rates"], values["tau"], params)

    status, out = call(good, DRISHTI)
    assert status == STATUS["WMR_OK"] and out != [123.0] * n_out
    cases: list[tuple[str, dict[str, list[float]], dict[str, float]]] = []
    for key, indices in read.items():
        for i in indices:
            for value in (math.nan, math.inf):
                bad = {k: list(v) for k, v in good.items()}
                bad[key][i] = value
                cases.append(("WMR_ERR_NONFINITE_INPUT", bad, DRISHTI))
    for key, symbol in zip(PARAM_KEYS, PARAM_SYMBOLS, strict=True):
        if symbol in used:
            cases.append(("WMR_ERR_NONFINITE_INPUT", good, {**DRISHTI, key: math.nan}))
    for key, value in (("b", 0.0), ("r", 0.0), ("b", -0.414), ("r", -0.096)):
        cases.append(("WMR_ERR_BAD_PARAMS", good, {**DRISHTI, key: value}))
    for expected, values, params in cases:
        status, out = call(values, params)
        assert status == STATUS[expected], (expected, values, params, status)
        assert out == [123.0] * n_out
        if precision == "double":
            with pytest.raises(ValueError, match=f"^{expected}:"):
                py_call(values, params)


def test_forward_dynamics_rejects_an_indefinite_model() -> None:
    """Iw = -1 keeps det(SᵀMS) > 0 (both eigenvalues negative): the leading-minor guard
    (Sylvester) must still reject it."""
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
    from generated.python import robot as gen_robot
    from generated.python import wmr_model as gen_model

    params = {**gen_robot.PARAMS, "Iw": -1.0}
    with pytest.raises(ValueError, match="WMR_ERR_BAD_PARAMS"):
        gen_model.forward_dynamics(np.zeros(5), np.zeros(5), np.zeros(2), params)
    with pytest.raises(ValueError, match="WMR_ERR_BAD_PARAMS"):
        gen_model.minimal_forward_dynamics(np.zeros(5), np.zeros(2), np.zeros(2), params)
