"""The robot a physics engine builds, from generated code and plant parameters (no MuJoCo,
no SymPy), and what its contacts can carry: the traction-aware torque limit of
``[controller] traction_mu``."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace

from modeling.contact_loads import static_loads
from modeling.planar_robot import PlanarRobot, from_lumped
from runtime.bindings.generated import RobotCode
from runtime.experiment.settings import Experiment


def robot_layout(code: RobotCode, base: Mapping[str, float]) -> PlanarRobot:
    """The robot the engine simulates: the generated ``LAYOUT`` of a bodies-and-wheels
    robot, else the lumped robot of the plant parameters ``base``; standing on the
    supports its robot file states (``SUPPORTS``; not stated: the default rule of
    ``modeling.supports``, applied to these numbers). ``ValueError`` if a
    bodies-and-wheels robot is asked with other parameters than its own (the engine takes
    masses and inertias, not the derived model's base parameters)."""
    layout = getattr(code.robot, "LAYOUT", None)
    if layout is None:
        if not code.paper_model:
            raise ValueError(f"robot '{code.name}': its generated robot.py has no LAYOUT "
                             "(generated before the MuJoCo plant); regenerate it with "
                             "`wmr model`")
        return from_lumped(code.name, base, code.supports)
    own = code.plant_defaults
    moved = [k for k in own if not math.isclose(float(base.get(k, own[k])), own[k],
                                                rel_tol=1e-12, abs_tol=1e-15)]
    if moved:
        raise ValueError(f"robot '{code.name}': the MuJoCo plant simulates the robot's own "
                         f"bodies and wheels; plant parameter '{moved[0]}' = "
                         f"{base[moved[0]]!r} differs from the robot's {own[moved[0]]!r} "
                         "(perturbed parameters run on the generated plant)")
    return replace(PlanarRobot.from_data(layout), supports=code.supports)


def traction_torque_limit(code: RobotCode, base: Mapping[str, float], exp: Experiment,
                          mu: float) -> float:
    """The largest wheel torque no driven wheel can spend on slipping at friction ``mu``:
    min over the driven wheels and the payload states the schedule makes (fixed payload;
    fixed and extra) of μ N r, N the wheel's normal load at rest from the one load model
    (``modeling.contact_loads``; the extra payload, ahead and left on Drishti, unloads the
    right wheel to 99.9 N). A wheel at rest whose torque stays below it cannot spin on the
    floor (its own spin inertia and bearing friction only lower what reaches the contact);
    accelerating the body, turning and load transfer take part of μ N too (the grip
    verdict, ``runtime.stability.saturation``, simulates them), so this is a ceiling to
    stay under, not a guarantee."""
    robot = robot_layout(code, base)
    pl = exp.plant
    states = ((pl.fixed_payload, 0.0), (pl.fixed_payload, pl.extra_payload))
    return min(mu * static_loads(robot, ((m0, pl.fixed_payload_x, pl.fixed_payload_y),
                                         (m1, pl.extra_payload_x, pl.extra_payload_y)))[w.name]
               * w.radius for m0, m1 in states for w in robot.wheels if w.driven)
