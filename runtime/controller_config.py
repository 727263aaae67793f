"""The C configuration of a controller for an experiment, with or without the checks.

:func:`controller_config` fills ``wmr_<name>_config_t`` from the experiment's
``[controller]`` and ``[sensing]`` tables and a nominal model (ROC's α and φ from
:func:`roc_bounds`); :func:`checked_controller_config` builds the same configuration after
the checks of ``runtime.nominal_check`` (the TDE condition over the uncertainty box, the
sampled loop's predicted stability). ``runtime.simulate`` runs the result; these names
are also importable from there.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from runtime import cbuild
from runtime.experiment import Experiment
from runtime.generated_modules import wmr_model
from runtime.nominal_check import UNCERTAIN, check_nominal, check_sampled_loop, mass_matrix_for

FORMULATIONS = {"paper": 0, "minimal": 1}


def roc_bounds(
    nominal: dict[str, float], uncertainty: float, formulation: str, max_rate: float = 8.0
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


# accel_estimator of the experiment file -> WMR_ACCEL_* of the generated configs.
ACCEL_CODES = {"backward": 0, "central": 1, "matched": 2}


def controller_config(
    lib: cbuild.CLibrary,
    name: str,
    formulation: str,
    nominal: dict[str, float],
    exp: Experiment,
    held_gain: float | None = None,
) -> Any:
    """The C configuration of one controller for the experiment. ``held_gain`` (TDROC only)
    holds k̂ at that value instead of (25): the stability analysis' verification."""
    c = exp.controller
    cfg = lib.ffi.new(f"wmr_{name}_config_t *")
    cfg.nominal = cbuild.params_struct(lib, nominal)[0]
    cfg.formulation = FORMULATIONS[formulation]
    cfg.k1 = [c.k1] * 5
    cfg.k2 = [c.k2] * 5
    cfg.q_pos, cfg.q_vel, cfg.h, cfg.tau_max = c.q_pos, c.q_vel, c.h, c.tau_max
    if name in ("tdc", "tdroc"):
        cfg.accel_estimator = ACCEL_CODES[exp.sensing.accel_estimator]
        cfg.rate_window = exp.sensing.rate_window(c.h)
    if name != "tdc":
        cfg.eps = c.eps
    if name == "tdroc":
        cfg.n, cfg.a = c.n, c.a
        if held_gain is not None:
            cfg.hold_gain, cfg.held_gain = 1, held_gain
    elif held_gain is not None:
        raise ValueError(f"held_gain applies to TDROC only, not {name}")
    if name == "roc":
        cfg.alpha, cfg.phi = roc_bounds(nominal, c.uncertainty, formulation)
    if name == "asmc":
        cfg.gamma, cfg.gain0 = c.gamma, 0.0
    return cfg


def checked_controller_config(
    lib: cbuild.CLibrary,
    name: str,
    formulation: str,
    nominal: dict[str, float],
    exp: Experiment,
    true_params: Mapping[str, float] | None = None,
    held_gain: float | None = None,
) -> Any:
    """:func:`controller_config` after :func:`check_nominal` over the experiment's
    uncertainty box (``controller.uncertainty``) for the time-delay controllers."""
    if name in ("tdc", "tdroc"):
        check_nominal(
            nominal, exp.controller.uncertainty, true_params=true_params, formulation=formulation
        )
    check_sampled_loop(name, formulation, nominal, exp)
    return controller_config(lib, name, formulation, nominal, exp, held_gain)
