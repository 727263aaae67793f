"""The generated traction functions at extreme forces (issue 52), double and float32 C.

``wmr_traction_margins`` / ``wmr_traction_check`` return mu N_k - sqrt(Fx_k^2 + (s_k Fy)^2).
Squaring before scaling made a finite margin NONFINITE_OUTPUT for forces above
sqrt(REAL_MAX) (float32: 1.8e19 N) and, below sqrt(REAL_MIN) (1e-19 N), let the squares
vanish so that a negative margin read as grip. Checked here against exact rational
arithmetic: for every finite force, a margin whose true value is finite is returned finite
and with its sign; inputs outside the documented range (mu N_k in [1e-30, 1e30] N, shares
in [0, 1]) are refused with ``WMR_ERR_BAD_TRACTION``.
"""

from __future__ import annotations

import math
import struct
import sys
from fractions import Fraction
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from runtime.bindings import cbuild

FLT_MAX = struct.unpack("<f", bytes.fromhex("ffff7f7f"))[0]
REAL_MAX = {False: sys.float_info.max, True: FLT_MAX}
FRICTION_MIN, FRICTION_MAX = 1e-30, 1e30


@pytest.fixture(scope="module", params=[False, True], ids=["double", "float32"])
def lib(request: pytest.FixtureRequest) -> cbuild.CLibrary:
    return cbuild.build(bool(request.param))


def statuses(lib: cbuild.CLibrary) -> dict[str, int]:
    return {v: k for k, v in lib.ffi.typeof("wmr_status_t").elements.items()}


def call(lib: cbuild.CLibrary, fn: str, fx: list[float], fy: float, mu: float,
         loads: list[float], shares: list[float]) -> tuple[int, list[float]]:
    ffi = lib.ffi
    out = ffi.new("wmr_real_t[2]", [42.0, 42.0])
    status = getattr(lib.lib, f"wmr_{fn}")(
        ffi.new("wmr_real_t[2]", fx), ffi.new("wmr_real_t[1]", [fy]),
        ffi.new("wmr_real_t[1]", [mu]), ffi.new("wmr_real_t[2]", loads),
        ffi.new("wmr_real_t[2]", shares), out)
    return int(status), [float(x) for x in out]


def as_real(lib: cbuild.CLibrary, x: float) -> float:
    """x rounded to the build's real type."""
    return float(lib.ffi.cast("wmr_real_t", x))


def exact_sign(mu: float, load: float, fx: float, share: float, fy: float) -> int:
    """Sign of mu N - sqrt(Fx^2 + (s Fy)^2), exactly (mu N > 0: compare the squares)."""
    a = Fraction(mu) * Fraction(load)
    d = a * a - Fraction(fx) ** 2 - (Fraction(share) * Fraction(fy)) ** 2
    return (d > 0) - (d < 0)


# (fx, fy, mu, load, share, expected sign): forces beyond the squares' range, per precision.
EXTREMES = {
    True: [
        (3e19, 0.0, 1.0, 1e20, 1.0, 1),     # Fx^2 overflows float32, margin 7e19
        (3e19, 0.0, 1.0, 1e19, 1.0, -1),    # margin -2e19
        (0.0, 3e19, 0.5, 1e20, 0.8, 1),     # Fy^2 overflows
        (1e-23, 0.0, 1.0, 5e-24, 1.0, -1),  # Fx^2 = 1e-46 vanishes: grip reported
        (0.0, 2e-23, 1.0, 1e-23, 1.0, -1),  # Fy^2 vanishes
        (1e-21, 1e-21, 1.0, 1.5e-21, 1.0, 1),  # squares subnormal, sum loses digits
    ],
    False: [
        (3e160, 0.0, 1.0, 1e30, 1.0, -1),   # Fx^2 overflows double, margin -3e160
        (0.0, 2e155, 0.9, 1e29, 1.0, -1),
        (1e-170, 1e-170, 1.0, 1e-30, 1.0, 1),  # squares vanish; mu N at its floor decides
    ],
}


