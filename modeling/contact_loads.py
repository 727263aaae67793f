"""The one load model: the normal load on every support of a robot (driven and passive
wheels, and the frictionless supports the engine adds), no SymPy.

Every tool that needs a normal load takes it from :func:`support_loads`: the slip monitor
(``runtime.sim.slip_monitor``), the traction-aware torque limit (``[controller]
traction_mu``, ``runtime.setting.layout``), the saturation and grip verdict
(``runtime.stability.saturation``) and the MuJoCo comparison. Its inputs are the robot's
description (:class:`modeling.planar_robot.PlanarRobot`: bodies, wheels, and the supports
its robot file states, or their default: ``modeling.supports``), the payload state
(point masses on the root body) and the assembly's horizontal acceleration.

Model (stated; ``modeling.mjcf_export`` writes an MJCF that realises it):

* the robot is one rigid assembly on its contacts (hitches are vertical hinges: rigid in
  pitch and roll); every mass is at its stated point, bodies' and payloads' centres of
  mass at the axle height h (the mean wheel radius, as the MJCF places them), wheels' at
  their radius;
* **compliance**: every support is a vertical spring of the same stiffness, pre-load free.
  With three contacts or more off one line the split is statically indeterminate; equal
  springs under a rigid body sink along a plane, so the loads are the plane
  N_i = a + b x_i + c y_i over the contact points that balances the weight and its two
  moments (a least-squares fit whose normal equations are the equilibrium). The MJCF
  gives each contact geom a ``solref`` time constant that makes MuJoCo's contact
  stiffness, which scales with the inverse of the contact body's inverse weight, equal
  (:func:`modeling.mjcf_export.contact_time_constants`; ``tests/runtime/test_contact_loads.py``
  measures MuJoCo's loads at rest within 2 %);
* **lift-off**: a spring cannot pull. A support the plane would put in tension is lifted
  off (load 0, listed in :attr:`SupportLoads.lifted`) and the split is solved again over
  the rest; never a negative load. If what is left cannot carry the weight's moments (all
  on a line), the robot tips over: ``ValueError``;
* **load transfer**: under a horizontal acceleration (a_x, a_y) of the assembly's centre
  of mass (root frame), the ground's traction at z = 0 and the inertia at height h add the
  moments −m a h: Σ N_i x_i = Σ m_j (g x_j − a_x h_j), Σ N_i y_i = Σ m_j (g y_j −
  a_y h_j); yaw and its rates (the bodies' pitch and roll inertia) are left out.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from modeling.mjcf_export import GRAVITY
from modeling.planar_robot import PlanarRobot, Point, body_origins
from modeling.robot_io import RobotFileError
from modeling.supports import check_supports, support_points, wheel_points

Payload = tuple[float, float, float]  # (mass kg, x m, y m) on the root body
LOAD_MODEL = "equal contact springs under a rigid assembly; the MJCF realises them"


@dataclass(frozen=True)
class SupportLoads:
    """The normal load (N, ≥ 0) on every contact, and which ones lifted off (load 0)."""

    loads: dict[str, float]
    lifted: tuple[str, ...] = ()

    def __getitem__(self, name: str) -> float:
        return self.loads[name]


def contact_points(robot: PlanarRobot) -> dict[str, Point]:
    """Every contact's point (root frame, hitches straight): wheel names, then the
    supports' (the robot file's ``[[support]]``, else the default: ``modeling.supports``)."""
    return {**wheel_points(robot), **support_points(robot)}


def masses(robot: PlanarRobot, payloads: tuple[Payload, ...] = ()
           ) -> list[tuple[float, float, float, float]]:
    """(mass, x, y, height) of every mass of the assembly (root frame)."""
    origins = body_origins(robot)
    height = sum(w.radius for w in robot.wheels) / len(robot.wheels)
    out = [(b.mass, origins[b.name][0] + b.com[0], origins[b.name][1] + b.com[1], height)
           for b in robot.bodies]
    points = contact_points(robot)
    out += [(w.mass, *points[w.name], w.radius) for w in robot.wheels]
    out += [(m, x, y, height) for m, x, y in payloads]
    return out


def support_loads(robot: PlanarRobot, payloads: tuple[Payload, ...] = (),
                  accel: Point = (0.0, 0.0)) -> SupportLoads:
    """The normal loads of the module's model: ``robot`` with point ``payloads`` on its
    root body, its centre of mass accelerating at ``accel`` (m/s², root frame)."""
    ms = masses(robot, payloads)
    weight = GRAVITY * sum(m for m, _, _, _ in ms)
    mx = sum(m * (GRAVITY * x - accel[0] * h) for m, x, _, h in ms)
    my = sum(m * (GRAVITY * y - accel[1] * h) for m, _, y, h in ms)
    points = contact_points(robot)
    active = dict(points)
    while True:
        rows = np.array([(1.0, x, y) for x, y in active.values()])
        normal = rows.T @ rows
        if len(active) < 3 or np.linalg.cond(normal) > 1e12:
            raise ValueError(f"robot '{robot.name}': it tips over (the weight's moments "
                             f"leave only {', '.join(active)} on the ground)")
        coef = np.linalg.solve(normal, np.array([weight, mx, my]))
        loads = dict(zip(active, (float(v) for v in rows @ coef), strict=True))
        worst = min(loads, key=lambda k: loads[k])
        if loads[worst] >= 0.0:
            break
        del active[worst]  # a spring cannot pull: it lifts off, solve over the rest
    return SupportLoads({k: loads.get(k, 0.0) for k in points},
                        tuple(k for k in points if k not in active))


def checked_supports(robot: PlanarRobot, where: str) -> None:
    """A robot file's supports checked (``modeling.supports.check_supports``) and the robot
    standing at rest on its contacts without payload: ``RobotFileError``, one line naming
    ``where``, if it would tip over (every contact but a line of them lifted)."""
    check_supports(robot, where)
    try:
        support_loads(robot)
    except ValueError as exc:
        field = "support" if robot.supports is not None else "wheel"
        raise RobotFileError(f"{where}: field '{field}': {exc}; its supports cannot "
                             "carry it") from None


def static_loads(robot: PlanarRobot, payloads: tuple[Payload, ...] = ()) -> dict[str, float]:
    """The loads at rest (N; lifted supports 0) of :func:`support_loads`."""
    return support_loads(robot, payloads).loads


def describe_loads(loads: SupportLoads) -> str:
    """``name N`` per contact, the lifted ones said as lifted off (never a negative load)."""
    return ", ".join(f"{k} lifted off" if k in loads.lifted else f"{k} {v:.1f}"
                     for k, v in loads.loads.items())
