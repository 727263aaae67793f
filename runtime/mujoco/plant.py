"""MuJoCo as a plant of the one closed loop (``[plant] model = "mujoco"``).

The engine runs the MJCF that ``modeling.mjcf_export`` writes from the robot's layout: a
bodies-and-wheels robot's ``LAYOUT`` from its generated ``robot.py``, a ``[lumped]`` or
``[physical]`` robot's from its parameters (``modeling.planar_robot.from_lumped``). Its
planar inertias are the derived model's; what differs is physics the derivation assumed
away: wheels that roll only as far as friction lets them (μ, ``[plant] friction``), soft
contacts, a tyre's width, a body that may pitch and roll on its supports, and exact
(non-smoothed) Coulomb bearing friction.

The :class:`runtime.sim.plant.Plant` calls:

* ``start(q0)``: the robot flat at q0, let settle on its contacts for ``SETTLE`` s with no
  torque, then put back at q0's planar pose, at rest;
* ``set_parameters``: nothing (the engine's robot is its MJCF; a bodies-and-wheels robot
  with other parameters than its description's is refused when the plant is built);
* ``set_payload``: the payload bodies' masses (welded to the root body at the
  experiment's points), the schedule applied in the engine;
* ``set_faults``: a traction loss scales the wheel's friction coefficient by (1 − loss);
  a torque limit clips what ``actuate`` delivers;
* ``advance``: ``nsub`` engine steps of ``dt`` under the held torque (MuJoCo's
  ``implicitfast`` integrator); False if the state is non-finite or MuJoCo flagged a
  diverging acceleration;
* ``q`` and ``wheels``: q read off the engine (:mod:`runtime.mujoco.coordinates`), the
  driven wheels' hinge angles and rates (what their encoders see: rolling and slip).
"""

from __future__ import annotations

import logging
from collections.abc import Mapping

import mujoco
import numpy as np
from numpy.typing import NDArray

from modeling.mjcf_export import PAYLOAD_PLACEHOLDER_MASS, ContactSettings, mjcf
from modeling.planar_robot import PlanarRobot
from runtime.bindings.generated import RobotCode
from runtime.experiment.settings import Experiment
from runtime.mujoco.coordinates import CoordinateMap
from runtime.setting.layout import robot_layout

LOG = logging.getLogger("wmr.mujoco")


def _engine_warning(text: str) -> None:
    """MuJoCo's warnings, which it prints on the terminal and appends to MUJOCO_LOG.TXT in
    the working directory by default, go to the log instead: a run
    that diverges ("Nan, Inf or huge value …", on purpose in a stability bisection) is
    detected by :meth:`MujocoPlant.advance` from the engine's warning counters and reported
    by the loop; anything else is a warning of the log."""
    if "The simulation is unstable" in text:
        LOG.debug("MuJoCo: %s", text)
    else:
        LOG.warning("MuJoCo: %s", text)


mujoco.set_mju_user_warning(_engine_warning)

Array = NDArray[np.float64]
SETTLE = 0.3  # s the robot settles on its contacts before a run


def contact_settings(exp: Experiment) -> ContactSettings:
    """The MJCF's contact, actuator and payload settings of an experiment."""
    pl = exp.plant
    return ContactSettings(
        friction=pl.friction, tyre_width=pl.tyre_width,
        contact_timeconst=pl.contact_timeconst, timestep=exp.controller.h / pl.substeps,
        tau_max=exp.controller.tau_max, viscous=pl.viscous, coulomb=pl.coulomb,
        payloads=((pl.fixed_payload_x, pl.fixed_payload_y),
                  (pl.extra_payload_x, pl.extra_payload_y)),
    )


