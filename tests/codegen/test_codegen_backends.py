"""Code-generation backends (C99, NumPy, CasADi) against the SymPy expressions they print.

Toy FunctionSpecs cover every construct the backends print: a params struct (with an
array field), a struct input and struct output of the same type, a 2x2 matrix output,
trig, sqrt and half-integer powers, integer and negative powers, rationals and pi,
Piecewise/Max/Min/Abs, several outputs sharing subexpressions, an unused input and a
function of constants only. Each backend is evaluated at random inputs and compared with
the SymPy expressions evaluated by mpmath at 50 digits: to 1e-12 (relative, scale
max(1, |ref|)) in double, to 2e-5 in the float32 C build.
"""

from __future__ import annotations

import hashlib
import os
import platform
import re
import shutil
import subprocess
import sys
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

import casadi as ca
import mpmath
import numpy as np
import pytest
import sympy as sp

from codegen.backends import c as c_backend
from codegen.backends import casadi as casadi_backend
from codegen.backends import python as py_backend
from codegen.cse import count_ops, cse_function
from codegen.layout import argument_size, split_fields
from codegen.spec import Argument, Field, FunctionSpec
from runtime.bindings import cbuild

MODULE = "wmr_toy"
SOURCE = "tests/codegen/test_codegen_backends.py (toy specs)"
N_SAMPLES = 120
RTOL_DOUBLE = 1e-12
RTOL_FLOAT = 2e-5
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

# ---------------------------------------------------------------------------- toy specs
x, y, theta = sp.symbols("x y theta", real=True)
u_r, u_l = sp.symbols("u_r u_l", real=True)
m, I, r, b, d = sp.symbols("m I r b d", real=True)
k1, k2 = sp.symbols("k_1 k_2", real=True)
e = sp.Symbol("e", real=True)
z = sp.symbols("z_0 z_1", real=True)
P = sp.symbols("P_00 P_01 P_10 P_11", real=True)

Q = Argument("q", "array", (3, 1), (x, y, theta), doc="pose")
U = Argument("u", "array", (1, 2), (u_r, u_l), doc="wheel speeds (a row)")
PARAMS = Argument(
    "p",
    "params",
    fields=(
        Field("m", (m,), doc="mass"),
        Field("I", (I,), doc="inertia", c_name="Iz"),  # I is a <complex.h> macro
        Field("r", (r,)),
        Field("b", (b,)),
        Field("d", (d,)),
        Field("gains", (k1, k2), (2, 1), doc="two gains"),
    ),
)
STATE_FIELDS = (
    Field("e", (e,), doc="scalar"),
    Field("z", z, (2, 1), doc="vector"),
    Field("P", P, (2, 2), doc="matrix"),
)
STATE = Argument("s", "struct", fields=STATE_FIELDS, ctype="wmr_toy_state_t", doc="state")

_v = r / 2 * (u_r + u_l)
_M_common = m * r**2 / 4
_M_cross = (I + m * d**2) * r**2 / (4 * b**2)
KINEMATICS = FunctionSpec(
    name="kinematics",
    doc="Unicycle kinematics and a wheel-space mass matrix.\nShares r**2 and b**2.",
    inputs=(Q, U, PARAMS),
    outputs=(
        Argument(
            "xdot",
            "array",
            (3, 1),
            exprs=(_v * sp.cos(theta), _v * sp.sin(theta), r / (2 * b) * (u_r - u_l)),
        ),
        Argument(
            "M",
            "array",
            (2, 2),
            exprs=(
                _M_common + _M_cross,
                _M_common - _M_cross,
                _M_common - _M_cross,
                _M_common + _M_cross,
            ),
        ),
    ),
    equations=("(1)", "(2)"),
)

POWERS = FunctionSpec(
    name="powers",
    doc="Roots, integer and negative powers, rationals, constants and other functions.",
    inputs=(Q, PARAMS),
    outputs=(
        Argument(
            "out",
            "array",
            (1, 10),
            exprs=(
                sp.sqrt(x**2 + y**2 + d**2),
                (x + y) ** 3 - x**4 + y**5 / (x + 3),
                x**-2 + (y + m) ** -3,
                (x**2 + 1) ** sp.Rational(3, 2) + (y**2 + 2) ** sp.Rational(-1, 2),
                sp.exp(-x) * sp.tan(theta / 3) + sp.log(m),
                sp.atan2(y, x) + sp.asin(sp.cos(theta) / 2) * sp.tanh(y),
                sp.Rational(1, 3) * x + sp.Rational(7, 8) * y + sp.pi + sp.sqrt(2) * x,
                m**2.5 + sp.Float("0.1") * y - sp.Rational(-2, 3),
                sp.Abs(x - y) * sp.cosh(y / 4) + sp.sinh(x / 3) * sp.acos(sp.sin(theta) / 3),
                sp.sin(theta) ** 2 * k1 - sp.atan(y) * k2 / (m * r),
            ),
        ),
    ),
)

