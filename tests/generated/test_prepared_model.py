"""The prepare-parameters API of the generated forward dynamics, for every shipped robot in
double and float32, and for the paper's robot with the numbers of
tests/robots/small_robot.toml (a robot file users tried):

* ``<prefix>_forward_dynamics_prepared`` after ``<prefix>_model_prepare`` gives the results
  of ``<prefix>_forward_dynamics`` bit for bit, with the same status, at random states and
  parameters, valid or not;
* ``<prefix>_model_prepare`` refuses each bad parameter with the status the unprepared
  function returns for it (NaN or infinite: ``ERR_NONFINITE_INPUT``; r, b and the like
  <= 0, an indefinite S^T M S: ``ERR_BAD_PARAMS``) and writes nothing on error (a struct
  it prepared before still holds the old parameters);
* a struct ``_prepare`` did not fill (zero-filled, garbage, the magic word overwritten) is
  refused with ``ERR_NOT_INITIALISED``;
* the prepared call checks the state inputs it reads and its results, and writes no
  output on error;
* the split itself (codegen.prepare) on a toy function: parameter-only subexpressions and
  guards go to prepare, a state-dependent guard stays in the per-call part, no division
  is left per call, and the rendered C agrees bit for bit.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import sympy as sp

from codegen.backend import function_ir
from codegen.backends import c as c_backend
from codegen.backends.c.config import CConfig, StatusCode
from modeling.robot_file import load_robot, load_robot_model, shipped_robot_files
from runtime.bindings import cbuild
from runtime.bindings.generated import GENERATED, RobotCode, load_robot_code

ROOT = Path(__file__).resolve().parents[2]
SMALL = ROOT / "tests" / "robots" / "small_robot.toml"  # a case users tried
ROBOT_FILES = {p.stem: p for p in shipped_robot_files()}
STRICT = ("-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Wshadow", "-Wdouble-promotion",
          "-Wfloat-equal", "-Wconversion", "-Werror")
SENTINEL = 123.0


@dataclass
class Api:
    """One robot's generated C (one precision) through cffi."""

    name: str
    code: RobotCode
    lib: Any
    float32: bool
    positive: tuple[str, ...]

    @property
    def ffi(self) -> Any:
        return self.lib.ffi

    def status(self, name: str) -> int:
        return int(getattr(self.lib.lib, f"{self.code.prefix.upper()}_{name}"))

    def params(self, values: Mapping[str, float]) -> Any:
        return cbuild.params_struct(self.lib, values, f"{self.code.prefix}_params_t",
                                    self.code.controllers.C_FIELD_NAMES)

    def new_prepared(self, fill: int = 0) -> Any:
        prepared = self.ffi.new(f"{self.code.prefix}_model_prepared_t *")
        buf = self.ffi.buffer(prepared)
        buf[:] = bytes([fill]) * len(buf)
        return prepared

    def prepare(self, values: Mapping[str, float], prepared: Any = None) -> tuple[int, Any]:
        prepared = self.new_prepared() if prepared is None else prepared
        fn = getattr(self.lib.lib, f"{self.code.prefix}_model_prepare")
        return int(fn(self.params(values), prepared)), prepared

    def _arrays(self, *values: Any) -> list[Any]:
        real = f"{self.code.prefix}_real_t[]"
        return [self.ffi.new(real, [float(v) for v in np.ravel(x)]) for x in values]

    def _out(self) -> Any:
        return self.ffi.new(f"{self.code.prefix}_real_t[]", [SENTINEL] * self.code.nq)

    def unprepared(self, values: Mapping[str, float], q: Any, qdot: Any, tau: Any
                   ) -> tuple[int, list[float]]:
        out = self._out()
        fn = getattr(self.lib.lib, f"{self.code.prefix}_forward_dynamics")
        status = fn(self.params(values), *self._arrays(q, qdot, tau), out)
        return int(status), list(out)

    def prepared(self, prepared: Any, q: Any, qdot: Any, tau: Any) -> tuple[int, list[float]]:
        out = self._out()
        fn = getattr(self.lib.lib, f"{self.code.prefix}_forward_dynamics_prepared")
        status = fn(prepared, *self._arrays(q, qdot, tau), out)
        return int(status), list(out)


def _c_dir(out: str) -> Path:
    return GENERATED / out / "c" if out else GENERATED / "c"


