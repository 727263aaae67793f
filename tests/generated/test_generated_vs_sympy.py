"""The generated code computes the SymPy model it was printed from.

Every FunctionSpec of ``model_specs()`` and ``law_specs()`` at N_SAMPLES random inputs:
the SymPy expressions (lambdified once per spec, NumPy, double) against the generated
Python function, the C compiled in double and in float (-DWMR_FLOAT32) through cffi, and
the CasADi function loaded from generated/casadi. Error measure, per output argument and
sample (norm-wise relative with an absolute floor):
    ||got - ref||_2 / max(||ref||_2, FLOOR),  FLOOR = 1e-6,
bounded by RTOL_DOUBLE = 1e-12 (Python, C double, CasADi) and RTOL_FLOAT = 1e-4 (C float;
the float build gets float-representable inputs and the reference is evaluated at exactly
those inputs, so only the float arithmetic is measured).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from functools import cache
from typing import Any

import casadi as ca
import numpy as np
import pytest
import sympy as sp
from generated_code_support import DRISHTI, FLOOR, GENERATED, STATUS, CBuild, _c_params

from codegen.layout import argument_size
from codegen.robot_functions import law_specs, model_specs
from codegen.spec import Argument, FunctionSpec
from modeling.robots.drishti.model import PARAM_KEYS, robot_model
from runtime.bindings.generated import controllers as pyctl
from runtime.bindings.generated import wmr_model as py_model

N_SAMPLES = 100
RTOL_DOUBLE = 1e-12
RTOL_FLOAT = 1e-4
MODEL_SPECS = model_specs(robot_model())
SPECS: tuple[FunctionSpec, ...] = (*MODEL_SPECS, *law_specs(robot_model()))
SPEC_IDS = [s.name for s in SPECS]
# Max deviation per (backend, spec), printed at the end of the session.
DEVIATIONS: dict[tuple[str, str], float] = {}


@pytest.fixture(scope="session", autouse=True)
def _deviation_summary(request: pytest.FixtureRequest) -> Iterator[None]:
    yield
    if not DEVIATIONS:
        return
    reporter = request.config.pluginmanager.get_plugin("terminalreporter")
    capture = request.config.pluginmanager.get_plugin("capturemanager")
    if reporter is None or capture is None:
        return
    with capture.global_and_fixture_disabled():
        reporter.write_line("")
        reporter.write_line("generated code vs SymPy, max norm-wise relative deviation:")
        for backend in sorted({b for b, _ in DEVIATIONS}):
            items = {s: e for (b, s), e in DEVIATIONS.items() if b == backend}
            worst = max(items, key=items.__getitem__)
            reporter.write_line(f"  {backend:14s} {items[worst]:.3g}  (worst: {worst})")


def _uniform(rng: np.random.Generator, lo: float, hi: float, n: int, size: int) -> np.ndarray:
    return rng.uniform(lo, hi, (n, size))


def _sample_argument(arg: Argument, rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, size) values for one input argument, in sensible physical ranges."""
    size = argument_size(arg)
    name = arg.name
    if arg.kind == "params":  # within +-30 % of Drishti
        base = np.array([DRISHTI[f.name] for f in arg.fields])
        return base * _uniform(rng, 0.7, 1.3, n, size)
    if name in ("q", "q_prev"):  # positions [m], then angles [rad]
        out = _uniform(rng, -np.pi, np.pi, n, size)
        out[:, :2] = _uniform(rng, -10.0, 10.0, n, 2)
        return out
    if name in ("qdot", "wheel_rates", "qdot_now", "qdot_then"):
        return _uniform(rng, -5.0, 5.0, n, size)
    if name in ("tau", "u_prev", "H1hat", "omega"):
        return _uniform(rng, -20.0, 20.0, n, size)
    if name in ("span", "minv_norm", "gains"):
        lo, hi = {"span": (1e-3, 2e-2), "minv_norm": (0.1, 30.0), "gains": (0.5, 10.0)}[name]
        return _uniform(rng, lo, hi, n, size)
    if name == "w":  # normalised weights, zero beyond a random active window
        w = _uniform(rng, 0.1, 1.0, n, size)
        active = rng.integers(1, size + 1, n)
        w[np.arange(size)[None, :] >= active[:, None]] = 0.0
        return w / w.sum(axis=1, keepdims=True)
    if name == "e":
        return _uniform(rng, -0.5, 0.5, n, size)
    if name == "edot":
        return _uniform(rng, -1.0, 1.0, n, size)
    if name == "qddot_des":
        return _uniform(rng, -2.0, 2.0, n, size)
    if name in ("k1", "k2"):
        return _uniform(rng, 1.0, 10.0, n, size)
    if name in ("p12", "p22"):
        return _uniform(rng, 0.05, 2.0, n, size)
    if name == "gain":
        return _uniform(rng, 0.0, 10.0, n, size)
    if name in ("mu", "loads", "shares"):  # a floor that holds: traction_check returns OK
        lo, hi = {"mu": (0.5, 1.0), "loads": (3000.0, 6000.0), "shares": (0.0, 1.0)}[name]
        return _uniform(rng, lo, hi, n, size)
    if name == "eps":  # both sides of max(||s||, eps) occur
        return _uniform(rng, 0.01, 1.0, n, size)
    if name == "bounds":  # alpha in [0, 0.9), phi
        return np.column_stack([rng.uniform(0.0, 0.9, n), rng.uniform(0.0, 5.0, n)])
    if name == "adapt":  # gamma, h
        return np.column_stack([rng.uniform(0.0, 5.0, n), rng.uniform(1e-3, 2e-2, n)])
    # An argument this file does not know yet: positive symbols get positive values.
    if all(s.is_positive for s in arg.all_symbols()):
        return _uniform(rng, 0.1, 10.0, n, size)
    return _uniform(rng, -2.0, 2.0, n, size)


