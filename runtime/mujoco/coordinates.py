"""The derived model's coordinates q in a MuJoCo model of the robot, and back.

The MJCF of ``modeling.mjcf_export`` has a free root body (qpos: x, y, z, quaternion;
qvel: world linear velocity, body-frame angular velocity), a vertical hinge per hitch
(the relative yaw) and a hinge per wheel. q is ordered as
``modeling.planar_robot.PlanarRobot.coordinate_order`` says: root x, y, yaw; each
further body's absolute yaw; the wheels' angles, driven first.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
from numpy.typing import NDArray

from modeling.planar_robot import PlanarRobot

Array = NDArray[np.float64]


def wrap(angle: float) -> float:
    """``angle`` in [−π, π)."""
    return (angle + math.pi) % (2 * math.pi) - math.pi


def quaternion_yaw(quat: Array) -> float:
    """The heading of a body's x axis projected on the ground, from its quaternion."""
    w, x, y, z = (float(v) for v in quat)
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


class CoordinateMap:
    """Where each entry of q is in a compiled MuJoCo model of ``robot``."""

    def __init__(self, model: mujoco.MjModel, robot: PlanarRobot) -> None:
        self.robot = robot
        self.order = robot.coordinate_order()
        self.nq = len(self.order)
        self.yaw_index = {c[4:]: i for i, c in enumerate(self.order) if c.startswith("yaw:")}
        placed, pending = {robot.root.name}, list(robot.joints)
        self.hitches: list[tuple[str, str, int, int]] = []  # parents before children
        while pending:
            j = next(j for j in pending if j.parent in placed)
            pending.remove(j)
            placed.add(j.child)
            joint = model.joint(f"hitch_{j.child}")
            self.hitches.append((j.parent, j.child, int(joint.qposadr[0]),
                                 int(joint.dofadr[0])))
        self.wheels = [(i, int(model.joint(f"wheel_{c[6:]}").qposadr[0]),
                        int(model.joint(f"wheel_{c[6:]}").dofadr[0]))
                       for i, c in enumerate(self.order) if c.startswith("wheel:")]
        self.driven = [w for w in self.wheels
                       if next(x for x in robot.wheels if f"wheel:{x.name}" ==
                               self.order[w[0]]).driven]
        self.nv = model.nv

    def set_pose(self, data: mujoco.MjData, q: Array) -> None:
        """Put the robot flat at configuration q (height and velocities untouched)."""
        data.qpos[0:2] = q[0:2]
        th = float(q[self.yaw_index[self.robot.root.name]])
        data.qpos[3:7] = [math.cos(th / 2), 0.0, 0.0, math.sin(th / 2)]
        for parent, child, qadr, _ in self.hitches:
            data.qpos[qadr] = q[self.yaw_index[child]] - q[self.yaw_index[parent]]
        for i, qadr, _ in self.wheels:
            data.qpos[qadr] = q[i]

    def q(self, data: mujoco.MjData, previous_yaw: float) -> Array:
        """q of the engine's state; the root's yaw continued from ``previous_yaw`` (q's yaw
        is not wrapped)."""
        out = np.empty(self.nq)
        out[0:2] = data.qpos[0:2]
        yaw = previous_yaw + wrap(quaternion_yaw(data.qpos[3:7]) - previous_yaw)
        out[self.yaw_index[self.robot.root.name]] = yaw
        for parent, child, qadr, _ in self.hitches:
            out[self.yaw_index[child]] = out[self.yaw_index[parent]] + data.qpos[qadr]
        for i, qadr, _ in self.wheels:
            out[i] = data.qpos[qadr]
        return out

    def velocity_map(self) -> Array:
        """J (nv × nq): the engine's qvel of a flat robot moving at q̇ is J q̇."""
        jac = np.zeros((self.nv, self.nq))
        jac[0, 0] = jac[1, 1] = 1.0
        jac[5, self.yaw_index[self.robot.root.name]] = 1.0
        for parent, child, _, dadr in self.hitches:
            jac[dadr, self.yaw_index[child]] += 1.0
            jac[dadr, self.yaw_index[parent]] -= 1.0
        for i, _, dadr in self.wheels:
            jac[dadr, i] = 1.0
        return jac