CASES = [(name, float32) for name in sorted(ROBOT_FILES) for float32 in (False, True)]


@pytest.fixture(scope="module", params=CASES,
                ids=[f"{n}-{'float32' if f else 'double'}" for n, f in CASES])
def api(request: Any) -> Api:
    name, float32 = request.param
    model, _ = load_robot_model(ROBOT_FILES[name])
    code = load_robot_code(model.output_dir)
    lib = cbuild.build(float32, c_dir=_c_dir(model.output_dir), prefix=code.prefix)
    return Api(name, code, lib, float32, tuple(model.positive))


def _states(api: Api, rng: np.random.Generator, p: Mapping[str, float], n: int = 50
            ) -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    code = api.code
    for _ in range(n):
        q = np.r_[rng.uniform(-5, 5, 2), rng.uniform(-np.pi, np.pi, code.nq - 2)]
        eta = rng.uniform(-15, 15, code.nu)
        tau = rng.uniform(-10, 10, code.nu)
        qdot = code.velocities(q, eta, p)
        yield q, qdot, tau


def _scaled(params: Mapping[str, float], rng: np.random.Generator, spread: float
            ) -> dict[str, float]:
    return {k: v * rng.uniform(1 - spread, 1 + spread) for k, v in params.items()}


def test_prepared_equals_unprepared_bit_for_bit(api: Api) -> None:
    """Random parameters (±30 %), 50 states each: equal statuses and equal bits; the
    example's plant (payload parameters 20 % heavier) too. The base parameters of five carts
    drawn one by one can give an indefinite S^T M S at some configurations (train5: 64 of
    the 350 states; the ±30 % box of its base parameters is far wider than its physical
    set); both functions must refuse those alike (BAD_PARAMS), and most states must be a
    compared OK."""
    rng = np.random.default_rng(3)
    parameter_sets = [dict(api.code.params)] + [_scaled(api.code.params, rng, 0.3)
                                               for _ in range(6)]
    compared = refused = 0
    for p in parameter_sets:
        status, prepared = api.prepare(p)
        assert status == api.status("OK"), p
        for q, qdot, tau in _states(api, rng, p):
            want = api.unprepared(p, q, qdot, tau)
            got = api.prepared(prepared, q, qdot, tau)
            assert got == want, (p, q, qdot, tau)
            if want[0] == api.status("OK"):
                compared += 1
            else:
                assert want[0] == api.status("ERR_BAD_PARAMS") and p != api.code.params
                refused += 1
    assert compared + refused == 350 and compared >= 250, (compared, refused)
    if api.name != "train5":  # the chains up to three carts: every draw is physical here
        assert refused == 0


def test_small_robot_numbers_prepare_and_match() -> None:
    """tests/robots/small_robot.toml: the paper's robot with a 2 kg robot's numbers (the
    same generated code, its parameters at run time), double and float32."""
    small = load_robot(SMALL).lumped
    code = load_robot_code("")
    for float32 in (False, True):
        lib = cbuild.build(float32, c_dir=_c_dir(""), prefix=code.prefix)
        api = Api("small_robot", code, lib, float32, ("r", "b"))
        status, prepared = api.prepare(small)
        assert status == api.status("OK")
        rng = np.random.default_rng(5)
        for q, qdot, tau in _states(api, rng, small):
            want = api.unprepared(small, q, qdot, tau)
            assert want[0] == api.status("OK")
            assert api.prepared(prepared, q, qdot, tau) == want


def _bad_parameter_cases(api: Api) -> list[tuple[str, dict[str, float]]]:
    base = dict(api.code.params)
    cases = []
    for key in base:
        for value in (math.nan, math.inf, -math.inf):
            cases.append((f"{key}={value}", {**base, key: value}))
    for key in api.positive:
        for value in (0.0, -abs(base[key])):
            cases.append((f"{key}={value}", {**base, key: value}))
    if api.name == "drishti":  # det(S^T M S) > 0 with both eigenvalues negative
        cases.append(("Iw=-1", {**base, "Iw": -1.0}))
        cases.append(("I=K^2/m", {**base, "I": base["K"] ** 2 / base["m"]}))
    # NaN and a non-positive radius together: the non-finite input is reported first
    cases.append(("NaN first", {**base, api.positive[0]: 0.0, next(iter(base)): math.nan}))
    return cases


