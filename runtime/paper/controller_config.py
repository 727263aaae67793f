"""The C configuration of a controller for an experiment, with or without the checks.

:func:`controller_config` fills ``wmr_<name>_config_t`` from the experiment's
``[controller]`` and ``[sensing]`` tables and a nominal model (ROC's α and φ from
:func:`roc_bounds`); :func:`checked_controller_config` builds the same configuration after
the checks of ``runtime.paper.nominal_check`` (the TDE condition over the uncertainty box, the
sampled loop's predicted stability). ``runtime.paper.simulate`` runs the result; these names
are also importable from there.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from runtime import cbuild
from runtime.experiment import ACCEL_CODES, Experiment
from runtime.paper.nominal_check import check_nominal, roc_bounds
from runtime.paper.sampled_loop import check_sampled_loop

__all__ = ["ACCEL_CODES", "FORMULATIONS", "checked_controller_config", "controller_config",
           "roc_bounds"]

FORMULATIONS = {"paper": 0, "minimal": 1}


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
