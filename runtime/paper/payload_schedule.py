"""The paper's robot's payload over an experiment: the fixed payload always, the extra one
on for half of every period (``[plant]`` of the experiment), as plant parameters."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from runtime.experiment import Experiment
from runtime.generated_modules import robot as generated_robot
from runtime.generated_modules import wmr_plant


def plant_params(robot: dict[str, float], exp: Experiment, t: float) -> NDArray[np.float64]:
    """True (m, I, K, K_lat, Iw, r, b, d) at time t: robot + fixed payload + periodic payload."""
    pl = exp.plant
    base = {**robot, "K_lat": 0.0}
    p = wmr_plant.plant_params_with_payload(
        [pl.fixed_payload, pl.fixed_payload_x, pl.fixed_payload_y], base
    )
    if extra_payload_on(exp, t):
        p = wmr_plant.plant_params_with_payload(
            [pl.extra_payload, pl.extra_payload_x, pl.extra_payload_y],
            dict(zip(generated_robot.PLANT_PARAMS, p, strict=True)),
        )
    return p


def extra_payload_on(exp: Experiment, t: float) -> bool:
    pl = exp.plant
    if t < pl.extra_on_at:
        return False
    return ((t - pl.extra_on_at) % pl.extra_period) < pl.extra_period / 2
