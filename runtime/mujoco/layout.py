"""The robot a physics engine builds, from generated code and plant parameters (no MuJoCo,
no SymPy), and what its contacts can carry: the traction-aware torque limit of
``[controller] traction_mu``."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from modeling.contact_loads import static_loads
from modeling.planar_robot import PlanarRobot, from_lumped
from runtime.bindings.generated import RobotCode
from runtime.experiment.settings import Experiment
from runtime.sim import paths
from runtime.sim.slip_monitor import SlipMonitor


def robot_layout(code: RobotCode, base: Mapping[str, float]) -> PlanarRobot:
    """The robot the engine simulates: the generated ``LAYOUT`` of a bodies-and-wheels
    robot, else the lumped robot of the plant parameters ``base``. ``ValueError`` if a
    bodies-and-wheels robot is asked with other parameters than its own (the engine takes
    masses and inertias, not the derived model's base parameters)."""
    layout = getattr(code.robot, "LAYOUT", None)
    if layout is None:
        if code.prefix != "wmr":
            raise ValueError(f"robot '{code.name}': its generated robot.py has no LAYOUT "
                             "(generated before the MuJoCo plant); regenerate it with "
                             "`wmr model`")
        return from_lumped(code.name, base)
    own = code.plant_defaults
    moved = [k for k in own if not math.isclose(float(base.get(k, own[k])), own[k],
                                                rel_tol=1e-12, abs_tol=1e-15)]
    if moved:
        raise ValueError(f"robot '{code.name}': the MuJoCo plant simulates the robot's own "
                         f"bodies and wheels; plant parameter '{moved[0]}' = "
                         f"{base[moved[0]]!r} differs from the robot's {own[moved[0]]!r} "
                         "(perturbed parameters run on the generated plant)")
    return PlanarRobot.from_data(layout)


def traction_torque_limit(code: RobotCode, base: Mapping[str, float], exp: Experiment,
                          mu: float) -> float:
    """The largest wheel torque that keeps every driven wheel inside its friction circle at
    friction ``mu`` on the experiment's paths: min over the paths' samples and the driven
    wheels of r √((μ N)² − F_y²), N the wheel's normal load (the one load model,
    ``modeling.contact_loads``: the payload the schedule has on board at that sample, the
    load transfer of the tracked motion) and F_y its share of its axle's lateral force
    on the tracked path (:meth:`runtime.sim.slip_monitor.SlipMonitor.along`): a rolling
    force F_x ≈ τ/r under it leaves |F| ≤ μ N. What the wheel's own inertia and bearing
    friction take only lowers F_x; a controller that leaves the path turns harder than
    the path does, so this is a ceiling to stay under, not a guarantee. A robot whose
    generated code has no contact forces gets the static rule: μ N r of the lightest
    driven wheel at rest over the payload states."""
    robot = robot_layout(code, base)
    pl = exp.plant
    driven = [w for w in robot.wheels if w.driven]
    states = ((pl.fixed_payload, 0.0), (pl.fixed_payload, pl.extra_payload))
    static = min(mu * static_loads(robot, ((m0, pl.fixed_payload_x, pl.fixed_payload_y),
                                           (m1, pl.extra_payload_x, pl.extra_payload_y)))[w.name]
                 * w.radius for m0, m1 in states for w in driven)
    try:
        monitor = SlipMonitor(code, robot, exp)
    except ValueError:  # generated before the contact forces: the static rule
        return static
    radius = np.array([{w.name: w.radius for w in driven}[w] for w in monitor.driven])
    nominal = {k: float(base.get(k, v)) for k, v in code.params.items()}
    limit = static
    for name in paths.PATHS:
        _, fy, n = monitor.along(paths.reference(code, nominal, exp, name), nominal, exp)
        room = np.sqrt(np.maximum((mu * n) ** 2 - fy**2, 0.0))
        limit = min(limit, float((room * radius).min()))
    return limit
