"""The plant registry: which plant a closed loop runs, by the experiment's ``[plant] model``.

It sits above every plant (the generated model of :mod:`runtime.sim.plant`, the MuJoCo
engine of :mod:`runtime.mujoco.plant`), so it imports each of them like any other module.
A new plant is a module with its class (the :class:`runtime.sim.plant.Plant` protocol), one
entry in :data:`PLANTS` and its name in ``runtime.experiment.settings.PLANT_MODELS``; the
loop (:mod:`runtime.sim.loop`) does not change: it runs the plant it is given.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

from runtime.bindings import cbuild
from runtime.bindings.generated import RobotCode
from runtime.experiment.settings import Experiment
from runtime.mujoco.plant import mujoco_plant
from runtime.sim.plant import Plant, generated_plant, library_for, plant_base

PlantFactory = Callable[[RobotCode, cbuild.CLibrary, Experiment, Mapping[str, float]], Plant]

# [plant] model -> the plant a closed loop runs (the keys are PLANT_MODELS): the robot's
# generated code, the library of its generated C, the experiment, the plant parameters
# before payload.
PLANTS: dict[str, PlantFactory] = {
    "generated": lambda code, lib, exp, base: generated_plant(code, lib, exp),
    "mujoco": lambda code, lib, exp, base: mujoco_plant(code, exp, base),
}


def make_plant(code: RobotCode, lib: cbuild.CLibrary, exp: Experiment,
               base: Mapping[str, float]) -> Plant:
    """The plant the experiment names (``[plant] model``) for this robot, whose plant
    parameters before payload are ``base``."""
    return PLANTS[exp.plant.model](code, lib, exp, base)


def plant_for(code: RobotCode, exp: Experiment, nominal: Mapping[str, float],
              plant_params: Mapping[str, float] | None = None,
              float32: bool = False) -> Plant:
    """The plant of a :func:`runtime.sim.loop.run` with these arguments: the one the
    experiment names, for the simulated robot ``plant_params`` (default: the nominal model,
    :func:`runtime.sim.plant.plant_base`)."""
    return make_plant(code, library_for(code, float32), exp,
                      plant_base(code, nominal, plant_params))
