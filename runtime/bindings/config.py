"""A controller's C configuration, ``<prefix>_<ctrl>_config_t``, from the registry's export.

Every field comes from where the generated ``robot.py`` says (``CONTROLLERS``, each field's
``source``; ``modeling.controllers.ConfigField``): an experiment field
(``experiment.<section>.<field>``, a vector field gets one value per coordinate of q), or
one of :data:`SOURCES`, each a function of the :class:`ConfigInputs` (the robot's code, the
controller, formulation, nominal parameters, experiment and options). A new source is one
entry in that table; a new controller needs nothing here. Every command that fills a
configuration (the closed loop, campaigns, the stability analysis, ``wmr freeze``, the
firmware reports) calls :func:`controller_config`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from runtime.bindings import cbuild
from runtime.bindings.generated import ControllerInfo, RobotCode
from runtime.bindings.physical_bounds import check_physical_roc
from runtime.bindings.uncertainty import roc_bounds
from runtime.experiment.settings import ACCEL_CODES, Experiment

EXPERIMENT_SOURCE = "experiment."  # experiment.<section>.<field>: an experiment field


@dataclass(frozen=True)
class ConfigInputs:
    """What a configuration is built from. ``held_gain``: hold the adaptive k̂ of (25) at
    this value instead (the stability analysis' verification; controllers with a
    ``hold_gain`` field); ``bounds``: ROC's (α, φ) if given, else :func:`roc_bounds` of the
    nominal model over the experiment's box (``controller.uncertainty``, wheel rates up to
    ``controller.roc_max_rate``), or, when the experiment declares
    ``[physical_uncertainty]``, :func:`runtime.bindings.physical_bounds.check_physical_roc`
    over that physical box (``ValueError`` naming the range where α < 1 cannot be shown)."""

    code: RobotCode
    controller: ControllerInfo
    formulation: str
    nominal: Mapping[str, float]
    experiment: Experiment
    held_gain: float | None = None
    bounds: tuple[float, float] | None = None

    @cached_property
    def roc_bounds(self) -> tuple[float, float]:
        if self.bounds is not None:
            return self.bounds
        c = self.experiment.controller
        if self.experiment.physical:
            return check_physical_roc(self.code, self.nominal, self.experiment.physical,
                                      self.formulation, c.roc_max_rate)
        return roc_bounds(self.code, self.nominal, c.uncertainty, self.formulation,
                          c.roc_max_rate)

    @cached_property
    def wheel_inertia(self) -> float:
        """J of the PI rules: the mean of the diagonal of the nominal minimal mass matrix M̄
        at q = 0, the inertia each motor feels."""
        m_bar = self.code.model.minimal_mass_matrix(np.zeros(self.code.nq), dict(self.nominal))
        return float(np.mean(np.diag(np.asarray(m_bar, dtype=np.float64))))

    @property
    def pi_kp(self) -> float:
        """Proportional gain of the wheel-velocity PI: J × bandwidth."""
        return self.wheel_inertia * self.experiment.controller.pi_bandwidth

    @property
    def pi_ki(self) -> float:
        """Integral gain: kp × bandwidth / 4 (the integrator's corner a quarter of it)."""
        return self.pi_kp * self.experiment.controller.pi_bandwidth / 4


# Source name (ConfigField.source) -> its value. ``experiment.<section>.<field>`` is read
# from the experiment directly (:func:`source_value`).
SOURCES: dict[str, Callable[[ConfigInputs], Any]] = {
    "formulation": lambda c: getattr(c.code.controllers, f"FORMULATION_{c.formulation.upper()}"),
    "accel_estimator": lambda c: ACCEL_CODES[c.experiment.sensing.accel_estimator],
    "rate_window": lambda c: c.experiment.sensing.rate_window(c.experiment.controller.h),
    "hold_gain": lambda c: 0 if c.held_gain is None else 1,
    "held_gain": lambda c: 0.0 if c.held_gain is None else float(c.held_gain),
    "roc_bounds.alpha": lambda c: c.roc_bounds[0],
    "roc_bounds.phi": lambda c: c.roc_bounds[1],
    "zero": lambda c: 0.0,
    "pi_kp": lambda c: c.pi_kp,
    "pi_ki": lambda c: c.pi_ki,
}


def source_value(source: str, inputs: ConfigInputs) -> Any:
    """The value of one field's ``source``; ``ValueError`` for an unknown source."""
    if source.startswith(EXPERIMENT_SOURCE):
        section, _, name = source.removeprefix(EXPERIMENT_SOURCE).partition(".")
        return getattr(getattr(inputs.experiment, section), name)
    if source not in SOURCES:
        raise ValueError(f"configuration source {source!r} of {inputs.controller.name} is not "
                         f"known to the runtime (runtime.bindings.config.SOURCES)")
    return SOURCES[source](inputs)


def controller_config(lib: cbuild.CLibrary, code: RobotCode, name: str, formulation: str,
                      nominal: Mapping[str, float], exp: Experiment, *,
                      held_gain: float | None = None,
                      bounds: tuple[float, float] | None = None) -> Any:
    """A new ``<prefix>_<name>_config_t`` for the nominal parameters and the experiment,
    each field from its registry source (see the module docstring). Not validated: the C's
    ``_init`` (or ``_check_config``) does that."""
    info = code.controller(name)
    if formulation not in info.formulations:
        raise ValueError(f"{name} is not generated in the {formulation} formulation for robot "
                         f"'{code.name}' (it has {', '.join(info.formulations)})")
    if held_gain is not None and "hold_gain" not in info.field_names():
        raise ValueError(f"held_gain applies to a controller with an adaptive k̂ it can hold "
                         f"(a hold_gain field), not {name}")
    inputs = ConfigInputs(code, info, formulation, nominal, exp, held_gain, bounds)
    cfg = lib.ffi.new(f"{code.prefix}_{name}_config_t *")
    cfg.nominal = cbuild.params_struct(lib, dict(nominal), f"{code.prefix}_params_t",
                                       code.controllers.C_FIELD_NAMES)[0]
    for f in info.fields:
        value = source_value(f.source, inputs)
        setattr(cfg, f.name, [value] * code.nq if f.kind == "vector" else value)
    return cfg
