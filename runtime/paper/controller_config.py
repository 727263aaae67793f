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
from functools import lru_cache
from typing import Any

from runtime import cbuild
from runtime.experiment import ACCEL_CODES, Experiment
from runtime.generated_modules import load_robot_code
from runtime.paper.nominal_check import check_nominal, roc_bounds
from runtime.paper.sampled_loop import check_sampled_loop
from runtime.robot_simulation import controller_config as generic_config

__all__ = ["ACCEL_CODES", "FORMULATIONS", "checked_controller_config", "controller_config",
           "roc_bounds"]

FORMULATIONS = {"paper": 0, "minimal": 1}


@lru_cache(maxsize=64)
def _roc_bounds(nominal: tuple[tuple[str, float], ...], uncertainty: float,
                formulation: str) -> tuple[float, float]:
    """:func:`roc_bounds` once per nominal model (it samples a box: ~0.1 s, as long as a
    run; a campaign's ROC runs share a few nominal models)."""
    return roc_bounds(dict(nominal), uncertainty, formulation)


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
    bounds = (
        _roc_bounds(tuple(sorted(nominal.items())), exp.controller.uncertainty, formulation)
        if name == "roc"
        else None
    )
    return generic_config(lib, load_robot_code(""), name, formulation, nominal, exp, bounds,
                          held_gain)


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
