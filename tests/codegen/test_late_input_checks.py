"""Late input checks of a checked function (codegen/backends/c/deferred.py): an input that
+, -, *, sin and cos carry to a result is tested only when a guard or the finite-output
check fails, and the function returns what checking every input first returns.

* which inputs qualify, on expressions: a divisor, an exponential or a comparison may
  turn an infinity into a finite value, so an input reaching the results only through
  one of them is checked first;
* on a toy spec rendered to C in both precisions: the function with late checks against
  the same function with every input checked first (the same arithmetic), at random
  inputs with NaN and infinities in every input, parameters included, bad parameters and
  overflows: the same status and the same bits; and the printed checks are where the
  analysis says;
* ``wmr_forward_dynamics``'s checks: only b, which reaches the results through 1/b alone,
  is tested before the arithmetic; the others in one helper that each failing check calls.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import sympy as sp

from codegen.backends import c as c_backend
from codegen.backends.c import lowering
from codegen.backends.c.config import CConfig, StatusCode
from codegen.backends.c.deferred import carried, late_inputs
from runtime.bindings import cbuild
from runtime.bindings.cbuild import GENERATED_C

a, c, x, t, u = sp.symbols("a c x t u", real=True)
T0, T1 = sp.symbols("_t0 _t1", real=True)
STRICT = ("-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Wshadow", "-Wdouble-promotion",
          "-Wfloat-equal", "-Wconversion", "-Werror", "-O2")
STATUS = (StatusCode("WMR_OK", 0, "ok"), StatusCode("WMR_ERR_NONFINITE_INPUT", -2, ""),
          StatusCode("WMR_ERR_BAD_PARAMS", -3, ""),
          StatusCode("WMR_ERR_NONFINITE_OUTPUT", -4, ""),
          StatusCode("WMR_ERR_NOT_INITIALISED", -15, ""))


def test_carried_follows_sums_products_powers_sin_cos_only() -> None:
    assert carried(a * x + sp.sin(t) * c) == {a, x, t, c}
    assert carried(x / a) == {x}  # a divisor: 1/inf is 0
    assert carried(x**2 + sp.cos(u) ** 3) == {x, u}
    assert carried(x ** sp.Rational(1, 2)) == set()
    assert carried(sp.exp(x) + sp.atan(t) + sp.Abs(u)) == set()
    assert carried(sp.Piecewise((x, a > 0), (c, True))) == set()
    assert carried(sp.Integer(3)) == set()


def test_late_inputs_follow_temporaries_back_from_the_results() -> None:
    temps = [(T0, 1 / a), (T1, T0 * x + c)]
    # x and c reach the result through T1; a only through 1/a; u through exp
    assert late_inputs([a, c, x, u], temps, [T1 * sp.sin(t) + sp.exp(u)]) == {c, x}
    assert late_inputs([a, c, x, t], temps, [T0]) == set()
    assert late_inputs([x], temps, []) == set()


def _toy_spec() -> Any:
    """Parameters a (reaching the results only as a divisor: checked first) and c (a
    factor: late), state x and t (late, t through sin and cos) and u (only under a
    divisor: checked first); a parameter guard and a state guard."""
    from codegen.spec import Argument, Field, FunctionSpec, Guard

    params = Argument("p", "params", fields=(Field("a", (a,)), Field("c", (c,))))
    state = Argument("s", "array", (3, 1), (x, t, u))
    outputs = (Argument("y", "array", (3, 1), exprs=(
        c * x / a + sp.sin(t) * c,
        x**2 / (a**2 + 1) + sp.cos(t) * x,
        1 / (u**2 + 1) + c * x,
    )),)
    guards = (Guard("WMR_ERR_BAD_PARAMS", a, "a > 0"),
              Guard("WMR_ERR_BAD_PARAMS", c - x, "x < c"))
    return FunctionSpec("toy", "a toy", (params, state), outputs, returns_status=True,
                        guards=guards, nonfinite_input="WMR_ERR_NONFINITE_INPUT",
                        nonfinite_output="WMR_ERR_NONFINITE_OUTPUT", prepared=True)


def _toy_c(tmp: Path, late: bool) -> dict[str, str]:
    """The toy's files in ``tmp``; without ``late``, every input is checked first."""
    config = CConfig(status_codes=STATUS)
    with pytest.MonkeyPatch.context() as mp:
        if not late:
            mp.setattr(lowering, "late_inputs", lambda *_: frozenset())
        files = c_backend.render([_toy_spec()], "wmr_toy", config)
    files.update(c_backend.render_types([_toy_spec()], config))
    tmp.mkdir()
    for name, text in files.items():
        (tmp / name).write_text(text)
    return files