@cache
def _inputs(spec_name: str) -> list[np.ndarray]:
    spec = _spec(spec_name)
    rng = np.random.default_rng(sum(map(ord, spec_name)))
    return [_sample_argument(a, rng, N_SAMPLES) for a in spec.inputs]


def _spec(name: str) -> FunctionSpec:
    return next(s for s in SPECS if s.name == name)


def _as_float32(values: list[np.ndarray]) -> list[np.ndarray]:
    return [v.astype(np.float32).astype(np.float64) for v in values]


@cache
def _lambdified(spec_name: str) -> Callable[..., Any]:
    spec = _spec(spec_name)
    # A spec's intermediate quantities (its definitions) written out: the reference is the
    # closed form, whatever order of evaluation the generated code takes.
    subs: dict[sp.Basic, sp.Expr] = {}
    for symbol, definition in spec.definitions:
        subs[symbol] = sp.sympify(definition).xreplace(subs)
    exprs = [sp.sympify(e).xreplace(subs) for a in spec.outputs for e in a.exprs]
    return sp.lambdify(spec.input_symbols(), exprs, "numpy", cse=True)


def _reference(spec: FunctionSpec, values: list[np.ndarray]) -> np.ndarray:
    """(n, outputs) from the SymPy expressions, vectorised over the samples."""
    columns = np.concatenate(values, axis=1).T
    n = columns.shape[1]
    out = _lambdified(spec.name)(*columns)
    return np.column_stack([np.broadcast_to(np.asarray(v, dtype=np.float64), (n,)) for v in out])


# Outputs measured as one vector: the wheel contact forces are all forces in newtons, and
# an axle's lateral force alone crosses zero (a sample has -0.0018 N beside 40 N
# longitudinal), where a relative measure of that entry alone would measure nothing real.
ONE_BLOCK = {"wheel_contact_forces"}


def _blocks(spec: FunctionSpec) -> list[slice]:
    if spec.name in ONE_BLOCK:
        return [slice(None)]
    blocks, start = [], 0
    for a in spec.outputs:
        blocks.append(slice(start, start + argument_size(a)))
        start += argument_size(a)
    return blocks


def _normwise(got: np.ndarray, ref: np.ndarray, blocks: Sequence[slice] | None = None) -> float:
    """max over samples and output blocks of ||got - ref|| / max(||ref||, FLOOR)."""
    got, ref = np.atleast_2d(got), np.atleast_2d(ref)
    worst = 0.0
    for sl in blocks or [slice(None)]:
        num = np.linalg.norm(got[:, sl] - ref[:, sl], axis=1)
        den = np.maximum(np.linalg.norm(ref[:, sl], axis=1), FLOOR)
        worst = max(worst, float(np.max(num / den)))
    return worst


