"""Shared numeric views of the symbolic WMR model (lambdified once per session), and the
order in which ``make test`` hands the test files to its workers.

Every function takes (q, qdot, qddot, tau, p) with p = (m, I, K, K_lat, I_w, r, b, d) in the
order of ``wmr.PLANT_SYMBOLS``; arguments an expression does not use are ignored.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import sympy as sp

from modeling.robot_file import load_robot
from modeling.robots.drishti import model as wmr

# The test files that take longest (per-test durations of a full `make test`, summed per
# file), longest first. `make test` runs one file per worker (--dist loadfile) on two
# workers: these start first, so that neither worker is left running one of them alone at
# the end while the other has nothing to do. pytest-xdist's own order (--loadscope-reorder,
# its default: most tests first) put the two-test tutorial, minutes long, last.
LONGEST_FILES = (
    "codegen/test_codegen_cli.py",
    "docs/test_tutorial.py",
    "firmware/test_misra.py",
    "runtime/test_bench.py",
    "firmware/test_frozen_config.py",
    "runtime/test_audit_warnings_travel.py",
    "robot_files/test_public_pipeline.py",
    "runtime/test_cli.py",
    "generated/test_any_robot_pipeline.py",
    "derivation/test_description_trailer.py",
)


def pytest_configure(config: pytest.Config) -> None:
    if hasattr(config.option, "loadscopereorder"):  # pytest-xdist is loaded
        config.option.loadscopereorder = False  # the collection's order, as sorted below


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """The longest files first (:data:`LONGEST_FILES`), every other file after them in the
    collection's order; the tests of a file keep theirs (a stable sort)."""
    rank = {name: i for i, name in enumerate(LONGEST_FILES)}
    here = Path(__file__).parent

    def key(item: pytest.Item) -> int:
        try:
            return rank.get(item.path.relative_to(here).as_posix(), len(rank))
        except ValueError:  # a test outside tests/
            return len(rank)

    items.sort(key=key)


ARGS = (wmr.q, wmr.qdot, wmr.qddot, tuple(wmr.tau), wmr.PLANT_SYMBOLS)
NumFn = Callable[..., np.ndarray]


def numeric(expr: sp.Expr | sp.MatrixBase) -> NumFn:
    """f(q, qdot, qddot, tau, p) -> float or 2-D array."""
    f = sp.lambdify(ARGS, expr, "numpy", cse=True)

    def call(q, qd=(0.0,) * 5, qdd=(0.0,) * 5, tau=(0.0, 0.0), p=None):  # type: ignore[no-untyped-def]
        assert p is not None
        return np.asarray(f(q, qd, qdd, tau, p), dtype=float)

    return call


class NumericWMR:
    """Lambdified pieces of ``wmr.wmr_system(lateral_moment)``."""

    def __init__(self, lateral_moment: bool) -> None:
        s = wmr.wmr_system(lateral_moment)
        self.system = s
        self.M = numeric(s.mass_matrix)
        self.H = numeric(s.bias)
        self.A = numeric(s.constraint_matrix)
        self.Adot_qdot = numeric(s.constraint_rate_term)
        self.B = numeric(s.input_matrix)
        self.S = numeric(s.null_space)
        self.Sdot_eta = numeric(s.null_space_rate)
        self.M_red = numeric(s.reduced_mass_matrix)
        self.H_red = numeric(s.reduced_bias)
        self.M_red_inv = numeric(s.reduced_mass_matrix_inverse)
        self.M_min = numeric(s.minimal_mass_matrix)
        self.H_min = numeric(s.minimal_bias)
        self.B_min = numeric(s.minimal_input_matrix)
        self.eta_dot = numeric(s.minimal_forward_dynamics(wmr.tau))
        self.qdd_red = numeric(s.reduced_forward_dynamics(wmr.tau))
        # λ(q, q̇, η̇, τ): η̇ is read from qddot[3:5].
        self.multipliers = numeric(s.multipliers_given_accelerations(wmr.tau))
        lhs, rhs = s.kkt_matrix()
        self.kkt_lhs = numeric(lhs)
        self.kkt_rhs = numeric(rhs)
        self.T = numeric(s.kinetic_energy)

    def qdot_on_manifold(self, q: np.ndarray, eta: np.ndarray, p: np.ndarray) -> np.ndarray:
        return (self.S(q, p=p) @ eta).ravel()

    def kkt_solve(
        self, q: np.ndarray, qd: np.ndarray, tau: np.ndarray, p: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """(q̈, λ) from [[M, Aᵀ], [A, 0]] [q̈; λ] = [B τ − H; −Ȧ q̇]."""
        lhs = self.kkt_lhs(q, qd, p=p)
        rhs = self.kkt_rhs(q, qd, p=p).ravel()
        rhs[:5] += (self.B(q, p=p) @ tau).ravel()
        sol = np.linalg.solve(lhs, rhs)
        return sol[:5], sol[5:]


@cache
def numeric_wmr(lateral_moment: bool) -> NumericWMR:
    return NumericWMR(lateral_moment)


def drishti_params() -> np.ndarray:
    """(m, I, K, K_lat, I_w, r, b, d) of Drishti from the packaged robot file."""
    p = load_robot().lumped
    return np.array([p["m"], p["I"], p["K"], 0.0, p["Iw"], p["r"], p["b"], p["d"]])


@pytest.fixture(scope="session")
def paper_model() -> NumericWMR:
    return numeric_wmr(False)


@pytest.fixture(scope="session")
def lateral_model() -> NumericWMR:
    return numeric_wmr(True)


@pytest.fixture(scope="session")
def drishti() -> np.ndarray:
    return drishti_params()


@pytest.fixture(scope="session")
def c_builds(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The generated C compiled with the strict flags in both precisions (see
    ``generated_code_support.build_generated_c``), shared by
    ``tests/generated/test_generated_*.py``."""
    from generated_code_support import build_generated_c

    return build_generated_c(tmp_path_factory)
