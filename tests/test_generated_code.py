"""The checked-in generated code (generated/c, generated/python, generated/casadi) against
the SymPy model it was printed from, against each other, and under bad input.

1. Every FunctionSpec of ``model_specs()`` and ``law_specs()`` at N_SAMPLES random inputs:
   the SymPy expressions (lambdified once per spec, NumPy, double) against the generated
   Python function, the C compiled in double and in float (-DWMR_FLOAT32) through cffi,
   and the CasADi function loaded from generated/casadi. Error measure, per output
   argument and sample (norm-wise relative with an absolute floor):
       ||got - ref||_2 / max(||ref||_2, FLOOR),  FLOOR = 1e-6,
   bounded by RTOL_DOUBLE = 1e-12 (Python, C double, CasADi) and RTOL_FLOAT = 1e-4 (C
   float; the float build gets float-representable inputs and the reference is evaluated
   at exactly those inputs, so only the float arithmetic is measured).
2. All generated .c files compile with the strict flags in both precisions; example_main
   runs and its final position error is < 0.05 m; the float objects link no double libm
   function.
3. The four controllers, both formulations: C step == Python class step (tau and state) on
   smooth multi-step sequences, and both == the SymPy laws of modeling.controllers with
   the step semantics re-implemented here.
4. Bad input: exact status codes, state and outputs unchanged, the next valid step equal to
   that of a twin that never saw the bad input; saturation; forward-dynamics guards.
5. ``python -m codegen``: byte-identical output under two hash seeds, ``--check`` on the
   repository, ``--check`` on an edited copy, ``--robot`` with a bad file.

The C is compiled from a snapshot of generated/c into pytest tmp directories.
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
import shutil
import subprocess
import sys
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

import casadi as ca
import cffi
import numpy as np
import pytest
import sympy as sp

from codegen.controller_api import CONTROLLERS, STATUS_CODES, ControllerInfo
from codegen.generate import C_CONFIG
from codegen.layout import argument_size
from codegen.spec import Argument, FunctionSpec
from codegen.wmr_functions import MAX_WINDOW, PARAM_FIELDS, PARAM_KEYS, law_specs, model_specs
from modeling import controllers as ctl
from modeling import wmr
from modeling.robot_file import load_robot
from runtime.generated_modules import controllers as pyctl
from runtime.generated_modules import wmr_model as py_model

ROOT = Path(__file__).resolve().parent.parent
GENERATED = ROOT / "generated"
N_SAMPLES = 100
FLOOR = 1e-6
RTOL_DOUBLE = 1e-12
RTOL_FLOAT = 1e-4
RTOL_CONTROLLER = 1e-10  # C step vs Python step
RTOL_SYMPY_LAW = 1e-9  # steps vs the SymPy laws evaluated directly (other rounding)
C_FLAGS = [
    "-std=c99",
    "-Wall",
    "-Wextra",
    "-Wpedantic",
    "-Wshadow",
    "-Wdouble-promotion",
    "-Wconversion",
    "-Werror",
]
STATUS = {s.name: s.value for s in STATUS_CODES}
DRISHTI = load_robot().lumped
PARAM_SYMBOLS = tuple(sym for _, sym, _ in PARAM_FIELDS)
SPECS: tuple[FunctionSpec, ...] = (*model_specs(), *law_specs())
SPEC_IDS = [s.name for s in SPECS]
INFO = {c.name: c for c in CONTROLLERS}
PY_CLASSES = {"tdc": pyctl.TDC, "tdroc": pyctl.TDROC, "roc": pyctl.ROC, "asmc": pyctl.ASMC}
FORMULATIONS = {"paper": 0, "minimal": 1}
DOUBLE_MATH = {
    "sin", "cos", "sincos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh",
    "exp", "log", "sqrt", "pow", "fabs", "fmax", "fmin",
}  # fmt: skip

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


# ============================================================ random inputs per argument
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


# ======================================================================== the reference
@cache
def _lambdified(spec_name: str) -> Callable[..., Any]:
    spec = _spec(spec_name)
    exprs = [e for a in spec.outputs for e in a.exprs]
    return sp.lambdify(spec.input_symbols(), exprs, "numpy", cse=True)


def _reference(spec: FunctionSpec, values: list[np.ndarray]) -> np.ndarray:
    """(n, outputs) from the SymPy expressions, vectorised over the samples."""
    columns = np.concatenate(values, axis=1).T
    n = columns.shape[1]
    out = _lambdified(spec.name)(*columns)
    return np.column_stack([np.broadcast_to(np.asarray(v, dtype=np.float64), (n,)) for v in out])


def _blocks(spec: FunctionSpec) -> list[slice]:
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


# ============================================================================ C builds
@dataclass
class CBuild:
    ffi: Any
    lib: Any
    float32: bool
    objects: dict[str, Path]
    example: Path


def _gcc() -> str:
    gcc = shutil.which("gcc")
    if gcc is None:
        pytest.skip("gcc not available")
    return gcc


def _run_all(cmds: list[list[str]]) -> None:
    """Run the commands two at a time (2 cores); every one must succeed silently."""
    for i in range(0, len(cmds), 2):
        procs = [
            (c, subprocess.Popen(c, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True))
            for c in cmds[i : i + 2]
        ]
        for cmd, proc in procs:
            out, err = proc.communicate()
            assert proc.returncode == 0, f"{' '.join(cmd)}\n{out}{err}"
            assert not err.strip(), f"{' '.join(cmd)} printed:\n{err}"


def _cdef(gcc: str, src: Path, float32: bool) -> str:
    """The generated headers preprocessed (empty <math.h>): typedefs, enums, prototypes."""
    fake = src / "fake_include"
    fake.mkdir(exist_ok=True)
    (fake / "math.h").write_text("")
    others = ("wmr_types.h", "wmr_robot.h")
    headers = ["wmr_types.h", *sorted(p.name for p in src.glob("wmr_*.h") if p.name not in others)]
    all_h = src / f"all_{'float' if float32 else 'double'}.h"
    all_h.write_text("".join(f'#include "{h}"\n' for h in headers))
    cmd = [gcc, "-E", "-P", "-nostdinc", f"-I{fake}", f"-I{src}", str(all_h)]
    if float32:
        cmd.insert(2, "-DWMR_FLOAT32")
    return subprocess.run(cmd, check=True, capture_output=True, text=True).stdout


@pytest.fixture(scope="session")
def c_builds(tmp_path_factory: pytest.TempPathFactory) -> dict[str, CBuild]:
    """Every generated .c compiled with the strict flags in both precisions (objects, a
    shared library of the wmr_*.c for cffi, and the example executable)."""
    gcc = _gcc()
    root = tmp_path_factory.mktemp("generated_c")
    src = root / "src"
    shutil.copytree(GENERATED / "c", src)  # a snapshot: concurrent regeneration is harmless
    sources = sorted(src.glob("*.c"))
    assert {p.name for p in sources} >= {"example_main.c", "wmr_model.c", "wmr_laws.c"}
    builds: dict[str, CBuild] = {}
    cmds: list[list[str]] = []
    objects: dict[str, dict[str, Path]] = {}
    for precision in ("double", "float"):
        out = root / precision
        out.mkdir()
        defines = ["-DWMR_FLOAT32"] if precision == "float" else []
        objects[precision] = {p.name: out / f"{p.stem}.o" for p in sources}
        cmds += [
            [gcc, *C_FLAGS, "-O2", "-fPIC", *defines, f"-I{src}", "-c", str(p), "-o", str(o)]
            for p, o in zip(sources, objects[precision].values(), strict=True)
        ]
    _run_all(cmds)
    links = []
    for precision in ("double", "float"):
        objs = objects[precision]
        lib_objs = [str(o) for n, o in objs.items() if n != "example_main.c"]
        so = root / precision / "libwmr.so"
        exe = root / precision / "example_main"
        links.append([gcc, "-shared", *lib_objs, "-lm", "-o", str(so)])
        links.append([gcc, str(objs["example_main.c"]), *lib_objs, "-lm", "-o", str(exe)])
    _run_all(links)
    for precision in ("double", "float"):
        float32 = precision == "float"
        ffi = cffi.FFI()
        ffi.cdef(_cdef(gcc, src, float32))
        lib = ffi.dlopen(str(root / precision / "libwmr.so"))
        builds[precision] = CBuild(
            ffi, lib, float32, objects[precision], root / precision / "example_main"
        )
    return builds


def _c_params(ffi: Any, values: Sequence[float] | dict[str, float]) -> Any:
    obj = ffi.new("wmr_params_t *")
    items = values.items() if isinstance(values, dict) else zip(PARAM_KEYS, values, strict=True)
    for key, value in items:
        setattr(obj, C_CONFIG.c_field(key), float(value))
    return obj


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
    module = py_model if spec in model_specs() else pyctl.laws
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


# ===================================================================== 1. vs the SymPy
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


# ================================================================ 2. builds and example
@pytest.mark.parametrize("precision", ["double", "float"])
def test_example_main_runs_and_tracks(c_builds: dict[str, CBuild], precision: str) -> None:
    """The strict-flag build succeeded (fixture); the example loop ends on the circle."""
    build = c_builds[precision]
    proc = subprocess.run([str(build.example)], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    errors = [float(x) for x in re.findall(r"position error = ([0-9.eE+-]+) m", proc.stdout)]
    assert len(errors) >= 5, proc.stdout
    assert errors[-1] < 0.05, proc.stdout
    assert all(math.isfinite(e) for e in errors)


def _undefined_symbols(obj: Path) -> set[str]:
    nm = shutil.which("nm")
    if nm is None:
        pytest.skip("nm not available")
    out = subprocess.run([nm, "-u", str(obj)], capture_output=True, text=True, check=True).stdout
    return {line.split()[-1] for line in out.splitlines() if line.strip()}


def test_float_build_calls_no_double_math(c_builds: dict[str, CBuild]) -> None:
    float_syms: set[str] = set()
    for name, obj in c_builds["float"].objects.items():
        undefined = _undefined_symbols(obj)
        assert not undefined & DOUBLE_MATH, (name, sorted(undefined & DOUBLE_MATH))
        float_syms |= undefined
    double_syms = set().union(*map(_undefined_symbols, c_builds["double"].objects.values()))
    # Not vacuous: the same code calls the double functions in the double build.
    assert double_syms & {"sin", "cos", "sincos"} and double_syms & {"sqrt"}, double_syms
    assert float_syms & {"sinf", "cosf", "sincosf"} and "sqrtf" in float_syms, float_syms


# ========================================================================= 3. controllers
def _config(name: str, formulation: int, **changes: Any) -> Any:
    config = pyctl.Config(
        nominal=dict(DRISHTI),
        formulation=formulation,
        k1=[4.0, 5.0, 6.0, 7.0, 8.0],
        k2=[3.0, 3.5, 4.0, 4.5, 5.0],
        q_pos=1.5,
        q_vel=0.8,
        h=0.01,
        tau_max=200.0,
        eps=0.05,
        n=4,
        a=0.8,
        alpha=0.3,
        phi=2.0,
        gamma=2.0,
        gain0=0.5 if name == "asmc" else 0.0,
    )
    return dataclasses.replace(config, **changes)


def _c_config(build: CBuild, name: str, config: Any) -> Any:
    """``wmr_<name>_config_t`` with every field taken from the Python Config."""
    ffi = build.ffi
    ctype = f"wmr_{name}_config_t"
    obj = ffi.new(f"{ctype} *")
    for field, ftype in ffi.typeof(ctype).fields:
        value = getattr(config, field)
        if field == "nominal":
            obj.nominal = _c_params(ffi, dict(value))[0]
        elif ftype.type.kind == "array":
            setattr(obj, field, [float(x) for x in value])
        elif ftype.type.cname in ("int", "long"):
            setattr(obj, field, int(value))
        else:
            setattr(obj, field, float(value))
    return obj


def _c_value(ffi: Any, value: Any) -> Any:
    if not isinstance(value, ffi.CData):
        return value
    t = ffi.typeof(value)
    if t.kind == "array":
        return np.array([_c_value(ffi, v) for v in value])
    if t.kind == "struct":
        return {f: _c_value(ffi, getattr(value, f)) for f, _ in t.fields}
    raise TypeError(t)


class CController:
    """``wmr_<name>_init`` / ``_step`` through cffi with a caller-owned state."""

    def __init__(self, build: CBuild, name: str, config: Any) -> None:
        self.build, self.name = build, name
        self.config = _c_config(build, name, config)
        self.state = build.ffi.new(f"wmr_{name}_state_t *")
        status = self.init()
        assert status == STATUS["WMR_OK"], status

    def init(self, config: Any = None) -> int:
        init = getattr(self.build.lib, f"wmr_{self.name}_init")
        return int(init(self.state, self.config if config is None else config))

    def step(self, *inputs: np.ndarray, config: Any = None, tau: Any = None) -> tuple[int, Any]:
        ffi = self.build.ffi
        tau = ffi.new("wmr_real_t[2]") if tau is None else tau
        arrays = [ffi.new("wmr_real_t[5]", [float(x) for x in v]) for v in inputs]
        step = getattr(self.build.lib, f"wmr_{self.name}_step")
        status = step(self.state, self.config if config is None else config, *arrays, tau)
        return int(status), tau

    def fields(self) -> dict[str, Any]:
        return _c_value(self.build.ffi, self.state[0])

    def raw(self) -> bytes:
        return bytes(self.build.ffi.buffer(self.state))


def _smooth_sequence(seed: int, steps: int, h: float) -> list[tuple[np.ndarray, ...]]:
    """(q, qdot, q_des, qdot_des, qddot_des) per step: sums of sinusoids on a drift, the
    reference a smooth offset of the measured motion (a closed loop that tracks)."""
    rng = np.random.default_rng(seed)
    t = np.arange(steps) * h

    def signal(amplitude: np.ndarray, drift: np.ndarray) -> tuple[np.ndarray, ...]:
        a = rng.uniform(0.3, 1.0, (5, 3)) * amplitude[:, None]
        w = 2 * np.pi * rng.uniform(0.1, 0.6, (5, 3))
        ph = rng.uniform(0.0, 2 * np.pi, (5, 3))
        arg = w[None] * t[:, None, None] + ph[None]
        q = drift[None] * t[:, None] + (a[None] * np.sin(arg)).sum(-1)
        qd = drift[None] + (a[None] * w[None] * np.cos(arg)).sum(-1)
        qdd = -(a[None] * w[None] ** 2 * np.sin(arg)).sum(-1)
        return q, qd, qdd

    drift = np.array([0.3, 0.1, 0.05, 2.0, 1.5])
    q, qd, _ = signal(np.array([0.5, 0.5, 0.3, 0.5, 0.5]), drift)
    e, ed, edd = signal(np.array([0.05, 0.05, 0.05, 0.1, 0.1]), np.zeros(5))
    return [(q[k], qd[k], q[k] + e[k], qd[k] + ed[k], edd[k]) for k in range(steps)]


def _close(a: Any, b: Any, rtol: float) -> bool:
    a, b = np.atleast_1d(np.asarray(a, dtype=np.float64)), np.atleast_1d(np.asarray(b, dtype=float))
    if a.shape != b.shape:
        return False
    return bool(np.linalg.norm(a - b) <= rtol * max(float(np.linalg.norm(b)), FLOOR))


def _compare_states(
    c_fields: dict[str, Any], py_state: dict[str, Any], info: ControllerInfo
) -> None:
    required = {"steps", "gain", "s_norm", "H1hat", "tau"} | ({"omega"} if info.window else set())
    common = {k for k in c_fields.keys() & py_state.keys() if not isinstance(c_fields[k], dict)}
    assert required <= common, sorted(required - common)
    for key in sorted(common):
        assert _close(c_fields[key], py_state[key], RTOL_CONTROLLER), (
            f"{key}: C {c_fields[key]} vs Python {py_state[key]}"
        )


CONTROLLER_CASES = [(c, f) for c in INFO for f in FORMULATIONS]
CONTROLLER_IDS = [f"{c}-{f}" for c, f in CONTROLLER_CASES]


@pytest.mark.parametrize(("name", "form"), CONTROLLER_CASES, ids=CONTROLLER_IDS)
def test_controller_c_equals_python(c_builds: dict[str, CBuild], name: str, form: str) -> None:
    info = INFO[name]
    estimators = (pyctl.ACCEL_BACKWARD, pyctl.ACCEL_CENTRAL) if info.tde else (0,)
    for estimator in estimators:
        config = _config(name, FORMULATIONS[form], accel_estimator=estimator)
        c_ctl = CController(c_builds["double"], name, config)
        py_ctl = PY_CLASSES[name](config)
        _compare_states(c_ctl.fields(), py_ctl.state(), info)
        seq = _smooth_sequence(7 + estimator, 60, config.h)
        gains = []
        for k, inputs in enumerate(seq):
            status, tau_c = c_ctl.step(*inputs)
            tau_py = py_ctl.step(*inputs)
            assert status == STATUS[py_ctl.last_status], (k, status, py_ctl.last_status)
            assert _close(list(tau_c), tau_py, RTOL_CONTROLLER), (k, list(tau_c), tau_py)
            _compare_states(c_ctl.fields(), py_ctl.state(), info)
            gains.append(py_ctl.gain)
        assert py_ctl.steps == len(seq)
        if info.switching:  # the switching gain is exercised, not identically zero
            assert max(gains) > 0.0


# -------------------------------------------------- the SymPy laws, evaluated directly
@dataclass(frozen=True)
class SympyLaws:
    tde: Callable[..., Any]
    gain: Callable[..., Any]
    law: Callable[..., Any]
    lyapunov: Callable[..., Any]
    size: int


@cache
def _sympy_laws(name: str, form: str) -> SympyLaws:
    f: ctl.Formulation = "paper" if form == "paper" else "minimal"
    tde, ts = ctl.tde_estimate(f)
    tde_fn = sp.lambdify(
        [*PARAM_SYMBOLS, *ts.q_prev, *ts.u_prev, *ts.qdot_now, *ts.qdot_then, ts.span], list(tde)
    )
    gain, omega, w = ctl.tdroc_gain(f, MAX_WINDOW)
    # ||Mhat^-1||_F may be a separate input symbol of (25): substitute its expression.
    gain = gain.subs(sp.Symbol("minv_norm", positive=True), ctl.mass_inverse_norm(f))
    gain_fn = sp.lambdify([*PARAM_SYMBOLS, *wmr.q, *omega, *w], gain)
    if name in ("tdc", "tdroc"):
        law, ls = ctl.tde_law(f, switching=name == "tdroc")
    else:
        law, ls = ctl.model_law(f, name)  # type: ignore[arg-type]
    law_args = [
        *PARAM_SYMBOLS, *wmr.q, *wmr.qdot, *ls.e, *ls.edot, *ls.qddot_des, *ls.k1, *ls.k2,
        *ls.p12, *ls.p22, *ls.h1, ls.gain, ls.eps, ls.alpha, ls.phi,
    ]  # fmt: skip
    law_fn = sp.lambdify(law_args, [*law.u, law.s_norm, law.gain])
    k1, k2, q1, q2 = sp.symbols("k1 k2 q1 q2", positive=True)
    lyap_fn = sp.lambdify([k1, k2, q1, q2], list(ctl.lyapunov_p(k1, k2, q1, q2)))
    return SympyLaws(tde_fn, gain_fn, law_fn, lyap_fn, ctl.control_model(f).size)


class SympyController:
    """The documented step semantics, independently: (17) from the previous applied input
    once two steps are stored (h backward / 2h central); Omega(1) = H1hat pushed newest
    first; (25) over the min(count - 1, n) newest differences with weights a^(i-1)
    normalised; tau = B^T u clipped to tau_max; ASMC's gain advanced after the law."""

    def __init__(self, name: str, form: str, config: Any) -> None:
        self.info, self.c = INFO[name], config
        self.laws = _sympy_laws(name, form)
        self.paper = form == "paper"
        self.p = [config.nominal[k] for k in PARAM_KEYS]
        pm = [
            self.laws.lyapunov(a, b, config.q_pos, config.q_vel)
            for a, b in zip(config.k1, config.k2, strict=True)
        ]
        self.p12 = np.array([x[1] for x in pm])
        self.p22 = np.array([x[2] for x in pm])
        self.steps = 0
        self.q_prev, self.qdot_prev, self.qdot_prev2 = np.zeros(5), np.zeros(5), np.zeros(5)
        self.u_prev = np.zeros(5)  # B tau of the previous step
        self.omegas: list[np.ndarray] = []
        self.gain = config.gain0 if self.info.adaptive else 0.0

    def step(self, q: np.ndarray, qdot: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
             qddd: np.ndarray) -> tuple[np.ndarray, float]:  # fmt: skip
        c, n = self.c, self.laws.size
        sl = slice(5 - n, 5)
        h1 = np.zeros(n)
        if self.info.tde and self.steps >= 2:
            central = c.accel_estimator == pyctl.ACCEL_CENTRAL
            then = self.qdot_prev2 if central else self.qdot_prev
            up = self.u_prev if self.paper else self.u_prev[3:]
            span = 2 * c.h if central else c.h
            h1 = np.array(self.laws.tde(*self.p, *self.q_prev, *up, *qdot[sl], *then[sl], span))
        gain = self.gain
        if self.info.window:
            if self.steps >= 2:
                self.omegas = [h1, *self.omegas][: MAX_WINDOW + 1]
            gain = 0.0
            if len(self.omegas) >= 2:
                active = min(len(self.omegas) - 1, c.n)
                w = np.array([c.a**i if i < active else 0.0 for i in range(MAX_WINDOW)])
                om = np.zeros((MAX_WINDOW + 1, n))
                om[: len(self.omegas)] = self.omegas
                gain = float(self.laws.gain(*self.p, *q, *om.reshape(-1), *(w / w.sum())))
        k1, k2 = np.asarray(c.k1)[sl], np.asarray(c.k2)[sl]
        out = self.laws.law(
            *self.p, *q, *qdot, *(qd - q)[sl], *(qdd - qdot)[sl], *qddd[sl], *k1, *k2,
            *self.p12[sl], *self.p22[sl], *h1, gain, c.eps, c.alpha, c.phi,
        )  # fmt: skip
        u, s_norm = np.array(out[:n], dtype=float), float(out[n])
        if self.info.bounds:
            gain = float(out[n + 1])
        tau = np.clip(u[3:] if self.paper else u, -c.tau_max, c.tau_max)
        if self.info.adaptive:
            self.gain = float(ctl.asmc_adaptation(gain, c.gamma, s_norm, c.h))
        self.qdot_prev2, self.qdot_prev, self.q_prev = self.qdot_prev, qdot.copy(), q.copy()
        self.u_prev = np.array([0.0, 0.0, 0.0, *tau])
        self.steps += 1
        return tau, (self.gain if self.info.adaptive else gain)


