"""How far an implementation is from the reference, and how far it may be.

Deviation of a quantity: max over samples of ‖x − x_ref‖∞ / max(‖x_ref‖∞, 10⁻³·S), S the
largest ‖x_ref‖∞ of the sequence. Tolerances: :data:`DOUBLE_TOL` for the double
implementations, :data:`FLOAT32_TOL` for float32 (compared on float32-rounded inputs, see
:func:`f32`). Also the ``--perturb`` scaling of parameters (:func:`perturbed`) and a
controller's per-step outputs (:class:`Trace`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

DOUBLE_TOL = 1e-9
#: float32 tolerance. Unit roundoff u = 2⁻²⁴ ≈ 6.0e-8. Each generated output is a
#: straight-line expression of at most ~200 operations, so a few tens of u is the normal
#: normwise error; cancellation (θ̇_r² − θ̇_l² in H, Ĥ1 = u(t−h) − M̂ q̈ in (17), Ω(i) − Ω(i+1)
#: in (25), the sum in (16)) is amplified at most 10³× by the 10⁻³·S floor of the metric, so
#: rounding alone stays below ~10³ u ≈ 6e-5 (observed: ≤ 4e-6). 1e-4 (≈ 1700 u) therefore
#: separates rounding from a real difference (a 1 % parameter error gives > 1e-3).
FLOAT32_TOL = 1e-4
#: Floor of the metric (× S): below it values are compared in absolute terms.
FLOOR = 1e-3
#: float32 against the generated NumPy of any robot (no hand-written reference): relative
#: to max(‖x_ref‖∞, 10⁻²·S), bound 1e-3. A described robot's expressions are far longer than
#: the paper's (the trailer: up to ~4000 operations after CSE against ≤ 200) and some cancel
#: (its minimal bias forces H̄: a normwise float32 error up to 5e-6·S ≈ 90 u, measured over
#: 10⁴ random states, where the paper's stay near a few u), so the paper's 10⁻³ floor would
#: amplify rounding to ~1e-3. With the floor at 10⁻²·S rounding stays ≤ 5e-4 (≤ 1e-4 in the
#: controller steps); 1e-3 still separates it from a real difference (a 1 % parameter error
#: gives ~1e-2) and from the float32-only defects (a double function, an overflow: O(1)).
GENERATED_FLOAT32_TOL = 1e-3
GENERATED_FLOAT32_FLOOR = 1e-2
IMPLS = ("python", "c64", "casadi", "c32")
FUNCTION_IMPLS = ("c64", "c32", "casadi")  # against the generated NumPy
CONTROLLER_IMPLS = ("c64", "c32")  # against the generated Python controller classes
IMPL_TITLES = {"python": "gen-python", "c64": "C double", "casadi": "CasADi", "c32": "C float32"}
Arr = NDArray[np.float64]
Params = dict[str, float]


def f32(x: Any) -> Any:
    """Round to float32 (returned as float64 / float)."""
    if isinstance(x, float | int):
        return float(np.float32(x))
    return np.asarray(x, dtype=np.float64).astype(np.float32).astype(np.float64)


def f32_params(p: Mapping[str, float]) -> Params:
    return {k: f32(float(v)) for k, v in p.items()}


@dataclass
class Deviation:
    """Largest deviation of one implementation, over samples and quantities."""

    value: float = 0.0
    worst: str = ""
    floor: float = FLOOR

    def add(self, name: str, got: Sequence[Any], ref: Sequence[Any]) -> None:
        """Per-sample normwise relative deviation of quantity ``name``."""
        g = [np.atleast_1d(np.asarray(x, dtype=np.float64)).ravel() for x in got]
        r = [np.atleast_1d(np.asarray(x, dtype=np.float64)).ravel() for x in ref]
        if len(g) != len(r):
            raise ValueError(f"{name}: {len(g)} samples against {len(r)}")
        if not r:
            return
        scale = max(float(np.max(np.abs(x))) if x.size else 0.0 for x in r)
        floor = max(self.floor * scale, 1e-300)
        dev = 0.0
        for a, b in zip(g, r, strict=True):
            if a.shape != b.shape:
                dev = math.inf
                break
            err = float(np.max(np.abs(a - b))) if a.size else 0.0
            if not math.isfinite(err):
                dev = math.inf
                break
            dev = max(dev, err / max(float(np.max(np.abs(b))), floor))
        self.merge(dev, name)

    def merge(self, value: float, name: str) -> None:
        if value > self.value or (math.isnan(value)):
            self.value, self.worst = value, name


@dataclass
class Row:
    name: str
    cells: dict[str, Deviation] = field(default_factory=dict)


@dataclass
class Trace:
    """Per-step outputs of one controller implementation."""

    tau: list[Arr] = field(default_factory=list)
    gain: list[float] = field(default_factory=list)
    s_norm: list[float] = field(default_factory=list)
    H1hat: list[Arr] = field(default_factory=list)
    u_discarded: list[float] = field(default_factory=list)
    saturated: list[bool] = field(default_factory=list)

    def record(
        self, tau: Any, gain: float, s_norm: float, h1: Any, u_disc: float, sat: bool
    ) -> None:
        self.tau.append(np.array(tau, dtype=np.float64))
        self.gain.append(float(gain))
        self.s_norm.append(float(s_norm))
        self.H1hat.append(np.array(h1, dtype=np.float64))
        self.u_discarded.append(float(u_disc))
        self.saturated.append(bool(sat))


def perturbed(
    p: Mapping[str, float], impl: str, perturb: Mapping[str, Mapping[str, float]]
) -> Params:
    """``p`` with the ``--perturb`` factors of ``impl`` applied (keys ``p`` has)."""
    out = {k: float(v) for k, v in p.items()}
    for key, factor in perturb.get(impl, {}).items():
        if key in out:
            out[key] *= factor
    return out


def tolerance(impl: str) -> float:
    """Bound of ``impl`` against the hand-written reference."""
    return FLOAT32_TOL if impl == "c32" else DOUBLE_TOL


def generated_tolerance(impl: str) -> float:
    """Bound of ``impl`` against the generated NumPy (any robot)."""
    return GENERATED_FLOAT32_TOL if impl == "c32" else DOUBLE_TOL


def generated_deviation(impl: str) -> Deviation:
    """An empty deviation of ``impl`` against the generated NumPy (float32: floor 10⁻²·S)."""
    return Deviation(floor=GENERATED_FLOAT32_FLOOR if impl == "c32" else FLOOR)