class MujocoPlant:
    """The robot in MuJoCo (see the module docstring)."""

    def __init__(self, code: RobotCode, exp: Experiment, robot: PlanarRobot) -> None:
        self.robot = robot
        self.contact = contact_settings(exp)
        self.xml = mjcf(robot, self.contact)
        self.model = mujoco.MjModel.from_xml_string(self.xml)
        self.data = mujoco.MjData(self.model)
        self.map = CoordinateMap(self.model, robot)
        if self.map.nq != code.nq or len(self.map.driven) != code.nu:
            raise ValueError(f"robot '{code.name}': its layout has {self.map.nq} coordinates "
                             f"and {len(self.map.driven)} driven wheels, its generated code "
                             f"{code.nq} and {code.nu}")
        self.nq, self.nu = code.nq, code.nu
        self.payload_ids = [int(self.model.body(f"payload_{i}").id) for i in range(2)]
        driven = [w for w in robot.ordered_wheels() if w.driven]
        self.tyres = [int(self.model.geom(f"tyre_{w.name}").id) for w in driven]
        self.limit = np.full(self.nu, np.inf)
        self.yaw = 0.0
        self.driven_bodies = [(int(self.model.body(f"wheel_{w.name}").id),
                               int(self.model.body(w.body).id), w.radius) for w in driven]

    def start(self, q0: Array) -> None:
        m, d = self.model, self.data
        mujoco.mj_resetData(m, d)
        self.map.set_pose(d, q0)
        d.ctrl[:] = 0.0
        mujoco.mj_step(m, d, nstep=max(1, round(SETTLE / m.opt.timestep)))
        self.map.set_pose(d, q0)
        d.qvel[:] = 0.0
        d.qacc_warmstart[:] = 0.0
        mujoco.mj_forward(m, d)
        self.yaw = float(q0[self.map.yaw_index[self.robot.root.name]])

    def set_parameters(self, params: Mapping[str, float]) -> None:
        """Nothing: the engine's robot is its MJCF (see :func:`robot_layout`)."""

    def set_payload(self, masses: Array) -> None:
        """The masses (kg) of the experiment's fixed and extra payloads, point masses at
        their stated points on the root body."""
        for body, mass in zip(self.payload_ids, masses, strict=True):
            self.model.body_mass[body] = max(float(mass), PAYLOAD_PLACEHOLDER_MASS)

    def set_faults(self, traction_loss: Array, torque_limit: Array) -> None:
        for geom, loss in zip(self.tyres, traction_loss, strict=True):
            self.model.geom_friction[geom, 0] = self.contact.friction * (1.0 - float(loss))
        self.limit = torque_limit

    def actuate(self, tau: Array) -> list[float]:
        lim = self.limit
        return [float(np.clip(tau[i], -lim[i], lim[i])) for i in range(self.nu)]

    def advance(self, tau: list[float], dt: float, nsub: int) -> bool:
        if nsub == 0:
            return True
        m, d = self.model, self.data
        m.opt.timestep = dt
        d.ctrl[:] = tau
        before = int(d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number)
        mujoco.mj_step(m, d, nstep=nsub)
        bad = int(d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number) > before
        return not bad and bool(np.all(np.isfinite(d.qpos)) and np.all(np.isfinite(d.qvel)))

    @property
    def q(self) -> Array:
        q = self.map.q(self.data, self.yaw)
        self.yaw = float(q[self.map.yaw_index[self.robot.root.name]])
        return q

    def slip(self) -> Array:
        """Each driven wheel's longitudinal slip speed (m/s): its rim speed r ω less its
        centre's speed along its body's heading (0 while it rolls; > 0 when it spins
        forward on the floor)."""
        m, d = self.model, self.data
        out = np.empty(self.nu)
        vel = np.empty(6)
        for i, ((wheel, body, radius), (_, _, dadr)) in enumerate(
                zip(self.driven_bodies, self.map.driven, strict=True)):
            mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_BODY, wheel, vel, 0)
            heading = d.xmat[body].reshape(3, 3)[:, 0]
            out[i] = radius * d.qvel[dadr] - float(vel[3:6] @ heading)
        return out

    def wheels(self) -> tuple[Array, Array]:
        d = self.data
        angles = np.array([d.qpos[qadr] for _, qadr, _ in self.map.driven])
        rates = np.array([d.qvel[dadr] for _, _, dadr in self.map.driven])
        return angles, rates


def mujoco_plant(code: RobotCode, exp: Experiment, base: Mapping[str, float]) -> MujocoPlant:
    """The MuJoCo plant of a robot with plant parameters ``base`` (before payload)."""
    return MujocoPlant(code, exp, robot_layout(code, base))
