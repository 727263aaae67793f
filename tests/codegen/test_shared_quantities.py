"""Quantities several functions of a module read, evaluated once by a static helper
(``codegen.shared``, issue 51): on toy specs, the C module prints the shared arithmetic in
the helper alone, every member calls it, and each member's results equal its SymPy
expressions (1e-12 in double); the certifier reads the member's whole evaluation.
"""

from __future__ import annotations

import random
import re

import pytest
import sympy as sp

from codegen.backend import function_ir, with_shared
from codegen.backends import c as c_backend
from codegen.backends.c.certify.program import program_of
from codegen.backends.c.config import CConfig
from codegen.backends.c.files import render_all_ir
from codegen.shared import share
from codegen.spec import Argument, Field, FunctionSpec
from runtime.bindings import cbuild

MODULE = "wmr_shared_toy"
C_FLAGS = ["-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Wshadow", "-Wdouble-promotion",
           "-Wfloat-equal", "-Wconversion", "-Werror", "-O1"]

a, b = sp.symbols("a b", real=True)
x = sp.symbols("x0:3", real=True)
u = sp.Symbol("u", real=True)
d0, d1, d2 = sp.symbols("_d0 _d1 _d2", real=True)
PARAMS = Argument("p", "params", fields=(Field("a", (a,)), Field("b", (b,))))
X = Argument("x", "array", shape=(3, 1), symbols=x)
U = Argument("u", "array", shape=(1, 1), symbols=(u,))
# d0, d1 shared by f and g; d2 f's alone
DEFS = ((d0, a * sp.sin(x[0]) + x[1] ** 2), (d1, d0 * sp.cos(x[2]) + b / (1 + x[1] ** 2)),
        (d2, d1 * u))
F = FunctionSpec("f", "toy f", (PARAMS, X, U),
                 (Argument("y", "array", shape=(2, 1), exprs=(d2 + d0, d1 - u)),),
                 definitions=DEFS, shares="grp")
G = FunctionSpec("g", "toy g", (PARAMS, X),
                 (Argument("z", "array", shape=(1, 1), exprs=(d0 * d1 + x[2],)),),
                 definitions=DEFS[:2], shares="grp")


def _written_out(spec: FunctionSpec) -> list[sp.Expr]:
    subs: dict[sp.Symbol, sp.Expr] = {}
    for sym, e in spec.definitions:
        subs[sym] = e.xreplace(subs)
    return [e.xreplace(subs) for arg in spec.outputs for e in arg.exprs]


def test_the_group_shares_what_both_read() -> None:
    helper, calls = share([F, G], "grp")
    assert helper.symbols == (d0, d1)
    assert [a.name for a in helper.spec.inputs] == ["p", "x"]  # the common leading inputs
    assert all(c.quantities is helper for c in calls)


def test_a_group_without_common_inputs_is_refused() -> None:
    lone = FunctionSpec("h", "", (X, PARAMS), G.outputs, definitions=DEFS[:2], shares="grp")
    with pytest.raises(ValueError, match="do not all take first"):
        share([F, lone], "grp")


@pytest.fixture(scope="module")
def module(tmp_path_factory: pytest.TempPathFactory) -> tuple[str, object]:
    functions = with_shared((function_ir(F), function_ir(G)))
    files = render_all_ir({MODULE: list(functions)})
    directory = tmp_path_factory.mktemp("shared")
    for name, text in files.items():
        (directory / name).write_text(text)
    lib = cbuild.build_library([directory / f"{MODULE}.c"], directory / "libshared.so",
                               c_backend.cdef([F, G]), flags=C_FLAGS,
                               include_dirs=[directory])
    return files[f"{MODULE}.c"], lib


def test_the_shared_arithmetic_is_printed_once(module: tuple[str, object]) -> None:
    text, _ = module
    assert len(re.findall(r"^WMR_SHARED_INLINE void wmr_grp\(", text, re.M)) == 1
    assert text.count("WMR_SIN(") + text.count("wmr_sin(") == 1, "sin(x0) printed twice"
    bodies = re.split(r"\n(?=\S.*\bwmr_[fg]\()", text)
    for name in ("wmr_f(", "wmr_g("):
        body = next(t for t in bodies if name in t.splitlines()[0])
        assert "wmr_grp(p, x, _shared);" in body, name


def test_each_member_equals_its_expressions(module: tuple[str, object]) -> None:
    _, lib = module
    ffi, c = lib.ffi, lib.lib  # type: ignore[attr-defined]
    rng = random.Random(51)
    for spec, fn in ((F, c.wmr_f), (G, c.wmr_g)):
        exact = _written_out(spec)
        for _ in range(20):
            values = {s: rng.uniform(-2.0, 2.0) for s in (a, b, *x, u)}
            p = ffi.new("wmr_params_t *", {"a": values[a], "b": values[b]})
            args = [p, ffi.new("wmr_real_t[3]", [values[s] for s in x])]
            if spec is F:
                args.append(ffi.new("wmr_real_t[1]", [values[u]]))
            out = ffi.new(f"wmr_real_t[{len(exact)}]")
            fn(*args, out)
            for k, e in enumerate(exact):
                ref = float(e.evalf(30, subs=values))
                assert abs(out[k] - ref) <= 1e-12 * max(1.0, abs(ref)), (spec.name, k)


def test_the_certifier_reads_the_whole_evaluation() -> None:
    """A member's program holds the helper's operations (the sin is there), and its
    outputs are the member's own."""
    (f_ir, _) = with_shared((function_ir(F), function_ir(G)))
    prog = program_of(f_ir, CConfig())
    assert any(n.op == "call" and n.name == "sin" for n in prog.nodes)
    assert len(prog.outputs) == 2


def test_without_a_group_there_is_no_helper() -> None:
    """Without a group, the same specs print no helper (the default is unchanged)."""
    plain = [function_ir(FunctionSpec(s.name, s.doc, s.inputs, s.outputs,
                                      definitions=s.definitions)) for s in (F, G)]
    text = render_all_ir({MODULE: plain})[f"{MODULE}.c"]
    assert "static void" not in text and "wmr_grp" not in text
    assert "SHARED_INLINE" not in text
