"""A campaign's physical draws: the same drawn robot on both plants.

A campaign on a bodies-and-wheels robot may draw its physical quantities (``physical.KEY``:
a body's mass, yaw inertia, centre of mass, a wheel's mass and inertias, a payload on the
root; ``[physical_uncertainty]`` of the campaign file draws every quantity it gives a
range, uniformly). Run i's drawn robot then reaches

* the generated plant through the generated map (``plant_params_from_physical``,
  ``modeling.physical_map``): its base parameters, payload included;
* MuJoCo as bodies (:func:`physical_layout`): the robot file's layout with the drawn masses,
  inertias and centres of mass, the payload a point mass merged into the root body
  (parallel-axis theorem: the same kinetic energy as the map's).

Both plants take run i's draws from (seed, i) alone (``runtime.campaign.sampling``), so
two campaigns that differ only in ``[plant] model`` simulate the same robots run by run.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

import numpy as np

from modeling.planar_robot import PlanarBody, PlanarRobot
from runtime.bindings.generated import RobotCode
from runtime.bindings.physical_bounds import physical_model

PREFIX = "physical."


def drawn(values: Mapping[str, object]) -> dict[str, float]:
    """The physical quantities among a run's drawn values (key without the prefix)."""
    return {k.removeprefix(PREFIX): float(v) for k, v in values.items()  # type: ignore[arg-type]
            if k.startswith(PREFIX)}


def physical_vector(code: RobotCode, values: Mapping[str, float]) -> np.ndarray:
    """The map's input: the robot file's quantities with ``values`` over them."""
    pm = physical_model(code)
    unknown = sorted(set(values) - set(pm.keys))
    if unknown:
        raise ValueError(f"robot '{code.name}' has no physical quantity '{unknown[0]}'")
    return np.array([values.get(k, v) for k, v in zip(pm.keys, pm.nominal, strict=True)])


def physical_params(code: RobotCode, values: Mapping[str, float]) -> dict[str, float]:
    """The plant parameters of the drawn robot (the generated map)."""
    return physical_model(code).params(physical_vector(code, values))


def physical_layout(code: RobotCode, values: Mapping[str, float]) -> PlanarRobot:
    """The drawn robot as bodies for an engine: the generated ``LAYOUT`` with each drawn
    mass, inertia and centre of mass, and a drawn payload (``payload_mass`` at
    (``payload_x``, ``payload_y``) of the root's frame) merged into the root body."""
    layout = getattr(code.robot, "LAYOUT", None)
    if layout is None:
        raise ValueError(f"robot '{code.name}' has no bodies to draw (a [lumped] robot)")
    pm = physical_model(code)
    p = dict(zip(pm.keys, physical_vector(code, values), strict=True))
    robot = PlanarRobot.from_data(layout)
    bodies = [PlanarBody(b.name, p[f"mass_{b.name}"], p[f"yaw_inertia_{b.name}"],
                         (p[f"com_x_{b.name}"], p[f"com_y_{b.name}"])) for b in robot.bodies]
    wheels = tuple(replace(w, mass=p[f"mass_{w.name}"], spin_inertia=p[f"spin_inertia_{w.name}"],
                           diameter_inertia=p[f"diameter_inertia_{w.name}"])
                   for w in robot.wheels)
    m_l, x_l, y_l = p["payload_mass"], p["payload_x"], p["payload_y"]
    if m_l > 0:
        root = bodies[0]
        m = root.mass + m_l
        cx = (root.mass * root.com[0] + m_l * x_l) / m
        cy = (root.mass * root.com[1] + m_l * y_l) / m
        inertia = (root.yaw_inertia
                   + root.mass * ((root.com[0] - cx) ** 2 + (root.com[1] - cy) ** 2)
                   + m_l * ((x_l - cx) ** 2 + (y_l - cy) ** 2))
        bodies[0] = PlanarBody(root.name, m, inertia, (cx, cy))
    return PlanarRobot(robot.name, tuple(bodies), robot.joints, wheels)
