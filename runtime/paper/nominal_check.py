"""The time-delay estimation condition ‖M⁻¹ M̂ − I‖ < 1 over a parameter box.

TDC and TDROC estimate the unknown dynamics from the last sample (17); the estimate
converges only if the nominal inertia M̂ is not too far from the true M: ‖M⁻¹ M̂ − I‖₂ < 1
(Roy et al. 2017, the condition under (17); :func:`roc_bounds` computes the same α, and
φ, for ROC's bound over the box above nominal). :func:`check_nominal` evaluates

    α = max ‖M(p)⁻¹ M̂ − I‖₂

over the true parameters p in a box (m, I, K and Iw each within ±``box`` of the reference
values; r, b, d as given) and over headings θ, and raises ``ValueError`` when α ≥ 1.
The box is sampled on a three-level grid (lower face, centre, upper face: 81 points, the
16 corners included) × 9 headings in [−π, π]; M(p) is the generated ``wmr_model``.

``runtime.paper.sampled_loop.check_sampled_loop`` refuses a configuration whose sampled closed
loop is predicted unstable; ``runtime.paper.controller_config.checked_controller_config`` builds
a configuration behind both checks. This module imports no other runtime module but the
generated code's.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping

import numpy as np
from numpy.typing import NDArray

from runtime.generated_modules import robot, wmr_model
from runtime.paper.paths import ROC_MAX_RATE

UNCERTAIN = ("m", "I", "K", "Iw")  # the inertial parameters: what a payload changes
KEYS = tuple(robot.PARAMS)  # the generated model's parameter table
HEADINGS = tuple(float(x) for x in np.linspace(-math.pi, math.pi, 9))
LEVELS = (-1.0, 0.0, 1.0)


def _validate(params: Mapping[str, float], label: str) -> dict[str, float]:
    missing = [k for k in KEYS if k not in params]
    if missing:
        raise ValueError(f"{label}: missing parameter(s) {', '.join(missing)}")
    out = {k: float(params[k]) for k in KEYS}
    for key, value in out.items():
        if not math.isfinite(value):
            raise ValueError(f"{label}: parameter '{key}' must be finite, got {value!r}")
    for key in ("m", "I", "Iw", "r", "b"):
        if out[key] <= 0:
            raise ValueError(f"{label}: parameter '{key}' must be positive, got {out[key]!r}")
    if out["m"] * out["I"] - out["K"] ** 2 <= 0:
        raise ValueError(
            f"{label}: m I - K^2 = {out['m'] * out['I'] - out['K'] ** 2:.6g} must be positive "
            "(the mass matrix is not positive definite)"
        )
    return out


def mass_matrix_for(
    q: NDArray[np.float64], p: Mapping[str, float], formulation: str
) -> NDArray[np.float64]:
    """M̃(q) of (14) (``paper``) or Sᵀ M S (``minimal``) at parameters ``p``."""
    if formulation == "paper":
        return np.asarray(wmr_model.mass_matrix(q, p), dtype=np.float64)
    return np.asarray(wmr_model.minimal_mass_matrix(q, p), dtype=np.float64)


def tde_alpha(
    nominal: Mapping[str, float],
    box: float = 0.3,
    *,
    true_params: Mapping[str, float] | None = None,
    formulation: str = "paper",
) -> tuple[float, dict[str, float], float]:
    """(α, the true parameters where it is reached, the heading there); no check."""
    if formulation not in ("paper", "minimal"):
        raise ValueError(f"formulation must be 'paper' or 'minimal', got {formulation!r}")
    if not (math.isfinite(box) and 0.0 <= box < 1.0):
        raise ValueError(f"box must be in [0, 1), got {box!r}")
    nom = _validate(nominal, "nominal")
    ref = _validate(true_params if true_params is not None else nominal, "true_params")
    worst: tuple[float, dict[str, float], float] = (-1.0, ref, 0.0)
    for levels in itertools.product(LEVELS, repeat=len(UNCERTAIN)):
        p = {
            **ref,
            **{k: ref[k] * (1.0 + box * lv) for k, lv in zip(UNCERTAIN, levels, strict=True)},
        }
        if p["m"] * p["I"] - p["K"] ** 2 <= 0:
            raise ValueError(
                f"the box ±{box:.0%} around the true parameters contains a robot whose mass "
                f"matrix is not positive definite ({p})"
            )
        for theta in HEADINGS:
            q = np.array([0.0, 0.0, theta, 0.0, 0.0])
            m_true, m_hat = mass_matrix_for(q, p, formulation), mass_matrix_for(q, nom, formulation)
            dev = np.linalg.solve(m_true, m_hat) - np.eye(len(m_hat))
            alpha = float(np.linalg.norm(dev, 2))
            if alpha > worst[0]:
                worst = (alpha, p, theta)
    return worst


def check_nominal(
    nominal: Mapping[str, float],
    box: float = 0.3,
    *,
    true_params: Mapping[str, float] | None = None,
    formulation: str = "paper",
) -> float:
    """α = max ‖M⁻¹ M̂ − I‖₂ over the box; ``ValueError`` if the TDE condition α < 1 fails.

    ``nominal``: the controller's model (keys m, I, K, Iw, r, b, d). ``true_params``: the
    centre of the box of true robots (default: the nominal itself). ``box``: relative
    half-width for m, I, K and Iw (0.3 = ±30 %)."""
    alpha, where, theta = tde_alpha(nominal, box, true_params=true_params, formulation=formulation)
    if not alpha < 1.0:
        worst = ", ".join(f"{k}={where[k]:.4g}" for k in UNCERTAIN)
        centre = "the nominal" if true_params is None else "true_params"
        raise ValueError(
            f"nominal model fails the TDE condition ||M^-1 Mhat - I|| < 1 ({formulation} "
            f"formulation): alpha = {alpha:.3f} at {worst}, theta={theta:.3f} (true "
            f"parameters within ±{box:.0%} of {centre}). The nominal inertia is too far from "
            "the robot's: choose it closer (roughly, 0 < M-hat < 2 M for every robot in the box)."
        )
    return alpha


def roc_bounds(
    nominal: dict[str, float], uncertainty: float, formulation: str, max_rate: float = ROC_MAX_RATE
) -> tuple[float, float]:
    """(α, φ) for ROC: α = max ‖M⁻¹ M̂ − I‖₂ and φ = max ‖M⁻¹ (H − Ĥ)‖ over the box where m,
    I, K and Iw are each nominal or ``uncertainty`` above it ("30 % above nominal"), over
    headings and random wheel rates up to ``max_rate``. (The TDE condition for TDC/TDROC,
    over a symmetric box, is ``nominal_check.check_nominal``.)"""
    alpha, phi = 0.0, 0.0
    rng = np.random.default_rng(7)
    corners = [
        {
            **nominal,
            **{
                k: nominal[k] * (1 + uncertainty * ((mask >> i) & 1))
                for i, k in enumerate(UNCERTAIN)
            },
        }
        for mask in range(2 ** len(UNCERTAIN))
    ]
    for theta in np.linspace(-math.pi, math.pi, 9):
        q = np.array([0.0, 0.0, theta, 0.0, 0.0])
        m_hat = mass_matrix_for(q, nominal, formulation)
        for p in corners:
            inv = np.linalg.inv(mass_matrix_for(q, p, formulation))
            alpha = max(alpha, float(np.linalg.norm(inv @ m_hat - np.eye(len(m_hat)), 2)))
            for eta in rng.uniform(-max_rate, max_rate, size=(4, 2)):
                qdot = np.concatenate([wmr_model.kinematics(q, eta, p), eta])
                if formulation == "paper":
                    dh = wmr_model.bias_forces(q, qdot, p) - wmr_model.bias_forces(q, qdot, nominal)
                else:
                    dh = wmr_model.minimal_bias_forces(q, eta, p) - wmr_model.minimal_bias_forces(
                        q, eta, nominal
                    )
                phi = max(phi, float(np.linalg.norm(inv @ dh)))
    return alpha, phi
