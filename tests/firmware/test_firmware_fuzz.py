"""Property tests (Hypothesis) of the generated C, double build through cffi, with extreme
floats: subnormals, ±max, NaN, ±inf, huge and tiny values, in the inputs, in the
configuration (before or after ``_init``) and in the robot parameters.

Properties: no crash; every status is a documented one; on success every output (tau,
within ±tau_max; every real of the state; the accelerations) is finite; on an error the
state's bytes and the outputs are untouched; a non-finite argument of the forward
dynamics is reported as such. 300 examples per property, derandomised (reproducible).
"""

from __future__ import annotations

import math
import sys
from typing import Any

import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from runtime.bindings import cbuild
from runtime.tooling.bad_input.cases import DRISHTI, max_window
from runtime.tooling.bad_input.runner import base_config, status_names

EXAMPLES = 300
FUZZ = settings(
    max_examples=EXAMPLES,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
MAX = sys.float_info.max
EXTREMES = (
    0.0,
    -0.0,
    5e-324,
    -5e-324,
    sys.float_info.min,  # smallest normal
    1e-300,
    -1e-300,
    1e-30,
    1e6,
    -1e6,
    math.nextafter(1e6, math.inf),  # just beyond the input limit
    1e9,
    1e30,
    -1e30,
    1e300,
    MAX,
    -MAX,
    math.inf,
    -math.inf,
    math.nan,
)
extreme = st.one_of(st.sampled_from(EXTREMES), st.floats(allow_nan=True, allow_infinity=True))
moderate = st.floats(-10.0, 10.0, allow_subnormal=True)
value = st.one_of(moderate, extreme)
vector5 = st.lists(value, min_size=5, max_size=5)
# Accepted by the input check (finite, |x| <= 1e6) but far from a plausible motion.
in_range = st.one_of(
    st.sampled_from((0.0, -0.0, 5e-324, -5e-324, 1e-300, 1e-30, 1e6, -1e6, 999999.9)),
    st.floats(-1e6, 1e6),
)


@st.composite
def step_inputs(draw: Any) -> list[list[float]]:
    """q, qdot, q_des, qdot_des, qddot_des: plausible, plausible with one extreme entry,
    in range but wild, or anything."""
    mode = draw(st.integers(0, 3))
    if mode == 3:
        return [draw(vector5) for _ in range(5)]
    entry = in_range if mode == 2 else moderate
    inputs = [draw(st.lists(entry, min_size=5, max_size=5)) for _ in range(5)]
    if mode == 1:
        inputs[draw(st.integers(0, 4))][draw(st.integers(0, 4))] = draw(extreme)
    return inputs


REAL_FIELDS = {
    "tdc": ("q_pos", "q_vel", "h", "tau_max"),
    "tdroc": ("q_pos", "q_vel", "h", "tau_max", "eps", "a"),
    "roc": ("q_pos", "q_vel", "h", "tau_max", "eps", "alpha", "phi"),
    "asmc": ("q_pos", "q_vel", "h", "tau_max", "eps", "gamma", "gain0"),
}
INT_FIELDS = {
    "tdc": ("formulation", "accel_estimator"),
    "tdroc": ("formulation", "accel_estimator", "n"),
    "roc": ("formulation",),
    "asmc": ("formulation",),
}
NOMINAL = ("m", "Iz", "K", "Iw", "r", "b", "d")


@pytest.fixture(scope="module")
def lib() -> cbuild.CLibrary:
    return cbuild.build(False)


def _reals(ffi: Any, value: Any) -> list[float]:
    """Every floating-point number in a cffi struct/array (ints skipped)."""
    if isinstance(value, float):
        return [value]
    if not isinstance(value, ffi.CData):
        return []
    t = ffi.typeof(value)
    if t.kind == "array":
        return [x for v in value for x in _reals(ffi, v)]
    if t.kind == "struct":
        return [x for f, _ in t.fields for x in _reals(ffi, getattr(value, f))]
    return []


def _perturb(data: st.DataObject, cfg: Any, name: str, label: str) -> None:
    """Set up to three configuration fields to extreme values."""
    choices = [
        *REAL_FIELDS[name],
        *INT_FIELDS[name],
        *(f"nominal.{p}" for p in NOMINAL),
        *(f"k1[{i}]" for i in range(5)),
        *(f"k2[{i}]" for i in range(5)),
    ]
    picked = data.draw(st.lists(st.sampled_from(choices), max_size=3, unique=True), label=label)
    for field in picked:
        if field in INT_FIELDS[name]:
            v = data.draw(
                st.one_of(st.integers(-3, 10), st.integers(-(2**31), 2**31 - 1)), label=field
            )
            setattr(cfg, field, v)
            continue
        v = data.draw(value, label=field)
        if field.startswith("nominal."):
            setattr(cfg.nominal, field.split(".")[1], v)
        elif field.startswith("k"):
            getattr(cfg, field[:2])[int(field[3])] = v
        else:
            setattr(cfg, field, v)


@pytest.mark.parametrize("name", ["tdc", "tdroc", "roc", "asmc"])
def test_controller_step_with_extreme_floats(lib: cbuild.CLibrary, name: str) -> None:
    ffi, clib = lib.ffi, lib.lib
    codes = set(status_names(lib))
    init = getattr(clib, f"wmr_{name}_init")
    step = getattr(clib, f"wmr_{name}_step")
    check = getattr(clib, f"wmr_{name}_check_config")

    @FUZZ
    @given(data=st.data())
    def prop(data: st.DataObject) -> None:
        form = data.draw(st.sampled_from(["paper", "minimal"]), label="formulation")
        cfg = base_config(lib, name, form)
        if data.draw(st.booleans(), label="bad config before init"):
            _perturb(data, cfg, name, "before init")
        state = ffi.new(f"wmr_{name}_state_t *")
        blank = bytes(ffi.buffer(state))
        status = int(init(state, cfg))
        assert status in codes and status <= 0
        assert int(check(cfg)) == status
        tau = ffi.new("wmr_real_t[2]", [7.0, -7.0])
        if status != 0:
            assert bytes(ffi.buffer(state)) == blank  # init wrote nothing
            arrays = [ffi.new("wmr_real_t[5]") for _ in range(5)]
            assert step(state, cfg, *arrays, tau) == status_by_name(lib, "WMR_ERR_NOT_INITIALISED")
            assert list(tau) == [7.0, -7.0]
            return
        for k in range(data.draw(st.integers(1, 4), label="steps")):
            if data.draw(st.integers(0, 4), label=f"late change {k}") == 0:
                _perturb(data, cfg, name, f"after init {k}")
            inputs = data.draw(step_inputs(), label=f"inputs {k}")
            arrays = [ffi.new("wmr_real_t[5]", v) for v in inputs]
            before = bytes(ffi.buffer(state))
            tau[0], tau[1] = 7.0, -7.0
            status = int(step(state, cfg, *arrays, tau))
            event(f"step status {status_names(lib)[status]}")
            assert status in codes
            if status < 0:
                assert bytes(ffi.buffer(state)) == before
                assert list(tau) == [7.0, -7.0]
                continue
            assert all(math.isfinite(x) for x in tau)
            assert max(abs(tau[0]), abs(tau[1])) <= cfg.tau_max
            assert list(state.tau) == list(tau)
            assert all(math.isfinite(x) for x in _reals(ffi, state[0]))
            # An accepted input is finite and bounded by 1e6.
            assert all(math.isfinite(x) and abs(x) <= 1e6 for v in inputs for x in v)

    prop()


def status_by_name(lib: cbuild.CLibrary, name: str) -> int:
    return {v: k for k, v in status_names(lib).items()}[name]


param = st.one_of(
    st.floats(1e-3, 1e3),
    st.sampled_from([DRISHTI[k] for k in ("m", "I", "K", "Iw", "r", "b", "d")]),
    extreme,
)


@pytest.mark.parametrize("function", ["forward_dynamics", "minimal_forward_dynamics"])
def test_forward_dynamics_with_extreme_floats(lib: cbuild.CLibrary, function: str) -> None:
    ffi = lib.ffi
    fn = getattr(lib.lib, f"wmr_{function}")
    minimal = function.startswith("minimal")
    n_rates, n_out = (2, 2) if minimal else (5, 5)
    ok, bad_input, bad_params, bad_output = (
        status_by_name(lib, s)
        for s in (
            "WMR_OK",
            "WMR_ERR_NONFINITE_INPUT",
            "WMR_ERR_BAD_PARAMS",
            "WMR_ERR_NONFINITE_OUTPUT",
        )
    )

    @FUZZ
    @given(
        p=st.lists(param, min_size=7, max_size=7),
        q=vector5,
        rates=st.lists(value, min_size=n_rates, max_size=n_rates),
        tau=st.lists(value, min_size=2, max_size=2),
    )
    def prop(p: list[float], q: list[float], rates: list[float], tau: list[float]) -> None:
        params = ffi.new("wmr_params_t *")
        for key, v in zip(NOMINAL, p, strict=True):
            setattr(params, key, v)
        out = ffi.new(f"wmr_real_t[{n_out}]", [42.0] * n_out)
        status = int(
            fn(
                params,
                ffi.new("wmr_real_t[5]", q),
                ffi.new(f"wmr_real_t[{n_rates}]", rates),
                ffi.new("wmr_real_t[2]", tau),
                out,
            )
        )
        event(f"status {status}")
        assert status in (ok, bad_input, bad_params, bad_output)
        read = [*p, *tau, *(rates if minimal else [q[2], rates[3], rates[4]])]
        if not all(math.isfinite(x) for x in read):
            assert status == bad_input
        if status == ok:
            assert all(math.isfinite(x) for x in out)
        else:
            assert list(out) == [42.0] * n_out

    prop()


@pytest.mark.parametrize("name", ["tdc", "tdroc", "roc", "asmc"])
def test_controller_step_with_a_corrupted_state(lib: cbuild.CLibrary, name: str) -> None:
    """A state corrupted after a few valid steps, ``magic`` intact (issue 52): one to three
    flipped bits anywhere else, or (TDROC) its ring's head or count set to any int. The step
    returns a documented status; refused, it writes neither the state nor tau; accepted, tau
    is finite and within ±tau_max. A TDROC head or count out of its range is refused with
    ``WMR_ERR_NOT_INITIALISED`` (or ``WMR_ERR_CONFIG_CHANGED`` when a bit of the kept
    configuration flipped too; without the bound, the step wrote outside ``omega_ring``)."""
    ffi, clib = lib.ffi, lib.lib
    codes = set(status_names(lib))
    not_init = status_by_name(lib, "WMR_ERR_NOT_INITIALISED")
    changed = status_by_name(lib, "WMR_ERR_CONFIG_CHANGED")
    init = getattr(clib, f"wmr_{name}_init")
    step = getattr(clib, f"wmr_{name}_step")
    ctype = f"wmr_{name}_state_t"
    size = ffi.sizeof(ctype)
    magic = range(ffi.offsetof(ctype, "magic"), ffi.offsetof(ctype, "magic") + ffi.sizeof("long"))
    flippable = [i for i in range(size) if i not in magic]
    window = max_window(lib)
    motion = [[0.1 * (i + 1), 0.2, 0.1 * i, 0.2, 0.0] for i in range(5)]

    @FUZZ
    @given(data=st.data())
    def prop(data: st.DataObject) -> None:
        form = data.draw(st.sampled_from(["paper", "minimal"]), label="formulation")
        cfg = base_config(lib, name, form)
        state = ffi.new(f"{ctype} *")
        assert int(init(state, cfg)) == 0
        tau = ffi.new("wmr_real_t[2]")
        arrays = [ffi.new("wmr_real_t[5]", v) for v in motion]
        for _ in range(data.draw(st.integers(0, 12), label="valid steps")):
            assert int(step(state, cfg, *arrays, tau)) >= 0
        raw = ffi.cast("unsigned char *", state)
        if name == "tdroc" and data.draw(st.booleans(), label="set an index"):
            which = data.draw(st.sampled_from(["omega_head", "omega_count"]), label="index")
            setattr(state, which, data.draw(st.integers(-(2**31), 2**31 - 1), label="to"))
        else:
            for at in data.draw(st.lists(st.sampled_from(flippable), min_size=1, max_size=3),
                                label="bytes"):
                raw[at] ^= 1 << data.draw(st.integers(0, 7), label="bit")
        out_of_range = name == "tdroc" and not (
            0 <= state.omega_head < window and 0 <= state.omega_count <= window + 1)
        event("index out of range" if out_of_range else "in range")
        before = bytes(ffi.buffer(state))
        tau[0], tau[1] = 7.0, -7.0
        status = int(step(state, cfg, *arrays, tau))
        assert status in codes
        if out_of_range:  # refused (CONFIG_CHANGED first if a kept configuration bit flipped)
            assert status in (not_init, changed)
        if status < 0:
            assert bytes(ffi.buffer(state)) == before
            assert list(tau) == [7.0, -7.0]
        else:
            assert all(math.isfinite(x) and abs(x) <= cfg.tau_max for x in tau)

    prop()