BRANCHES = FunctionSpec(
    name="branches",
    doc="Piecewise, Max, Min and Abs.",
    inputs=(Q, PARAMS),
    outputs=(
        Argument(
            "out",
            "array",
            (4, 1),
            exprs=(
                sp.Piecewise(
                    (x, x > y),
                    (2 * y, sp.And(y >= 0, x < sp.Float("0.5"))),
                    (-y + 1, sp.Or(y < -1, sp.Not(x > 1))),
                    (0, True),
                ),
                sp.Max(x, y, -d) + sp.Min(x, sp.Rational(1, 10)),
                sp.Abs(sp.sin(theta)) * sp.Max(x, y),
                sp.Piecewise((sp.sqrt(x), x > 0), (-x, True)) + sp.Min(y, d, m),
            ),
        ),
    ),
)

_err = e * sp.cos(theta) + z[0]
CTRL_STEP = FunctionSpec(
    name="ctrl_step",
    doc="A controller step: struct state in, struct state out, an unused input.",
    inputs=(STATE, Q, U, PARAMS),
    outputs=(
        Argument(
            "s_next",
            "struct",
            fields=STATE_FIELDS,
            ctype="wmr_toy_state_t",
            exprs=(
                _err**2 + P[0],
                z[1] * k1 - _err,
                z[0] * k2 + P[1] * _err,
                P[0] * P[3] - P[1] * P[2],
                P[1] + _err / m,
                P[2] - x,
                P[3] * sp.sin(theta) ** 2,
            ),
        ),
        Argument("tau", "array", (2, 1), exprs=(k1 * _err, -k2 * _err + y)),
    ),
    equations=("(40)",),
    returns_status=True,
)

CONSTANTS = FunctionSpec(
    name="constants",
    doc="Symbol-free outputs only: every input is unused.",
    inputs=(Q,),
    outputs=(
        Argument(
            "out",
            "array",
            (5, 1),
            exprs=(sp.Integer(1), sp.Rational(-1, 3), sp.sqrt(2), sp.pi / 4, sp.Integer(0)),
        ),
    ),
)

SPECS: tuple[FunctionSpec, ...] = (KINEMATICS, POWERS, BRANCHES, CTRL_STEP, CONSTANTS)
SPEC_IDS = [s.name for s in SPECS]


# ------------------------------------------------------------------ inputs and reference
def _sample(symbol: sp.Symbol, rng: np.random.Generator) -> float:
    """Random value in a range where every toy expression is defined and well scaled."""
    if symbol in (x, m, I, r, b, d):
        return float(rng.uniform(0.5, 2.0))
    if symbol == theta:
        return float(rng.uniform(-np.pi, np.pi))
    return float(rng.uniform(-2.0, 2.0))


def _samples(spec: FunctionSpec, seed: int) -> list[dict[sp.Symbol, float]]:
    rng = np.random.default_rng(seed)
    symbols = spec.input_symbols()
    return [{s: _sample(s, rng) for s in symbols} for _ in range(N_SAMPLES)]


def _reference(spec: FunctionSpec) -> Callable[[dict[sp.Symbol, float]], np.ndarray]:
    """The spec's own expressions, evaluated by mpmath at 50 digits."""
    symbols = list(spec.input_symbols())
    exprs = [ex for arg in spec.outputs for ex in arg.exprs]
    f = sp.lambdify(symbols, exprs, modules="mpmath")

    def evaluate(values: dict[sp.Symbol, float]) -> np.ndarray:
        with mpmath.workdps(50):
            out = f(*[mpmath.mpf(values[s]) for s in symbols])
        return np.array([float(v) for v in out])

    return evaluate


def _assert_close(got: np.ndarray, ref: np.ndarray, rtol: float, what: str) -> None:
    scale = np.maximum(1.0, np.abs(ref))
    err = np.abs(np.asarray(got, dtype=np.float64) - ref) / scale
    assert np.all(err <= rtol), f"{what}: max scaled error {err.max():.3g} > {rtol}"


def _arg_values(arg: Argument, values: dict[sp.Symbol, float]) -> list[float]:
    return [values[s] for s in arg.all_symbols()]


# -------------------------------------------------------------------------- C harness
def _gcc() -> str:
    gcc = shutil.which("gcc")
    if gcc is None:
        pytest.skip("gcc not available")
    return gcc


