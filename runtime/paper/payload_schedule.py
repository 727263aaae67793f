"""The paper's robot's payload over an experiment: the fixed payload always, the extra one
on for half of every period (``[plant]`` of the experiment), as plant parameters
(:func:`runtime.robot_simulation.plant_params_at` on the paper robot's generated code).
The paper places its payload "rather randomly"; the schedule is our choice (docs/PAPER.md
item 13)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from runtime.experiment import Experiment
from runtime.generated_modules import load_robot_code
from runtime.robot_simulation import plant_params_at


def plant_params(robot: dict[str, float], exp: Experiment, t: float) -> NDArray[np.float64]:
    """True (m, I, K, K_lat, Iw, r, b, d) at time t: robot + fixed payload + periodic payload."""
    p = plant_params_at(load_robot_code(""), exp, t, {**robot, "K_lat": 0.0})
    return np.array(list(p.values()))
