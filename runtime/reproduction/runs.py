"""One run of the reproduction, for every robot: the configuration checks first, then the
closed loop on the plant the experiment names.

The toolchain refuses to run a configuration it predicts will fail
(:func:`runtime.stability.checks.check_configuration`: the TDE condition of (17) over the
uncertainty box, the sampled loop's predicted stability). The one driver
(:mod:`runtime.reproduction.driver`) runs every robot's runs through :func:`checked_run`, so
a refused configuration is refused the same way on every robot: it is not simulated, and
its record (no sample) says why (outcome ``refused``, :mod:`runtime.sim.outcome`).
"""

from __future__ import annotations

from collections.abc import Mapping

from runtime.bindings.generated import RobotCode
from runtime.experiment.settings import Experiment
from runtime.plants import plant_for
from runtime.sim import loop
from runtime.sim.loop import Run
from runtime.sim.plant import Plant
from runtime.sim.reference import Reference
from runtime.stability.checks import check_configuration


def checked_run(code: RobotCode, controller: str, formulation: str, ref: Reference,
                nominal: Mapping[str, float], exp: Experiment, *,
                plant_params: Mapping[str, float] | None = None,
                plant: Plant | None = None) -> Run:
    """:func:`runtime.sim.loop.run` of ``controller`` in ``formulation`` if the
    configuration checks accept it (``plant``: default the experiment's, built by the
    registry), else the record of a refused run (:attr:`Run.refused`: the check's reason)."""
    try:
        check_configuration(code, controller, formulation, nominal, exp)
    except ValueError as exc:
        return loop.not_run(code, controller, formulation, ref, str(exc))
    if plant is None:
        plant = plant_for(code, exp, nominal, plant_params)
    return loop.run(code, controller, formulation, ref, nominal, exp,
                    plant_params=plant_params, plant=plant)