@pytest.mark.parametrize(("name", "form"), CONTROLLER_CASES, ids=CONTROLLER_IDS)
def test_controller_steps_match_sympy_laws(
    c_builds: dict[str, CBuild], name: str, form: str
) -> None:
    config = _config(name, FORMULATIONS[form])
    ref = SympyController(name, form, config)
    c_ctl = CController(c_builds["double"], name, config)
    py_ctl = PY_CLASSES[name](config)
    for k, inputs in enumerate(_smooth_sequence(11, 8, config.h)):
        tau_ref, gain_ref = ref.step(*inputs)
        _, tau_c = c_ctl.step(*inputs)
        tau_py = py_ctl.step(*inputs)
        assert _close(tau_py, tau_ref, RTOL_SYMPY_LAW), (k, tau_py, tau_ref)
        assert _close(list(tau_c), tau_ref, RTOL_SYMPY_LAW), (k, list(tau_c), tau_ref)
        assert _close(py_ctl.gain, gain_ref, RTOL_SYMPY_LAW), (k, py_ctl.gain, gain_ref)
    if INFO[name].window:
        assert ref.omegas and ref.steps == 8 and py_ctl.gain > 0.0


# ======================================================================= 4. bad input
K2_OVER_M = DRISHTI["K"] ** 2 / DRISHTI["m"]