def test_prepare_refuses_bad_parameters_like_the_unprepared_function(api: Api) -> None:
    """Each bad parameter: prepare returns the status the unprepared forward dynamics
    returns for it at a valid state, leaves a fresh struct's bytes as they were, and leaves
    a struct prepared before with the old parameters (the next prepared call is unchanged)."""
    rng = np.random.default_rng(11)
    good = dict(api.code.params)
    q, qdot, tau = next(_states(api, rng, good))
    status, old = api.prepare(good)
    assert status == api.status("OK")
    before = api.prepared(old, q, qdot, tau)
    seen = set()
    for label, p in _bad_parameter_cases(api):
        expected, out = api.unprepared(p, q, qdot, tau)
        fresh = api.new_prepared(0xA5)
        status, _ = api.prepare(p, fresh)
        assert status == expected, (label, status, expected)
        seen.add(status)
        if status != api.status("OK"):
            assert out == [SENTINEL] * api.code.nq, label
            assert bytes(api.ffi.buffer(fresh)) == bytes([0xA5]) * len(api.ffi.buffer(fresh))
            assert api.prepare(p, old)[0] == status
            assert api.prepared(old, q, qdot, tau) == before, label
    assert {api.status("ERR_NONFINITE_INPUT"), api.status("ERR_BAD_PARAMS")} <= seen
    nan_first = dict(_bad_parameter_cases(api))["NaN first"]
    assert api.prepare(nan_first)[0] == api.status("ERR_NONFINITE_INPUT")


def test_statuses_agree_on_random_parameters_valid_or_not(api: Api) -> None:
    """Parameters scaled by random factors in [-1.5, 1.5] (many invalid): whenever prepare
    succeeds, prepared and unprepared agree on status and bits; whenever it fails, the
    unprepared function fails with the same status (a state-dependent guard, as the
    trailer's S^T M S of the hitch angle, stays in the prepared call)."""
    rng = np.random.default_rng(17)
    outcomes = set()
    for _ in range(60):
        p = {k: v * rng.uniform(-1.5, 1.5) for k, v in api.code.params.items()}
        status, prepared = api.prepare(p)
        for q, qdot, tau in _states(api, rng, dict(api.code.params), 5):
            want = api.unprepared(p, q, qdot, tau)
            if status == api.status("OK"):
                assert api.prepared(prepared, q, qdot, tau) == want
            else:
                assert want == (status, [SENTINEL] * api.code.nq)
            outcomes.add(want[0])
    assert api.status("ERR_BAD_PARAMS") in outcomes


def test_unprepared_struct_is_refused(api: Api) -> None:
    """A zero-filled, a garbage-filled struct and a prepared one whose magic word was
    overwritten: ERR_NOT_INITIALISED, no output written."""
    rng = np.random.default_rng(19)
    q, qdot, tau = next(_states(api, rng, dict(api.code.params)))
    status, valid = api.prepare(api.code.params)
    assert status == api.status("OK")
    broken = api.new_prepared()
    api.ffi.buffer(broken)[:] = api.ffi.buffer(valid)[:]
    broken.magic = valid.magic + 1
    for label, prepared in (("zeros", api.new_prepared(0)), ("0x5a", api.new_prepared(0x5A)),
                            ("magic overwritten", broken)):
        got = api.prepared(prepared, q, qdot, tau)
        assert got == (api.status("ERR_NOT_INITIALISED"), [SENTINEL] * api.code.nq), label
    assert api.prepared(valid, q, qdot, tau)[0] == api.status("OK")