def _function(c_text: str) -> str:
    return c_text.split("wmr_toy(const", 1)[1].split("\n}\n", 1)[0]


def test_toy_with_late_checks_returns_what_checking_first_returns(tmp_path: Path) -> None:
    late_c = _function(_toy_c(tmp_path / "late", True)["wmr_toy.c"])
    first_c = _function(_toy_c(tmp_path / "first", False)["wmr_toy.c"])
    up_front = re.search(r"\n    if \(\(\((.*?)\) & WMR_EXP_CARRY_TOP", late_c, re.S)
    assert up_front is not None and re.findall(r"exp_carry\((\w+)\)", up_front.group(1)) == [
        "a", "u"]
    assert "an input not checked yet" in late_c and "not checked yet" not in first_c
    libs = {}
    for tag in ("late", "first"):
        for float32 in (False, True):
            d = tmp_path / tag
            libs[tag, float32] = cbuild.build_library(
                [d / "wmr_toy.c"], d / f"libtoy{int(float32)}.so",
                cbuild.declarations(float32, ("wmr_types.h", "wmr_toy.h"), c_dir=d),
                float32=float32, flags=[*STRICT, *(["-DWMR_FLOAT32"] if float32 else [])],
                include_dirs=[d])
    rng = np.random.default_rng(52)
    special = [math.nan, math.inf, -math.inf]
    for float32 in (False, True):
        huge = 1e30 if float32 else 1e200
        seen = set()
        for _ in range(1500):
            v = [rng.uniform(-1, 3), rng.uniform(-2, 4), rng.uniform(-3, 3),
                 rng.uniform(-4, 4), rng.uniform(-3, 3)]
            for k in range(5):  # each input may be NaN, infinite or huge
                roll = rng.uniform()
                if roll < 0.08:
                    v[k] = special[rng.integers(3)]
                elif roll < 0.12:
                    v[k] = huge * (1 if rng.uniform() < 0.5 else -1)
            got = []
            for tag in ("late", "first"):
                lib = libs[tag, float32]
                ffi = lib.ffi
                out = ffi.new("wmr_real_t[3]", [7.0] * 3)
                status = lib.lib.wmr_toy(ffi.new("wmr_params_t *", {"a": v[0], "c": v[1]}),
                                         ffi.new("wmr_real_t[]", v[2:]), out)
                got.append((int(status), [float(o).hex() for o in out]))
            assert got[0] == got[1], (float32, v, got)
            seen.add(got[0][0])
        # OK, a non-finite input, a guard, an overflow: every status was reached
        assert seen == {0, -2, -3, -4}


def test_drishti_forward_dynamics_checks_b_first_and_the_rest_late() -> None:
    text = (GENERATED_C / "wmr_model.c").read_text()
    body = text.split("wmr_status_t wmr_forward_dynamics(", 1)[1].split("\n}\n", 1)[0]
    first = body.split("WMR_ERR_NONFINITE_INPUT", 1)[0]
    assert re.findall(r"exp_carry\((\w+)\)", first) == ["b"]
    # the others in one helper, which each failing check calls (one copy of the test)
    helper = text.split("wmr_forward_dynamics_late_inputs(const", 1)[1].split("\n}\n", 1)[0]
    late = re.findall(r"exp_carry\((\w+)\)", helper)
    assert sorted(late) == sorted(["m", "I", "K", "I_w", "r", "d", "theta", "thetadot_r",
                                   "thetadot_l", "tau_r", "tau_l"])
    assert body.count("wmr_forward_dynamics_late_inputs(p, q, qdot, tau) != WMR_OK") == 5
    # the sin and cos of the heading right after it is read, before the other inputs
    assert body.index("WMR_SIN(theta)") < body.index("qdot[3]")