@dataclass(frozen=True)
class BadCase:
    id: str
    status: str
    inputs: tuple[int, int, float] | None = None  # (which input, index, value)
    config: dict[str, Any] | None = None
    applies: Callable[[ControllerInfo], bool] = lambda info: True


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
        ("k1=0", "WMR_ERR_BAD_GAINS", {"k1": [4.0, 0.0, 6.0, 7.0, 8.0]}, None),
        ("k2<0", "WMR_ERR_BAD_GAINS", {"k2": [3.0, 3.5, 4.0, 4.5, -5.0]}, None),
        ("q_pos=0", "WMR_ERR_BAD_GAINS", {"q_pos": 0.0}, None),
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
    if case.applies(INFO[name])
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
    config = _config(name, 0)
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
    spec = next(s for s in model_specs() if s.name == function)
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


# ======================================================================== 5. codegen CLI
# These run `python -m codegen` (about 10 s each, four at once on two cores).
@pytest.fixture(scope="module")
def codegen_runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    tmp = tmp_path_factory.mktemp("codegen")
    edited = tmp / "edited"
    shutil.copytree(GENERATED, edited, ignore=shutil.ignore_patterns("__pycache__"))
    target = edited / "c" / "wmr_model.h"
    target.write_text(target.read_text().replace("#define WMR_MODEL_H", "#define WMR_MODEL_H  "))
    base = [sys.executable, "-m", "codegen"]
    runs = {
        "a": ([*base, "--out", str(tmp / "a")], "0"),
        "b": ([*base, "--out", str(tmp / "b")], "12345"),
        "check": ([*base, "--check"], None),
        "edited": ([*base, "--check", "--out", str(edited)], None),
    }
    procs = {}
    for key, (cmd, seed) in runs.items():
        env = dict(os.environ)
        if seed is not None:
            env["PYTHONHASHSEED"] = seed
        procs[key] = subprocess.Popen(
            cmd, cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
        )
    results: dict[str, Any] = {"tmp": tmp}
    for key, proc in procs.items():
        out, err = proc.communicate(timeout=300)
        results[key] = (proc.returncode, out, err)
    return results