def test_extreme_forces_give_a_finite_margin_of_the_right_sign(lib: cbuild.CLibrary) -> None:
    codes = statuses(lib)
    for fx, fy, mu, load, share, sign in EXTREMES[lib.float32]:
        args = ([fx, 0.0], fy, mu, [load, 1.0], [share, 0.0])
        status, margins = call(lib, "traction_margins", *args)
        assert status == codes["WMR_OK"], (args, status)
        assert math.isfinite(margins[0]), (args, margins)
        assert (margins[0] > 0) - (margins[0] < 0) == sign, (args, margins)
        assert exact_sign(*(as_real(lib, v) for v in (mu, load, fx, share, fy))) == sign
        status, _ = call(lib, "traction_check", *args)
        assert status == codes["WMR_OK" if sign > 0 else "WMR_WARN_TRACTION"], (args, status)


def test_a_friction_budget_or_share_outside_the_range_is_refused(lib: cbuild.CLibrary) -> None:
    bad = statuses(lib)["WMR_ERR_BAD_TRACTION"]
    for mu, load, share in ((1e-20, 1e-20, 0.5), (1e20, 1e20, 0.5), (0.5, 100.0, 1.5),
                            (0.5, 100.0, -0.1)):
        for fn in ("traction_margins", "traction_check"):
            status, out = call(lib, fn, [1.0, 1.0], 1.0, mu, [load, load], [share, share])
            assert status == bad and out == [42.0, 42.0], (fn, mu, load, share, status)


def finite(lib: cbuild.CLibrary) -> Any:
    width = 32 if lib.float32 else 64
    return st.floats(allow_nan=False, allow_infinity=False, width=width)


def test_every_finite_force_gives_the_true_margins_sign(lib: cbuild.CLibrary) -> None:
    """Property: random finite forces (any magnitude), mu N_k anywhere in the documented
    range, shares in [0, 1]: a margin whose true value is finite is returned finite, with
    the exact sign wherever the true margin is not within a few roundings of zero."""
    codes = statuses(lib)
    real_max = REAL_MAX[lib.float32]
    width = 32 if lib.float32 else 64
    budget = st.floats(as_real(lib, FRICTION_MIN * 1.01), as_real(lib, FRICTION_MAX * 0.99),
                       width=width)
    unit = st.floats(0.0, 1.0, width=width)
    eps = 1e-5 if lib.float32 else 1e-13

    @settings(max_examples=400, deadline=None, derandomize=True, database=None,
              suppress_health_check=[HealthCheck.too_slow])
    @given(fx=finite(lib), fy=finite(lib), a=budget, share=unit,
           scale=st.sampled_from([1.0, 1e-20, 1e20, 1e-150, 1e150]))
    def prop(fx: float, fy: float, a: float, share: float, scale: float) -> None:
        fx, fy = as_real(lib, fx * scale), as_real(lib, fy * scale)
        if not (math.isfinite(fx) and math.isfinite(fy)):
            return
        mu, load = 1.0, a
        status, margins = call(lib, "traction_margins", [fx, 0.0], fy, mu, [load, 1.0],
                               [share, 0.0])
        true = Fraction(load) - Fraction(math.hypot(fx, share * fy)) \
            if math.isfinite(math.hypot(fx, share * fy)) else None
        if true is not None and abs(true) < Fraction(real_max) * Fraction(99, 100):
            assert status == codes["WMR_OK"], (fx, fy, load, share, status)
        if status != codes["WMR_OK"]:
            assert status == codes["WMR_ERR_NONFINITE_OUTPUT"]
            return
        m = margins[0]
        assert math.isfinite(m)
        sign = exact_sign(mu, load, fx, share, fy)
        gap = abs(Fraction(load) ** 2 - Fraction(fx) ** 2 - (Fraction(share) * Fraction(fy)) ** 2)
        if gap > Fraction(eps) * Fraction(load) ** 2:
            assert (m > 0) - (m < 0) == sign, (fx, fy, load, share, m)

    prop()
