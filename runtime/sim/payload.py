"""The simulated robot's true parameters over an experiment: its own, with the fixed payload
always and the extra one on for half of every period (``[plant]`` of the experiment), each
a point mass on the root body through the generated ``plant_params_with_payload``. The
paper places its payload "rather randomly"; the schedule is our choice (docs/PAPER.md
item 13)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import NDArray

from runtime.bindings.generated import RobotCode
from runtime.experiment.settings import Experiment


def payload_mass(exp: Experiment, t: float) -> float:
    """The payload on board at time t (kg)."""
    pl = exp.plant
    return pl.fixed_payload + (pl.extra_payload if pl.extra_on(t) else 0.0)


def payload_masses(exp: Experiment, t: float) -> NDArray[np.float64]:
    """The masses on board at time t at the experiment's two payload points (fixed,
    extra), as a plant that places them itself takes them (kg)."""
    pl = exp.plant
    return np.array([pl.fixed_payload, pl.extra_payload if pl.extra_on(t) else 0.0])


def plant_params_at(code: RobotCode, exp: Experiment, t: float,
                    base: Mapping[str, float] | None = None) -> dict[str, float]:
    """The simulated robot's parameters at time t (keys in the generated ``PLANT_PARAMS``
    order): ``base`` (default: the robot's) with the experiment's fixed payload, and the
    extra one when it is on."""
    pl = exp.plant
    keys = list(code.plant_defaults)
    p = dict(code.plant_defaults if base is None else base)
    loads = [(pl.fixed_payload, pl.fixed_payload_x, pl.fixed_payload_y)]
    if pl.extra_on(t):
        loads.append((pl.extra_payload, pl.extra_payload_x, pl.extra_payload_y))
    for load in loads:
        if load[0] > 0:
            values = code.plant.plant_params_with_payload(list(load), p)
            p = dict(zip(keys, (float(v) for v in values), strict=True))
    return {k: p[k] for k in keys}