def _tree(root: Path) -> dict[str, bytes]:
    return {
        p.relative_to(root).as_posix(): p.read_bytes()
        for p in sorted(root.rglob("*"))
        if p.is_file() and "__pycache__" not in p.parts
    }


def _stale_files(diff: str) -> set[str]:
    return set(re.findall(r"^--- generated/(\S+)", diff, flags=re.M))


def test_codegen_is_deterministic_across_hash_seeds(codegen_runs: dict[str, Any]) -> None:
    for key in ("a", "b"):
        assert codegen_runs[key][0] == 0, codegen_runs[key]
    a, b = _tree(codegen_runs["tmp"] / "a"), _tree(codegen_runs["tmp"] / "b")
    assert len(a) > 40 and a.keys() == b.keys()
    assert [k for k in a if a[k] != b[k]] == []


def test_codegen_check_passes_on_repository(codegen_runs: dict[str, Any]) -> None:
    rc, out, err = codegen_runs["check"]
    assert rc == 0, f"generated/ is stale: {sorted(_stale_files(out))}\n{err}"
    assert "up to date" in out


def test_codegen_check_reports_an_edited_file(codegen_runs: dict[str, Any]) -> None:
    rc, out, err = codegen_runs["edited"]
    assert rc == 1, (out, err)
    assert "--- generated/c/wmr_model.h" in out and "+++ regenerated/c/wmr_model.h" in out
    assert "-#define WMR_MODEL_H  " in out and "+#define WMR_MODEL_H\n" in out
    stale_in_repo = _stale_files(codegen_runs["check"][1])
    assert _stale_files(out) == {"c/wmr_model.h"} | stale_in_repo
    assert "stale" in err