def test_prepared_call_checks_state_inputs_and_results(api: Api) -> None:
    """NaN or an infinity in any entry of q, qdot, tau: the status of the unprepared call
    (ERR_NONFINITE_INPUT for an entry either reads, OK and the same result for one it
    ignores); results that overflow: ERR_NONFINITE_OUTPUT; no output written on error."""
    rng = np.random.default_rng(23)
    p = dict(api.code.params)
    q, qdot, tau = next(_states(api, rng, p))
    _, prepared = api.prepare(p)
    statuses = set()
    for which in range(3):
        for index in range(len((q, qdot, tau)[which])):
            for value in (math.nan, math.inf, -math.inf):
                args = [np.array(a, dtype=float) for a in (q, qdot, tau)]
                args[which][index] = value
                want = api.unprepared(p, *args)
                got = api.prepared(prepared, *args)
                assert got == want, (which, index, value)
                if got[0] != api.status("OK"):
                    assert got[1] == [SENTINEL] * api.code.nq
                statuses.add(got[0])
    assert api.status("ERR_NONFINITE_INPUT") in statuses
    huge = 1e30 if api.float32 else 1e300
    big = [np.array(a, dtype=float) for a in (q, qdot, tau)]
    big[1] = big[1] * huge
    big[2] = big[2] * huge
    want = api.unprepared(p, *big)
    assert want == (api.status("ERR_NONFINITE_OUTPUT"), [SENTINEL] * api.code.nq)
    assert api.prepared(prepared, *big) == want


def test_header_declares_the_api(api: Api) -> None:
    pre = api.code.prefix
    header = (_c_dir(load_robot_model(ROBOT_FILES[api.name])[0].output_dir)
              / f"{pre}_model.h").read_text()
    assert f"{pre}_status_t {pre}_model_prepare(const {pre}_params_t *p," in header
    assert f"{pre}_status_t {pre}_forward_dynamics_prepared(const {pre}_model_prepared_t *" \
        in header
    assert f"#define {pre.upper()}_MODEL_PREPARED_MAGIC 0x" in header


def test_example_prepares_once_and_steps_the_plant_with_it() -> None:
    for out in ("", "trailer"):
        example = (_c_dir(out) / "example_main.c").read_text()
        pre = "wmr" if not out else "trailer"
        assert example.count(f"{pre}_model_prepare(&plant, &plant_model)") == 1
        assert f"{pre}_forward_dynamics_prepared(&plant_model, q, qdot, tau, qddot)" in example
        assert f"{pre}_forward_dynamics(" not in example


# ------------------------------------------------------------------ the split on a toy
a, c = sp.symbols("a c", real=True)
x, t = sp.symbols("x t", real=True)
TOY_STATUS = (StatusCode("WMR_OK", 0, "ok"), StatusCode("WMR_ERR_NONFINITE_INPUT", -2, ""),
              StatusCode("WMR_ERR_BAD_PARAMS", -3, ""),
              StatusCode("WMR_ERR_NONFINITE_OUTPUT", -4, ""),
              StatusCode("WMR_ERR_NOT_INITIALISED", -15, ""))


def _toy_spec(variant: str = "state guard") -> Any:
    """A toy with a parameter guard and sin(t) (a library call: t is checked first); by
    ``variant``: a guard on the state ("state guard"), none ("lazy"): x reaches the results
    through +, -, * only, so it is checked only when a guard or the results fail; a
    division by x ("division"): x is checked right away."""
    from codegen.spec import Argument, Field, FunctionSpec, Guard

    params = Argument("p", "params", fields=(Field("a", (a,)), Field("c", (c,))))
    state = Argument("s", "array", (2, 1), (x, t))
    last = 1 / (x**2 + 1) if variant == "division" else (c + 2) * (x - 1) / a
    outputs = (Argument("y", "array", (3, 1), exprs=(
        a * c * x + a * c + sp.sin(t) * c / a,
        x**2 * c / (a**2 + 1) + sp.cos(t) * x + sp.sin(t) * t,
        last,
    )),)
    guards = (Guard("WMR_ERR_BAD_PARAMS", a, "a > 0"),)
    if variant == "state guard":
        guards += (Guard("WMR_ERR_BAD_PARAMS", c - x, "x < c"),)
    return FunctionSpec("toy", "a toy", (params, state), outputs, returns_status=True,
                        guards=guards, nonfinite_input="WMR_ERR_NONFINITE_INPUT",
                        nonfinite_output="WMR_ERR_NONFINITE_OUTPUT", prepared=True)


def test_split_of_a_toy_function() -> None:
    spec = _toy_spec()
    form = function_ir(spec).prepared
    assert form is not None
    assert [k for k, _ in form.param_guards] == [0] and [k for k, _ in form.state_guards] == [1]
    assert form.used_params() == {a, c} and form.used_state() == {x, t}
    params = {a, c}
    for _, e in form.param_temps:
        assert e.free_symbols <= params | {s for s, _ in form.param_temps}
    per_call = [e for _, e in form.state_temps] + [e for o in form.outputs for e in o]
    # nothing per call divides by a parameter: every division was prepared
    assert not any(isinstance(p, sp.Pow) and p.exp.is_negative
                   for e in per_call for p in sp.preorder_traversal(e))
    with pytest.raises(ValueError, match="must return a status"):
        from dataclasses import replace

        function_ir(replace(spec, returns_status=False))