MACRO_CHECK_C = """\
#include "wmr_types.h"
int wmr_check_macros(wmr_real_t v);
/* Macros the generated functions may not use yet, compiled with the same flags. */
int wmr_check_macros(wmr_real_t v)
{
    const wmr_real_t w = WMR_FMIN(WMR_FABS(v), WMR_LIT(1e3)) + WMR_POW(WMR_LIT(2.0), v);
    return (WMR_ISFINITE(w) && w < WMR_INF) ? WMR_OK : 1;
}
"""


def _render_c(directory: Path) -> dict[str, str]:
    files = c_backend.render_all({MODULE: SPECS}, source=SOURCE)
    for name, text in files.items():
        (directory / name).write_text(text)
    (directory / "check_macros.c").write_text(MACRO_CHECK_C)
    return files


@pytest.fixture(scope="module")
def c_build(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """Render the C files and compile them in both precisions with the strict flags
    (``runtime.bindings.cbuild`` compiles and binds)."""
    _gcc()
    directory = tmp_path_factory.mktemp("c")
    _render_c(directory)
    sources = [directory / f"{MODULE}.c", directory / "check_macros.c"]
    out: dict[str, Any] = {"dir": directory}
    for precision, defines in (("double", []), ("float", ["-DWMR_FLOAT32"])):
        float32 = precision == "float"
        so = directory / f"lib{MODULE}_{precision}.so"
        lib = cbuild.build_library(
            sources, so,
            [c_backend.cdef(SPECS, float32=float32), "int wmr_check_macros(wmr_real_t v);"],
            float32=float32, flags=[*C_FLAGS, "-O2", *defines], include_dirs=[directory],
            libs=[],
        )  # fmt: skip
        obj = directory / f"{MODULE}_{precision}.o"
        cbuild.run_compiler([cbuild.gcc_command(sources[:1], obj, kind="object",
                                                flags=[*C_FLAGS, "-O2", *defines])])
        out[precision] = (lib.ffi, lib.lib, obj)
    return out


def _call_c(ffi: Any, lib: Any, spec: FunctionSpec, values: dict[sp.Symbol, float]) -> np.ndarray:
    """Call ``wmr_<spec.name>`` through cffi; outputs flattened row-major."""
    args: list[Any] = []
    for arg in spec.inputs:
        if arg.kind == "array":
            args.append(ffi.new(f"wmr_real_t[{argument_size(arg)}]", _arg_values(arg, values)))
            continue
        ctype = arg.ctype or "wmr_params_t"
        obj = ffi.new(f"{ctype} *")
        for f in arg.fields:
            vals = [values[s] for s in f.symbols]
            cname = f.c_field
            if f.shape == (1, 1):
                setattr(obj, cname, vals[0])
            elif 1 in f.shape:
                setattr(obj, cname, vals)
            else:
                cols = f.shape[1]
                setattr(obj, cname, [vals[i : i + cols] for i in range(0, len(vals), cols)])
        args.append(obj)
    outs: list[Any] = []
    for arg in spec.outputs:
        if arg.kind == "array":
            outs.append(ffi.new(f"wmr_real_t[{argument_size(arg)}]"))
        else:
            outs.append(ffi.new(f"{arg.ctype} *"))
    status = getattr(lib, f"wmr_{spec.name}")(*args, *outs)
    if spec.returns_status:
        assert status == lib.WMR_OK
    flat: list[float] = []
    for arg, buf in zip(spec.outputs, outs, strict=True):
        if arg.kind == "array":
            flat += list(buf)
            continue
        for f in arg.fields:
            value = getattr(buf, f.name)
            if f.shape == (1, 1):
                flat.append(float(value))
            elif 1 in f.shape:
                flat += list(value)
            else:
                flat += [float(v) for row in value for v in row]
    return np.array(flat)


@pytest.mark.parametrize("precision", ["double", "float"])
@pytest.mark.parametrize("spec", SPECS, ids=SPEC_IDS)
def test_c_matches_sympy(c_build: dict[str, Any], spec: FunctionSpec, precision: str) -> None:
    ffi, lib, _ = c_build[precision]
    ref = _reference(spec)
    rtol = RTOL_DOUBLE if precision == "double" else RTOL_FLOAT
    for i, values in enumerate(_samples(spec, seed=1)):
        _assert_close(_call_c(ffi, lib, spec, values), ref(values), rtol, f"{spec.name}#{i}")


@pytest.mark.parametrize("precision", ["double", "float"])
def test_c_macros(c_build: dict[str, Any], precision: str) -> None:
    _, lib, _ = c_build[precision]
    assert lib.wmr_check_macros(0.5) == lib.WMR_OK
    assert lib.WMR_KINEMATICS_M_SIZE == 4 and lib.WMR_POWERS_OUT_SIZE == 10


def test_c_in_place_update_is_safe(c_build: dict[str, Any]) -> None:
    """Inputs are read into locals before any output is stored: s_next may alias s."""
    ffi, lib, _ = c_build["double"]
    values = _samples(CTRL_STEP, seed=3)[0]
    expected = _call_c(ffi, lib, CTRL_STEP, values)
    state = ffi.new("wmr_toy_state_t *")
    state.e, state.z, state.P = (
        values[e],
        [values[v] for v in z],
        [
            [values[P[0]], values[P[1]]],
            [values[P[2]], values[P[3]]],
        ],
    )
    q = ffi.new("wmr_real_t[3]", [values[v] for v in (x, y, theta)])
    u = ffi.new("wmr_real_t[2]", [values[u_r], values[u_l]])
    p = ffi.new("wmr_params_t *")
    p.m, p.Iz, p.r, p.b, p.d = (values[v] for v in (m, I, r, b, d))
    p.gains = [values[k1], values[k2]]
    tau = ffi.new("wmr_real_t[2]")
    assert lib.wmr_ctrl_step(state, q, u, p, state, tau) == lib.WMR_OK
    got = [state.e, *state.z, *state.P[0], *state.P[1], *tau]
    np.testing.assert_array_equal(got, expected)


def _undefined_symbols(obj: Path) -> set[str]:
    nm = shutil.which("nm")
    if nm is None:
        pytest.skip("nm not available")
    out = subprocess.run([nm, "-u", str(obj)], capture_output=True, text=True, check=True).stdout
    return {line.split()[-1] for line in out.splitlines() if line.strip()}


DOUBLE_MATH = {
    "sin", "cos", "sincos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh",
    "exp", "log", "sqrt", "pow", "fabs", "fmax", "fmin",
}  # fmt: skip


def test_float_build_uses_no_double(c_build: dict[str, Any]) -> None:
    """Float build (already compiled with -Wdouble-promotion -Werror): no double math
    function is linked, and on x86-64 with FMA no double-precision instruction is emitted."""
    _, _, obj = c_build["float"]
    undefined = _undefined_symbols(obj)
    assert not undefined & DOUBLE_MATH, sorted(undefined & DOUBLE_MATH)
    assert undefined & {"sinf", "sincosf", "cosf"}, sorted(undefined)
    # The toy specs' square roots are single precision: gcc inlines sqrtss and keeps a call
    # to sqrtf for a negative argument (errno), so sqrtf is linked exactly when used.
    assert "sqrtf" in undefined, sorted(undefined)
    _, _, obj_double = c_build["double"]
    undefined_double = _undefined_symbols(obj_double)
    assert undefined_double & {"sin", "sincos", "cos"} and "sqrt" in undefined_double
    objdump = shutil.which("objdump")
    if objdump is None or platform.machine() not in ("x86_64", "AMD64"):
        return
    # An x86-64 host without FMA reduces sin/cos's argument in double (types.h: fmaf is a
    # library call there, and double as fast as float); with FMA, as on a Cortex-M4F, in
    # float by fmaf. Built so, the float code holds no double instruction at all.
    fma_obj = c_build["dir"] / f"{MODULE}_float_fma.o"
    cbuild.run_compiler([cbuild.gcc_command([c_build["dir"] / f"{MODULE}.c"], fma_obj,
                                            kind="object",
                                            flags=[*C_FLAGS, "-O2", "-DWMR_FLOAT32", "-mfma"])])
    asm = subprocess.run([objdump, "-d", str(fma_obj)], capture_output=True, text=True).stdout
    double_ops = [
        line
        for line in asm.splitlines()
        if any(op in line for op in ("cvtss2sd", "cvtsd2ss", "addsd", "mulsd", "divsd", "subsd"))
    ]
    assert not double_ops, double_ops[:5]


def test_c_header_is_cxx_compatible(c_build: dict[str, Any]) -> None:
    gxx = shutil.which("g++")
    if gxx is None:
        pytest.skip("g++ not available")
    directory: Path = c_build["dir"]
    src = directory / "use.cpp"
    src.write_text(f'#include "{MODULE}.h"\nint main() {{ return WMR_OK; }}\n')
    cmd = [gxx, "-Wall", "-Wextra", "-Werror", "-fsyntax-only", "-I", str(directory), str(src)]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr


def test_c_printing_rules() -> None:
    files = c_backend.render([POWERS, BRANCHES, KINEMATICS], MODULE)
    text = files[f"{MODULE}.c"]
    assert "pow(" not in text.replace("WMR_POW(", "")  # only m**2.5 uses WMR_POW
    assert text.count("WMR_POW(") == 1
    assert "x*x*x*x" in text  # x**4 as a product
    assert "WMR_LIT(1.0)/(_t5*_t5*_t5)" in text  # (y + m)**-3, the base hoisted by CSE
    assert "WMR_LIT(2.0)/WMR_LIT(3.0)" in text  # a constant 2/3: folded by the compiler
    assert "WMR_LIT(0.875)" in text  # 7/8 is exact in binary: one literal
    assert "WMR_LIT(0.3333333333333333)*x" in text  # x/3: a product, not a division
    assert "x/WMR_LIT(3.0)" not in text
    assert "WMR_LIT(1.4142135623730951)" in text  # sqrt(2) folded to a literal
    assert "WMR_SQRT(" in text and " ? " in text
    assert "WMR_FMAX(" in text and "WMR_FMIN(" in text and "WMR_FABS(" in text
    for token in ("M_PI", "double", "float", "sqrt(", "0.5f"):
        assert token not in text.replace("WMR_SQRT(", ""), token
    header = files[f"{MODULE}.h"]
    assert "#define WMR_KINEMATICS_M_SIZE 4" in header
    assert "#define WMR_KINEMATICS_M_ROWS 2" in header
    assert "#define WMR_POWERS_OUT_SIZE 10" in header
    assert 'extern "C"' in header and "#ifndef WMR_TOY_H" in header
    for f in files.values():
        assert "DO NOT EDIT" in f.splitlines()[1] and SOURCE not in f  # no source given


def test_a_root_over_a_divisor_prints_the_reciprocal_beside_it() -> None:
    """sqrt(a)/d prints as sqrt(a)*(1/d), in C and Python alike: the reciprocal need not
    wait for the root (||Mhat^-1||_F of (25), sqrt(...)/|det Mhat|, is on a step's chain to
    tau), and the count has the one multiplication more. A quotient without a root stays
    one division."""
    spec = FunctionSpec(
        "root_ratio",
        "A root over a divisor, and a quotient without one.",
        (Argument("q", "array", (3, 1), (x, y, theta)),),
        (Argument("out", "array", (2, 1),
                  exprs=(sp.sqrt(x**2 + 2 * y**2) / sp.Abs(x * y - theta), x / (y + theta))),),
    )
    c_text = c_backend.render([spec], MODULE)[f"{MODULE}.c"]
    assert re.search(r"WMR_SQRT\([^;]*\)\*\(WMR_LIT\(1\.0\)/WMR_FABS\(", c_text), c_text
    assert re.search(r"= x/\((theta \+ y|y \+ theta)\);", c_text), c_text
    py_text = py_backend.render([spec], MODULE)[f"{MODULE}.py"]
    assert re.search(r"math\.sqrt\([^\n]*\)\*\(1\.0/abs\(", py_text), py_text
    # x*x + 2.0*y*y and x*y: 4 mul, then the product with the reciprocal
    ops = count_ops(cse_function(spec)).summary()
    assert ops == "3 add, 5 mul, 2 div, 0 sin/cos, 1 sqrt, 1 fabs", ops


def test_types_header_contents() -> None:
    files = c_backend.render_all({MODULE: SPECS, "wmr_other": [CTRL_STEP]}, source=SOURCE)
    types = files["wmr_types.h"]
    # Each struct once, even though two modules use it.
    assert types.count("} wmr_toy_state_t;") == 1
    assert types.count("} wmr_params_t;") == 1
    assert "wmr_real_t P[2][2];" in types and "wmr_real_t gains[2];" in types
    assert "WMR_OK = 0" in types
    # sin, cos: the generated ones (libm's beyond their bound) in both precisions
    assert "#define WMR_LIT(x) x##f" in types and "#define WMR_SIN(x) wmr_sin(x)" in types
    assert "#define WMR_TAN(x) tanf(x)" in types
    assert set(files) == {"wmr_types.h", f"{MODULE}.h", f"{MODULE}.c", "wmr_other.h", "wmr_other.c"}
    for text in files.values():
        assert SOURCE in text and "DO NOT EDIT" in text


def test_status_codes_are_config_data() -> None:
    config = c_backend.CConfig(
        status_codes=(
            c_backend.StatusCode("WMR_OK", 0, "success"),
            c_backend.StatusCode("WMR_E_NONFINITE", 1, "a result is not finite"),
        )
    )
    types = c_backend.render_types(SPECS, config)["wmr_types.h"]
    assert "WMR_OK = 0, /* success */" in types
    assert "WMR_E_NONFINITE = 1 /* a result is not finite */" in types


# ---------------------------------------------------------------------- Python backend
@pytest.fixture(scope="module")
def py_module(tmp_path_factory: pytest.TempPathFactory) -> Any:
    import importlib.util

    directory = tmp_path_factory.mktemp("py")
    files = py_backend.render(SPECS, MODULE, source=SOURCE)
    path = directory / f"{MODULE}.py"
    path.write_text(files[f"{MODULE}.py"])
    module_spec = importlib.util.spec_from_file_location(f"_generated_{MODULE}", path)
    assert module_spec is not None and module_spec.loader is not None
    module = importlib.util.module_from_spec(module_spec)
    module_spec.loader.exec_module(module)
    return module


def _py_arg(arg: Argument, values: dict[sp.Symbol, float]) -> Any:
    if arg.kind == "array":
        return np.array(_arg_values(arg, values)).reshape(arg.shape)
    return {
        f.name: values[f.symbols[0]]
        if f.shape == (1, 1)
        else np.array([values[s] for s in f.symbols]).reshape(f.shape)
        for f in arg.fields
    }


def _flatten_py(spec: FunctionSpec, result: Any) -> np.ndarray:
    results = result if len(spec.outputs) > 1 else (result,)
    flat: list[float] = []
    for arg, value in zip(spec.outputs, results, strict=True):
        if arg.kind == "array":
            expected = arg.shape if 1 not in arg.shape else (argument_size(arg),)
            assert isinstance(value, np.ndarray) and value.shape == expected
            flat += value.reshape(-1).tolist()
        else:
            assert list(value) == [f.name for f in arg.fields]
            for f in arg.fields:
                if f.shape == (1, 1):
                    assert isinstance(value[f.name], float)
                flat += np.asarray(value[f.name]).reshape(-1).tolist()
    return np.array(flat)


@pytest.mark.parametrize("spec", SPECS, ids=SPEC_IDS)
def test_python_matches_sympy(py_module: Any, spec: FunctionSpec) -> None:
    function = getattr(py_module, spec.name)
    ordered = [a for a in spec.inputs if a.kind != "params"] + [
        a for a in spec.inputs if a.kind == "params"
    ]
    ref = _reference(spec)
    for i, values in enumerate(_samples(spec, seed=2)):
        got = _flatten_py(spec, function(*[_py_arg(a, values) for a in ordered]))
        _assert_close(got, ref(values), RTOL_DOUBLE, f"{spec.name}#{i}")


def test_python_accepts_objects_and_checks_sizes(py_module: Any) -> None:
    class Params:
        m, I, r, b, d, gains = 1.0, 0.5, 0.1, 0.3, 0.05, (1.0, 2.0)

    values = {"m": 1.0, "I": 0.5, "r": 0.1, "b": 0.3, "d": 0.05, "gains": [1.0, 2.0]}
    a = py_module.kinematics([0.0, 0.0, 0.3], [[1.0, 2.0]], Params())
    b_ = py_module.kinematics(np.array([[0.0], [0.0], [0.3]]), (1.0, 2.0), values)
    for u_, v_ in zip(a, b_, strict=True):
        np.testing.assert_array_equal(u_, v_)
    with pytest.raises(ValueError, match="q: expected 3 values"):
        py_module.kinematics([0.0, 0.0], [1.0, 2.0], values)


def test_python_module_imports_only_numpy_and_math() -> None:
    text = py_backend.render(SPECS, MODULE)[f"{MODULE}.py"]
    imports = {line for line in text.splitlines() if line.startswith(("import ", "from "))}
    assert imports == {
        "from __future__ import annotations",
        "import math",
        "from collections.abc import Mapping",
        "from typing import Any",
        "import numpy as np",
        "from numpy.typing import ArrayLike, NDArray",
    }
    code = [line for line in text.splitlines() if line.startswith("    ") and "=" in line]
    assert code and not any("**" in line for line in code)  # powers are products
    assert "sympy" not in text and "casadi" not in text


def test_python_module_passes_ruff(tmp_path: Path) -> None:
    ruff = Path(sys.executable).with_name("ruff")
    if not ruff.exists():
        pytest.skip("ruff not installed")
    path = tmp_path / f"{MODULE}.py"
    path.write_text(py_backend.render(SPECS, MODULE)[f"{MODULE}.py"])
    proc = subprocess.run(
        [str(ruff), "check", "--isolated", "--select", "E9,F", str(path)],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr


# ---------------------------------------------------------------------- CasADi backend
def _call_casadi(
    function: ca.Function, spec: FunctionSpec, values: dict[sp.Symbol, float]
) -> np.ndarray:
    result = function(*[ca.DM(_arg_values(a, values)) for a in spec.inputs])
    results = result if isinstance(result, tuple) else (result,)
    return np.concatenate([np.asarray(v, dtype=np.float64).reshape(-1) for v in results])


@pytest.mark.parametrize("spec", SPECS, ids=SPEC_IDS)
def test_casadi_matches_sympy(spec: FunctionSpec, tmp_path: Path) -> None:
    function = casadi_backend.to_casadi(spec)
    assert function.name_in() == [a.name for a in spec.inputs]
    assert function.name_out() == [a.name for a in spec.outputs]
    files = casadi_backend.render([spec], MODULE)
    (tmp_path / f"{spec.name}.casadi").write_bytes(files[f"{spec.name}.casadi"])
    loaded = ca.Function.load(str(tmp_path / f"{spec.name}.casadi"))
    ref = _reference(spec)
    for i, values in enumerate(_samples(spec, seed=4)):
        expected = ref(values)
        _assert_close(_call_casadi(function, spec, values), expected, RTOL_DOUBLE, f"#{i}")
        _assert_close(_call_casadi(loaded, spec, values), expected, RTOL_DOUBLE, f"load #{i}")


def test_casadi_matrix_layout_is_row_major() -> None:
    """M is returned flat row-major; CasADi's column-major reshape needs a transpose."""
    values = _samples(KINEMATICS, seed=5)[0]
    function = casadi_backend.to_casadi(KINEMATICS)
    _, flat = function(*[ca.DM(_arg_values(a, values)) for a in KINEMATICS.inputs])
    expected = sp.Matrix(2, 2, list(KINEMATICS.outputs[1].exprs)).subs(values)
    matrix = np.array(ca.reshape(flat, 2, 2).T)
    np.testing.assert_allclose(matrix, np.array(expected, dtype=float), rtol=1e-12)
    np.testing.assert_allclose(np.asarray(flat).reshape(2, 2), matrix, rtol=0)


def test_casadi_generated_c_matches(tmp_path: Path) -> None:
    """CasADi's own C (for the benchmark) compiles and agrees with SymPy."""
    _gcc()
    c_file, h_file = casadi_backend.generate_c(SPECS, tmp_path, "casadi_toy")
    assert c_file.exists() and h_file.exists()
    so = tmp_path / "libcasadi_toy.so"
    decls = []
    for spec in SPECS:
        n = f"casadi_{spec.name}"
        decls.append(
            f"int {n}(const double** arg, double** res, long long* iw, double* w, int mem);"
            f"int {n}_work(long long* sz_arg, long long* sz_res, long long* sz_iw,"
            f" long long* sz_w);"
        )
    built = cbuild.build_library([c_file], so, "\n".join(decls), flags=["-std=c99", "-O2"])
    ffi, lib = built.ffi, built.lib
    for spec in SPECS:
        sizes = [ffi.new("long long *") for _ in range(4)]
        assert getattr(lib, f"casadi_{spec.name}_work")(*sizes) == 0
        n_arg, n_res, n_iw, n_w = (int(s[0]) for s in sizes)
        ref = _reference(spec)
        for values in _samples(spec, seed=6)[:20]:
            ins = [ffi.new("double[]", _arg_values(a, values)) for a in spec.inputs]
            outs = [ffi.new(f"double[{argument_size(a)}]") for a in spec.outputs]
            arg = ffi.new(f"const double*[{max(n_arg, len(ins))}]", ins)
            res = ffi.new(f"double*[{max(n_res, len(outs))}]", outs)
            iw = ffi.new(f"long long[{max(n_iw, 1)}]")
            w = ffi.new(f"double[{max(n_w, 1)}]")
            assert getattr(lib, f"casadi_{spec.name}")(arg, res, iw, w, 0) == 0
            got = np.concatenate([np.array(list(o)) for o in outs])
            _assert_close(got, ref(values), RTOL_DOUBLE, spec.name)


# ---------------------------------------------------------------- CSE and op counting
def test_cse_shares_across_outputs() -> None:
    result = cse_function(KINEMATICS)
    # r/2*(u_r + u_l) feeds xdot[0] and xdot[1]; r**2 and b**2 feed all of M.
    assert len(result.temps) >= 3
    assert [str(s) for s, _ in result.temps] == [f"_t{i}" for i in range(len(result.temps))]
    for exprs, arg in zip(result.outputs, KINEMATICS.outputs, strict=True):
        assert len(exprs) == len(arg.exprs)
    # Substituting the temporaries back gives the original expressions.
    subs: dict[sp.Basic, sp.Basic] = {}
    for s, ex in result.temps:
        subs[s] = ex.xreplace(subs)
    for exprs, arg in zip(result.outputs, KINEMATICS.outputs, strict=True):
        for got, want in zip(exprs, arg.exprs, strict=True):
            assert sp.simplify(got.xreplace(subs) - want) == 0


def test_compound_power_bases_become_temporaries() -> None:
    result = cse_function(POWERS)
    for _, ex in (*result.temps, *((None, o) for outs in result.outputs for o in outs)):
        for power in ex.atoms(sp.Pow):
            if power.exp.is_Integer and abs(power.exp) >= 2:
                assert isinstance(power.base, sp.Symbol), power


def test_op_count_format_and_values() -> None:
    spec = FunctionSpec(
        "ops",
        "op count",
        (Argument("q", "array", (3, 1), (x, y, theta)),),
        (
            Argument(
                "out",
                "array",
                (3, 1),
                exprs=(x**3 + x * y, -y / x + sp.sin(theta), sp.sqrt(x) * sp.cos(theta)),
            ),
        ),
    )
    ops = count_ops(cse_function(spec))
    # CSE without factoring (the "basic" preprocessing costs 10x the generation time):
    # x**3 + x*y prints x*x*x + x*y: 3 mul, 1 add; sin(theta) - y/x: 1 add, 1 div, the
    # negation is free; sqrt(x)*cos(theta): 1 mul.
    text = c_backend.render([spec], MODULE)[f"{MODULE}.c"]
    assert "x*x*x + x*y" in text and "WMR_SIN(theta) - y/x" in text
    assert ops.summary() == "2 add, 4 mul, 1 div, 2 sin/cos, 1 sqrt"
    assert ops.comment() == "operations after CSE: 2 add, 4 mul, 1 div, 2 sin/cos, 1 sqrt"
    assert count_ops(cse_function(BRANCHES)).summary().endswith(", 6 cmp, 1 fabs, 3 fmax, 3 fmin")


def test_op_counts_appear_in_every_backend() -> None:
    c_text = c_backend.render(SPECS, MODULE)[f"{MODULE}.c"]
    h_text = c_backend.render(SPECS, MODULE)[f"{MODULE}.h"]
    py_text = py_backend.render(SPECS, MODULE)[f"{MODULE}.py"]
    manifest = casadi_backend.render(SPECS, MODULE)[f"{MODULE}.casadi.txt"].decode()
    # (the C wraps comments at 100 columns: compare with its comment lines joined)
    c_text, h_text = (re.sub(r"\n *(?:\* )?", " ", t) for t in (c_text, h_text))
    for spec in SPECS:
        comment = count_ops(cse_function(spec, reciprocals=True)).comment()
        for text in (c_text, h_text, py_text, manifest):
            assert comment in text, (spec.name, comment)


def test_invalid_specs_are_rejected() -> None:
    stray = sp.Symbol("stray")
    bad = FunctionSpec("bad", "", (Q,), (Argument("out", "array", (1, 1), exprs=(x + stray,)),))
    with pytest.raises(ValueError, match="unknown symbols stray"):
        cse_function(bad)
    wrong_size = FunctionSpec("bad", "", (Q,), (Argument("out", "array", (2, 1), exprs=(x,)),))
    with pytest.raises(ValueError, match="expected 2"):
        cse_function(wrong_size)
    unprefixed = Argument("s", "struct", fields=STATE_FIELDS, ctype="state_t")
    with pytest.raises(ValueError, match="must start with wmr_"):
        c_backend.render_types([FunctionSpec("f", "", (unprefixed,), ())])


def test_struct_output_chunks() -> None:
    chunks = split_fields(CTRL_STEP.outputs[0], list(CTRL_STEP.outputs[0].exprs))
    assert [(f.name, len(v)) for f, v in chunks] == [("e", 1), ("z", 2), ("P", 4)]


# -------------------------------------------------------------------------- determinism
def _render_everything() -> Iterator[tuple[str, bytes]]:
    for name, text in sorted(c_backend.render_all({MODULE: SPECS}, source=SOURCE).items()):
        yield f"c/{name}", text.encode()
    for name, text in sorted(py_backend.render(SPECS, MODULE, source=SOURCE).items()):
        yield f"py/{name}", text.encode()
    for name, data in sorted(casadi_backend.render(SPECS, MODULE, source=SOURCE).items()):
        yield f"casadi/{name}", data


def digests() -> dict[str, str]:
    """sha256 of every rendered file (also called from a subprocess)."""
    return {name: hashlib.sha256(data).hexdigest() for name, data in _render_everything()}


def test_rendering_twice_is_identical() -> None:
    assert dict(_render_everything()) == dict(_render_everything())


@pytest.mark.parametrize("seeds", [("0", "4242")])
def test_rendering_is_independent_of_hash_seed(seeds: Sequence[str]) -> None:
    here = Path(__file__).resolve().parent
    code = (
        f"import sys, json; sys.path.insert(0, {str(here)!r}); "
        "import test_codegen_backends as t; print(json.dumps(t.digests(), sort_keys=True))"
    )
    outputs = []
    for seed in seeds:
        env = {**os.environ, "PYTHONHASHSEED": seed}
        proc = subprocess.run(
            [sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True
        )
        outputs.append(proc.stdout)
    assert outputs[0] == outputs[1]
    import json

    assert json.loads(outputs[0]) == digests()
