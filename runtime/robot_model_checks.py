"""Checks of a robot's nominal model against the robot it controls, from generated code.

* The TDE condition of (17): ‖M(q)⁻¹ M̂(q) − I‖₂ < 1 for TDC and TDROC, over a box of
  parameter errors and over an experiment's payload schedule.
* ROC's bounds α = max ‖M⁻¹ M̂ − I‖₂ and φ = max ‖M⁻¹ (H − Ĥ)‖ over the box above nominal
  (the paper's "30 % above nominal").

M and H are the generated minimal form (M̄, H̄ in the driven-wheel rates) or, where the
robot has it, the paper formulation's reduced form; configurations are sampled (heading,
and every other body's yaw within ±1 rad of the root's), so the maxima are sampled maxima.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from runtime.closed_loop import velocities
from runtime.generated_modules import RobotCode
from runtime.robot_scale import inertial_keys

Array = NDArray[np.float64]


def _box(code: RobotCode, nominal: dict[str, float], uncertainty: float, symmetric: bool,
         rng: np.random.Generator, count: int = 64) -> list[dict[str, float]]:
    """Corners of the box where each inertial parameter is nominal·(1 ± uncertainty)
    (``symmetric``) or nominal·(1 + {0, uncertainty}): all low, all high, and random ones."""
    keys = list(inertial_keys(code, nominal))
    low = -uncertainty if symmetric else 0.0
    corners = [np.full(len(keys), low), np.full(len(keys), uncertainty)]
    corners += [rng.choice([low, uncertainty], size=len(keys)) for _ in range(count - 2)]
    return [{**nominal, **{k: nominal[k] * (1 + f) for k, f in zip(keys, c, strict=True)}}
            for c in corners]


def sample_q(code: RobotCode, rng: np.random.Generator) -> Array:
    q = np.zeros(code.nq)
    q[2] = rng.uniform(-math.pi, math.pi)
    for i in code.dependent[3:]:
        q[i] = q[2] + rng.uniform(-1.0, 1.0)  # body yaws within ±1 rad of the root's
    return q


def mass_and_bias(code: RobotCode, formulation: str, q: Array, eta: Array,
                   p: dict[str, float]) -> tuple[Array, Array]:
    m = code.model
    if formulation == "paper":
        return m.mass_matrix(q, p), m.bias_forces(q, velocities(code, q, eta, p), p)
    return m.minimal_mass_matrix(q, p), m.minimal_bias_forces(q, eta, p)


@dataclass(frozen=True)
class ModelBounds:
    """Over the uncertainty box: the TDE condition's max ‖M⁻¹ M̂ − I‖₂ (symmetric box,
    must be < 1 for TDC/TDROC) and ROC's (α, φ) (box above nominal, as the paper's 30 %)."""

    tde: float
    alpha: float
    phi: float


def model_bounds(code: RobotCode, nominal: dict[str, float], uncertainty: float,
                 formulation: str, max_rate: float = 8.0, seed: int = 7) -> ModelBounds:
    """Sampled over headings, body yaws, wheel rates up to ``max_rate`` and box corners."""
    rng = np.random.default_rng(seed)
    tde = alpha = phi = 0.0
    sym = _box(code, nominal, uncertainty, True, rng)
    above = _box(code, nominal, uncertainty, False, rng)
    for _ in range(6):
        q = sample_q(code, rng)
        etas = rng.uniform(-max_rate, max_rate, size=(3, code.nu))
        m_hat = mass_and_bias(code, formulation, q, etas[0], nominal)[0]
        biases = [mass_and_bias(code, formulation, q, e, nominal)[1] for e in etas]
        eye = np.eye(len(m_hat))
        for p in sym:
            inv = np.linalg.inv(mass_and_bias(code, formulation, q, etas[0], p)[0])
            tde = max(tde, float(np.linalg.norm(inv @ m_hat - eye, 2)))
        for p in above:
            inv = np.linalg.inv(mass_and_bias(code, formulation, q, etas[0], p)[0])
            alpha = max(alpha, float(np.linalg.norm(inv @ m_hat - eye, 2)))
            for e, h_hat in zip(etas, biases, strict=True):
                dh = mass_and_bias(code, formulation, q, e, p)[1] - h_hat
                phi = max(phi, float(np.linalg.norm(inv @ dh)))
    return ModelBounds(tde, alpha, phi)


def schedule_tde(code: RobotCode, nominal: dict[str, float],
                 loaded: Sequence[dict[str, float]], formulation: str, seed: int = 11) -> float:
    """max ‖M(q)⁻¹ M̂(q) − I‖₂ between the nominal model and each of the simulated robot's
    parameter sets ``loaded`` (e.g. with its payloads), over sampled configurations."""
    rng = np.random.default_rng(seed)
    eta = np.zeros(code.nu)
    worst = 0.0
    for _ in range(12):
        q = sample_q(code, rng)
        m_hat = mass_and_bias(code, formulation, q, eta, nominal)[0]
        for p in loaded:
            m = mass_and_bias(code, formulation, q, eta, p)[0]
            gap = np.linalg.solve(m, m_hat) - np.eye(len(m))
            worst = max(worst, float(np.linalg.norm(gap, 2)))
    return worst
