"""The generated C builds and runs: all generated .c files compile with the strict flags in
both precisions (the ``c_builds`` fixture); example_main runs and its final position error
is < 0.05 m; the float objects link no double libm function.
"""

from __future__ import annotations

import math
import re
import shutil
import subprocess
from pathlib import Path

import pytest
from generated_code_support import CBuild

DOUBLE_MATH = {
    "sin", "cos", "sincos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh",
    "exp", "log", "sqrt", "pow", "fabs", "fmax", "fmin",
}  # fmt: skip


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