def _record(backend: str, spec: FunctionSpec, err: float, rtol: float) -> None:
    DEVIATIONS[(backend, spec.name)] = err
    assert err <= rtol, f"{backend} {spec.name}: deviation {err:.3g} > {rtol:g}"


def _call_c(build: CBuild, spec: FunctionSpec, row: list[np.ndarray]) -> np.ndarray:
    ffi = build.ffi
    args: list[Any] = []
    for arg, value in zip(spec.inputs, row, strict=True):
        if arg.kind == "params":
            args.append(_c_params(ffi, value.tolist()))
        else:
            assert arg.kind == "array", arg
            args.append(ffi.new(f"wmr_real_t[{argument_size(arg)}]", value.tolist()))
    outs = [ffi.new(f"wmr_real_t[{argument_size(a)}]") for a in spec.outputs]
    status = getattr(build.lib, f"wmr_{spec.name}")(*args, *outs)
    if spec.returns_status:
        assert status == STATUS["WMR_OK"], (spec.name, status)
    return np.concatenate([np.array(list(o), dtype=np.float64) for o in outs])


def _call_python(spec: FunctionSpec, row: list[np.ndarray]) -> np.ndarray:
    module = py_model if spec in MODEL_SPECS else pyctl.laws
    function = getattr(module, spec.name)
    ordered: list[Any] = []
    params: list[Any] = []
    for arg, value in zip(spec.inputs, row, strict=True):
        if arg.kind == "params":
            params.append(dict(zip(PARAM_KEYS, value.tolist(), strict=True)))
        else:
            ordered.append(value.reshape(arg.shape))
    result = function(*ordered, *params)
    results = result if len(spec.outputs) > 1 else (result,)
    for arg, value in zip(spec.outputs, results, strict=True):
        assert isinstance(value, np.ndarray) and value.size == argument_size(arg), arg.name
    return np.concatenate([np.asarray(v, dtype=np.float64).reshape(-1) for v in results])


@pytest.mark.parametrize("spec", SPECS, ids=SPEC_IDS)
def test_python_module_matches_sympy(spec: FunctionSpec) -> None:
    values = _inputs(spec.name)
    ref = _reference(spec, values)
    got = np.array([_call_python(spec, [v[i] for v in values]) for i in range(N_SAMPLES)])
    _record("python", spec, _normwise(got, ref, _blocks(spec)), RTOL_DOUBLE)


@pytest.mark.parametrize("precision", ["double", "float"])
@pytest.mark.parametrize("spec", SPECS, ids=SPEC_IDS)
def test_c_matches_sympy(c_builds: dict[str, CBuild], spec: FunctionSpec, precision: str) -> None:
    build = c_builds[precision]
    values = _inputs(spec.name)
    if build.float32:
        values = _as_float32(values)
    ref = _reference(spec, values)
    got = np.array([_call_c(build, spec, [v[i] for v in values]) for i in range(N_SAMPLES)])
    rtol = RTOL_FLOAT if build.float32 else RTOL_DOUBLE
    _record(f"c-{precision}", spec, _normwise(got, ref, _blocks(spec)), rtol)


@pytest.mark.parametrize("spec", SPECS, ids=SPEC_IDS)
def test_casadi_matches_sympy(spec: FunctionSpec) -> None:
    function = ca.Function.load(str(GENERATED / "casadi" / f"{spec.name}.casadi"))
    assert function.name_in() == [a.name for a in spec.inputs]
    assert function.name_out() == [a.name for a in spec.outputs]
    assert [function.size1_in(i) for i in range(function.n_in())] == [
        argument_size(a) for a in spec.inputs
    ]
    values = _inputs(spec.name)
    ref = _reference(spec, values)
    result = function.map(N_SAMPLES)(*[ca.DM(v.T) for v in values])
    results = result if isinstance(result, tuple) else (result,)
    got = np.concatenate([np.asarray(r, dtype=np.float64) for r in results], axis=0).T
    _record("casadi", spec, _normwise(got, ref, _blocks(spec)), RTOL_DOUBLE)