def test_codegen_bad_robot_file(tmp_path: Path) -> None:
    robot = tmp_path / "bad.toml"
    fields = {k: v for k, v in DRISHTI.items() if k != "Iw"}
    lines = "".join(f"{k} = {v!r}\n" for k, v in fields.items())
    robot.write_text(f'name = "bad"\n[lumped]\n{lines}')
    out = tmp_path / "out"
    proc = subprocess.run(
        [sys.executable, "-m", "codegen", "--robot", str(robot), "--out", str(out)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 2, proc
    assert "'Iw'" in proc.stderr and str(robot) in proc.stderr
    assert not out.exists()


def test_forward_dynamics_rejects_an_indefinite_model() -> None:
    """Iw = -1 keeps det(SᵀMS) > 0 (both eigenvalues negative): the leading-minor guard
    (Sylvester) must still reject it."""
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
    from generated.python import robot as gen_robot
    from generated.python import wmr_model as gen_model

    params = {**gen_robot.PARAMS, "Iw": -1.0}
    with pytest.raises(ValueError, match="WMR_ERR_BAD_PARAMS"):
        gen_model.forward_dynamics(np.zeros(5), np.zeros(5), np.zeros(2), params)
    with pytest.raises(ValueError, match="WMR_ERR_BAD_PARAMS"):
        gen_model.minimal_forward_dynamics(np.zeros(5), np.zeros(2), np.zeros(2), params)
