"""Timings measured from Python: the forward dynamics in the generated Python, hand-written
NumPy, ``sympy.lambdify`` and ``casadi.Function``; and cold-start wall times of the
derivation, ``python -m codegen`` and ``python -m runtime reproduce``.
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import tempfile
import time
import timeit
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from codegen.backends.casadi import to_casadi
from runtime.tooling.bench.c_bench import spread
from runtime.tooling.bench.c_variants import specs_by_name

ROOT = Path(__file__).resolve().parents[3]  # the repository


def python_bench(number: int) -> list[dict[str, Any]]:
    """Generated Python vs hand-written NumPy (if present), sympy.lambdify and CasADi."""
    import casadi as ca
    import sympy as sp

    from runtime.bindings.generated import robot, wmr_model

    p = dict(robot.PARAMS)
    rng = np.random.default_rng(0)
    q = rng.uniform(-1, 1, 5)
    qdot = rng.uniform(-1, 1, 5)
    tau = rng.uniform(-1, 1, 2)
    specs = specs_by_name()
    fd = specs["forward_dynamics"]
    syms = fd.input_symbols()
    lam = sp.lambdify(syms, [e for a in fd.outputs for e in a.exprs], "numpy")
    pvec = [p[k] for k in ("m", "I", "K", "Iw", "r", "b", "d")]
    flat = [*pvec, *q, *qdot, *tau]
    f_ca = to_casadi(fd)
    cases: dict[str, Callable[[], object]] = {
        "ours (generated Python)": lambda: wmr_model.forward_dynamics(q, qdot, tau, p),
        "sympy.lambdify": lambda: lam(*flat),
        "casadi.Function": lambda: f_ca(ca.DM(pvec), ca.DM(q), ca.DM(qdot), ca.DM(tau)),
    }
    try:
        from runtime.tooling.witness import model as hand

        cases["hand-written NumPy"] = lambda: hand.forward_dynamics(q, qdot, tau, p)
    except (ImportError, AttributeError):
        pass
    rows = []
    for label, fn in cases.items():
        times = timeit.repeat(fn, number=number, repeat=5)
        per = [t / number * 1e6 for t in times]
        rows.append(
            {
                "function": "forward_dynamics",
                "variant": label,
                "us": spread(per),
            }
        )
    return rows


DERIVATION_SNIPPET = """
import time
t0 = time.perf_counter()
from modeling.robots.drishti import model as wmr
s = wmr.wmr_system()
for name in ("mass_matrix", "bias", "null_space", "null_space_rate", "reduced_mass_matrix",
             "reduced_bias", "minimal_mass_matrix", "minimal_bias", "reduced_mass_matrix_inverse"):
    getattr(s, name)
s.multipliers_given_accelerations(wmr.tau)
s.reduced_forward_dynamics(wmr.tau)
wmr.lumped_relations(wmr.physical_bodies())
print(time.perf_counter() - t0)
"""


def toolchain_times() -> dict[str, float]:
    """Cold-start wall times in fresh interpreters (median of 3 for the derivation)."""
    runs = [
        float(
            subprocess.run(
                [sys.executable, "-c", DERIVATION_SNIPPET],
                check=True,
                capture_output=True,
                text=True,
                cwd=ROOT,
            ).stdout
        )
        for _ in range(3)
    ]
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        subprocess.run(
            [sys.executable, "-m", "codegen", "--out", tmp],
            check=True,
            capture_output=True,
            cwd=ROOT,
        )
        model = time.perf_counter() - t0
        t0 = time.perf_counter()
        subprocess.run(
            [sys.executable, "-m", "runtime", "reproduce", "--out", tmp + "/r"],
            check=True,
            capture_output=True,
            cwd=ROOT,
        )
        rep = time.perf_counter() - t0
    return {"derivation_s": statistics.median(runs), "make_model_s": model, "reproduce_s": rep}
