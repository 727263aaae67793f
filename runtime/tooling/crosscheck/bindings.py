"""How the crosscheck calls the generated code that is not Python: the C library through
cffi (double or float32, built by ``runtime.cbuild``, cached) and the CasADi functions
loaded from generated/casadi.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from runtime.handwritten import model as hw
from runtime.tooling.crosscheck.deviation import Arr

ROOT = Path(__file__).resolve().parents[3]  # the repository
CASADI_DIR = ROOT / "generated" / "casadi"
# accel_estimator codes of the generated configs (WMR_ACCEL_*).
ACCEL_CODES: dict[str, int] = {"backward": 0, "central": 1, "matched": 2}


@cache
def c_library(float32: bool) -> Any:
    from runtime import cbuild

    return cbuild.build(float32)


@cache
def casadi_function(name: str) -> Any:
    import casadi

    return casadi.Function.load(str(CASADI_DIR / f"{name}.casadi"))


def casadi_call(name: str, *args: Any) -> list[Arr]:
    out = casadi_function(name).call([np.asarray(a, dtype=np.float64).reshape(-1, 1) for a in args])
    return [np.asarray(o, dtype=np.float64).ravel() for o in out]


def pvec(p: Mapping[str, float]) -> Arr:
    return np.array([float(p[k]) for k in hw.PARAM_KEYS])


class CModel:
    """The generated model functions through cffi."""

    def __init__(self, float32: bool) -> None:
        self.lib = c_library(float32)
        self.ffi, self.c = self.lib.ffi, self.lib.lib

    def arr(self, x: Any) -> Any:
        return self.ffi.new("wmr_real_t[]", [float(v) for v in np.asarray(x).ravel()])

    def out(self, n: int) -> Any:
        return self.ffi.new("wmr_real_t[]", n)

    def params(self, p: Mapping[str, float]) -> Any:
        from runtime import cbuild

        return cbuild.fill_params(self.ffi.new("wmr_params_t *"), {k: p[k] for k in hw.PARAM_KEYS})

    def read(self, buf: Any, n: int) -> Arr:
        return np.array([buf[i] for i in range(n)], dtype=np.float64)

    def call(self, fn: str, p: Mapping[str, float], args: Sequence[Any], n_out: int) -> Arr:
        out = self.out(n_out)
        status = getattr(self.c, f"wmr_{fn}")(self.params(p), *map(self.arr, args), out)
        if status not in (None, 0):
            raise RuntimeError(f"wmr_{fn} returned {status}")
        return self.read(out, n_out)
