"""How the crosscheck calls the generated code that is not Python: a robot's C library
through cffi (double or float32, built by ``runtime.bindings.cbuild``, cached) and its CasADi
functions (``<target>/casadi/*.casadi``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from runtime.tooling.crosscheck.deviation import Arr
from runtime.tooling.crosscheck.targets import Target


@cache
def _c_library(c_dir: Path, prefix: str, float32: bool) -> Any:
    from runtime.bindings import cbuild

    return cbuild.build(float32, c_dir=c_dir, prefix=prefix)


def c_library(target: Target, float32: bool) -> Any:
    """The target's generated C built in double or float32 (a ``cbuild.CLibrary``)."""
    return _c_library(target.c_dir, target.prefix, float32)


@cache
def _casadi_function(path: Path) -> Any:
    import casadi

    return casadi.Function.load(str(path))


def casadi_function(target: Target, name: str) -> Any:
    return _casadi_function(target.casadi_dir / f"{name}.casadi")


def casadi_call(target: Target, name: str, *args: Any) -> list[Arr]:
    """Call a CasADi function with flat inputs (in its input order); flat outputs."""
    out = casadi_function(target, name).call(
        [np.asarray(a, dtype=np.float64).reshape(-1, 1) for a in args]
    )
    return [np.asarray(o, dtype=np.float64).ravel() for o in out]


def pvec(target: Target, p: Mapping[str, float]) -> Arr:
    """Nominal parameters as the CasADi ``p`` vector (the robot's PARAM_KEYS order)."""
    return np.array([float(p[k]) for k in target.code.controllers.PARAM_KEYS])


class CModel:
    """A robot's generated C functions through cffi (``<prefix>_<fn>``)."""

    def __init__(self, target: Target, float32: bool) -> None:
        self.target = target
        self.prefix = target.prefix
        self.lib = c_library(target, float32)
        self.ffi, self.c = self.lib.ffi, self.lib.lib
        self.field_names: Mapping[str, str] = target.code.controllers.C_FIELD_NAMES
        self.real = f"{self.prefix}_real_t"

    def arr(self, x: Any) -> Any:
        return self.ffi.new(f"{self.real}[]", [float(v) for v in np.asarray(x).ravel()])

    def out(self, n: int) -> Any:
        return self.ffi.new(f"{self.real}[]", n)

    def struct(self, ctype: str, values: Mapping[str, float]) -> Any:
        """A new C struct ``ctype`` (a parameter struct) from a mapping with Python keys."""
        from runtime.bindings import cbuild

        return cbuild.fill_params(self.ffi.new(f"{ctype} *"), values, self.field_names)

    def params(self, p: Mapping[str, float]) -> Any:
        keys = self.target.code.controllers.PARAM_KEYS
        return self.struct(f"{self.prefix}_params_t", {k: p[k] for k in keys})

    def read(self, buf: Any, n: int) -> Arr:
        return np.array([buf[i] for i in range(n)], dtype=np.float64)

    def prepared(self, p: Mapping[str, float]) -> Any:
        """``<prefix>_model_prepared_t`` filled by ``<prefix>_model_prepare`` from ``p``."""
        out = self.ffi.new(f"{self.prefix}_model_prepared_t *")
        status = getattr(self.c, f"{self.prefix}_model_prepare")(self.params(p), out)
        if status != 0:
            raise RuntimeError(f"{self.prefix}_model_prepare returned {status}")
        return out

    def call(self, fn: str, p: Mapping[str, float], args: Sequence[Any], n_out: int) -> Arr:
        """``<prefix>_<fn>(params, args..., out)`` with one output of ``n_out`` values; a
        ``<name>_prepared`` function gets the parameters prepared instead."""
        out = self.out(n_out)
        first = self.prepared(p) if fn.endswith("_prepared") else self.params(p)
        status = getattr(self.c, f"{self.prefix}_{fn}")(first, *map(self.arr, args), out)
        if status not in (None, 0):
            raise RuntimeError(f"{self.prefix}_{fn} returned {status}")
        return self.read(out, n_out)
