"""(17) with a sensing model: the matched estimate is exact under ZOH for a constant H1.

A linear plant M q̈ + H1 = u with constant M, H1, driven by a zero-order-held input that
changes every sample, is measured the three ways of ``[sensing]``: rates at the sample
instant, Δθ/h over the sample, and Δθ/w over the last w seconds. The generated Python
controller's Ĥ1 (TDC, minimal formulation, whose M̂ = M̄ is constant) must equal H1 for the
matched estimator, and must not for the plain backward quotient with averaged rates.
"""

from __future__ import annotations

import numpy as np
import pytest

from runtime.bindings.generated import controllers as gc
from runtime.bindings.generated import robot, wmr_model

H = 0.1
H1_TRUE = np.array([0.7, -0.3])


def measured_rates(
    window: float, steps: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(angles, measured rates, inputs) of M θ̈ + H1 = u under ZOH, exact in closed form."""
    m = wmr_model.minimal_mass_matrix(np.zeros(5), robot.PARAMS)
    inputs = rng.uniform(-3.0, 3.0, size=(steps, 2))
    theta, rate = np.zeros(2), np.zeros(2)
    angles, rates = [], []
    for k in range(steps):
        acc = np.linalg.solve(m, inputs[k - 1] - H1_TRUE) if k else np.zeros(2)
        if k:
            # Rate at t_k, and the mean rate over [t_k − w, t_k] under the constant acc.
            rate_then = rate
            rate = rate_then + acc * H
            theta = theta + rate_then * H + 0.5 * acc * H**2
        mean_over_window = rate - 0.5 * acc * window
        angles.append(theta.copy())
        rates.append(mean_over_window.copy() if window > 0 else rate.copy())
    return np.array(angles), np.array(rates), inputs


def estimates(window: float, estimator: int) -> np.ndarray:
    rng = np.random.default_rng(3)
    angles, rates, inputs = measured_rates(window, 12, rng)
    cfg = gc.Config(
        nominal=robot.PARAMS, formulation=gc.FORMULATION_MINIMAL, h=H, tau_max=1e6,
        accel_estimator=estimator, rate_window=window,
    )  # fmt: skip
    ctrl = gc.TDC(cfg)
    out = []
    for k in range(len(angles)):
        q = np.array([0.0, 0.0, 0.0, *angles[k]])
        qdot = np.array([0.0, 0.0, 0.0, *rates[k]])
        ctrl.step(q, qdot, q, qdot, np.zeros(5))
        # Drive the plant with the prescribed inputs, as applied (B τ, unsaturated).
        ctrl.u_prev[3:5] = inputs[k]
        ctrl.tau = inputs[k].copy()
        if ctrl.steps > 2:
            out.append(ctrl.H1hat[:2].copy())
    return np.array(out)


@pytest.mark.parametrize("window", [0.0, 0.03, H], ids=["sample-instant", "motor-30ms", "avg"])
def test_matched_estimate_is_exact(window: float) -> None:
    est = estimates(window, gc.ACCEL_MATCHED)
    assert np.max(np.abs(est - H1_TRUE)) < 1e-9


def test_backward_quotient_is_wrong_with_averaged_rates() -> None:
    est = estimates(H, gc.ACCEL_BACKWARD)
    assert np.max(np.abs(est - H1_TRUE)) > 0.1


def test_rate_window_outside_the_sample_is_refused() -> None:
    for bad in (-0.01, 2 * H, float("nan")):
        cfg = gc.Config(
            nominal=robot.PARAMS, h=H, accel_estimator=gc.ACCEL_MATCHED, rate_window=bad
        )
        with pytest.raises(gc.ControllerError, match="rate_window"):
            gc.TDROC(cfg)