@pytest.mark.parametrize("variant", ["state guard", "lazy", "division"])
def test_toy_renders_and_agrees_bit_for_bit(tmp_path: Path, variant: str) -> None:
    """The toy's C in both precisions: prepared = unprepared (status and bits), with the
    x check where the variant says; no division per call (but the one by x)."""
    spec = _toy_spec(variant)
    config = CConfig(status_codes=TOY_STATUS)
    files = c_backend.render([spec], "wmr_toy", config)
    files.update(c_backend.render_types([spec], config))
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    assert "WMR_ERR_NOT_INITIALISED" in files["wmr_toy.c"]
    prepared_c = files["wmr_toy.c"].split("wmr_toy_prepared(", 1)[1].split("\n}\n", 1)[0]
    code = re.sub(r"/\*.*?\*/", "", prepared_c, flags=re.S)
    assert code.count("/") == (1 if variant == "division" else 0), code
    # x is checked when a later check fails only if nothing but +, -, * leads it to the
    # results; else right after it is loaded
    with_results = "an input not checked yet" in prepared_c
    assert with_results == (variant != "division")
    libs = {}
    for float32 in (False, True):
        flags = [*STRICT, "-O2", *(["-DWMR_FLOAT32"] if float32 else [])]
        libs[float32] = cbuild.build_library(
            [tmp_path / "wmr_toy.c"], tmp_path / f"libtoy{int(float32)}.so",
            cbuild.declarations(float32, ("wmr_types.h", "wmr_toy.h"), c_dir=tmp_path),
            float32=float32, flags=flags, include_dirs=[tmp_path])
    rng = np.random.default_rng(29)
    seen = set()
    for float32, lib in libs.items():
        ffi, c_lib = lib.ffi, lib.lib
        for _ in range(400):
            pa, pc = rng.uniform(-1, 3), rng.uniform(-2, 2)
            s = [rng.uniform(-3, 3), rng.uniform(-4, 4)]
            if rng.uniform() < 0.15:
                s[rng.integers(2)] = [math.nan, math.inf, -math.inf][rng.integers(3)]
            elif rng.uniform() < 0.1:  # x*x overflows
                s[0] = (1e30 if float32 else 1e200) * (1 if rng.uniform() < 0.5 else -1)
            p = ffi.new("wmr_params_t *", {"a": pa, "c": pc})
            prepared = ffi.new("wmr_toy_prepared_t *")
            out1, out2 = ffi.new("wmr_real_t[3]", [7.0] * 3), ffi.new("wmr_real_t[3]", [7.0] * 3)
            want = c_lib.wmr_toy(p, ffi.new("wmr_real_t[]", s), out1)
            status = c_lib.wmr_toy_prepare(p, prepared)
            if status == 0:
                got = c_lib.wmr_toy_prepared(prepared, ffi.new("wmr_real_t[]", s), out2)
                assert (got, list(out2)) == (want, list(out1))
            else:  # the unprepared function reports a NaN state before bad parameters
                finite = all(math.isfinite(v) for v in s)
                assert want == (status if finite else -2), (want, status, s)
                assert list(out1) == [7.0] * 3
            seen.add(int(want))
    # OK, a non-finite state, a > 0 (or x < c) violated, an overflow
    assert seen == {0, -2, -3, -4}


def test_collect_factors_shares_a_factor_per_sum() -> None:
    from codegen.prepare import collect_factors

    y, z = sp.symbols("y z", real=True)
    assert collect_factors(a * x + a * y + z) == a * (x + y) + z
    # the symbol shared by most terms first (ties by name), then the rest
    got = collect_factors(a * x + a * y - c * x + c * y)
    assert got == a * (x + y) + c * (y - x)
    assert sp.expand(got - (a * x + a * y - c * x + c * y)) == 0
    assert collect_factors(sp.sin(a * x + a * t)) == sp.sin(a * (x + t))
    assert collect_factors(x + y) == x + y  # nothing shared: unchanged
