"""A slip monitor from the rolling constraints' multipliers: the traction each driven wheel
must transmit, against what friction lets it (μ N).

In the constrained dynamics (9), M q̈ + H = B τ + Aᵀ λ, a driven wheel's angle θ_w enters
the kinetic energy only through its spin, ½ J_w θ̇_w², and the constraints only through its
rolling row v_w · e_x − r_w θ̇_w = 0 (the wheel centre's speed along its heading equals its
rim speed). Its row of (9) is therefore J_w θ̈_w = τ_w − r_w λ_w, and the rolling row's
multiplier λ_w is the longitudinal force the ground must push the wheel with for it to roll:

    F_w = λ_w = (τ_w − τ_f,w − J_w θ̈_w) / r_w,

with θ̈_w from the generated minimal forward dynamics at the true state and parameters
(payload included), τ_f,w the bearing friction the plant applies (viscous and tanh-smoothed
Coulomb, as ``runtime.sim.plant.GeneratedPlant``) and J_w the parameter that is the wheel's
spin inertia (``runtime.sim.plant.spin_inertia_keys``). The wheel keeps grip while
|F_w| ≤ μ N_w; N_w is the wheel's static load (``modeling.mjcf_export.static_loads``, the
payload on board included), so the margin μ N_w − |F_w| (N) says how close each sample runs
to slipping. The lateral multipliers are not in it: two wheels on one axle share one
no-side-slip row, so the rigid model does not split the lateral force between them (that
split is statically indeterminate); the margin is the longitudinal one, the part a start-up
or a braking torque uses up. :class:`MonitoredPlant` puts the monitor on any plant of the
loop and records it along a run; ``runtime.mujoco.comparison`` checks its predicted onset
of slip against the wheel slip MuJoCo measures.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
from numpy.typing import NDArray

from modeling.mjcf_export import static_loads
from modeling.planar_robot import PlanarRobot
from runtime.bindings.generated import RobotCode
from runtime.experiment.settings import Experiment
from runtime.sim.plant import COULOMB_SPEED, Plant, spin_inertia_keys

Array = NDArray[np.float64]


class SlipMonitor:
    """The longitudinal traction of a robot's driven wheels (see the module docstring)."""

    def __init__(self, code: RobotCode, robot: PlanarRobot, exp: Experiment) -> None:
        keys = spin_inertia_keys(code)
        if keys is None:
            raise ValueError(f"robot '{code.name}': no parameter is its driven wheels' spin "
                             "inertia; the slip monitor needs it")
        self.code, self.robot, self.keys = code, robot, keys
        self.driven = [w for w in robot.ordered_wheels() if w.driven]
        self.radii = np.array([w.radius for w in self.driven])
        self.viscous, self.coulomb = exp.plant.viscous, exp.plant.coulomb
        pl = exp.plant
        self.points = ((pl.fixed_payload_x, pl.fixed_payload_y),
                       (pl.extra_payload_x, pl.extra_payload_y))
        self._cache: dict[tuple[float, ...], Array] = {}

    def normal_loads(self, masses: Array) -> Array:
        """N_w (N) of each driven wheel with the experiment's payloads of ``masses`` (kg:
        fixed, extra) on board."""
        key = tuple(float(m) for m in masses)
        if key not in self._cache:
            loads = static_loads(self.robot, tuple((m, x, y) for m, (x, y)
                                                   in zip(key, self.points, strict=True)))
            self._cache[key] = np.array([loads[w.name] for w in self.driven])
        return self._cache[key]

    def forces(self, q: Array, rates: Array, tau: Array, params: Mapping[str, float]) -> Array:
        """F_w (N): the longitudinal force each driven wheel must transmit to roll, at the
        true state (q, driven-wheel rates) under the applied torque, with the true
        parameters ``params``."""
        friction = self.viscous * rates + self.coulomb * np.tanh(rates / COULOMB_SPEED)
        net = np.asarray(tau, dtype=np.float64) - friction
        accel = np.asarray(self.code.model.minimal_forward_dynamics(q, rates, net, dict(params)),
                           dtype=np.float64)
        spin = np.array([float(params[k]) for k in self.keys])
        return np.asarray((net - spin * accel) / self.radii)

    def margin(self, forces: Array, mu: float, masses: Array) -> Array:
        """μ N_w − |F_w| (N): negative where the wheel needs more traction than it has."""
        return np.asarray(mu * self.normal_loads(masses) - np.abs(forces))

    def friction_needed(self, forces: Array, masses: Array) -> float:
        """The smallest μ at which every driven wheel keeps grip: max_w |F_w| / N_w."""
        n = self.normal_loads(masses)
        return float(np.max(np.abs(forces) / n)) if np.all(n > 0) else math.inf


class MonitoredPlant:
    """Any plant with the slip monitor on it: at every sample, when the actuators deliver
    a torque, the traction each driven wheel needs (``forces``, N) and the friction
    coefficient that needs (``needed``) at the plant's true state and parameters."""

    def __init__(self, inner: Plant, monitor: SlipMonitor) -> None:
        self.inner, self.monitor = inner, monitor
        self.nq, self.nu = inner.nq, inner.nu
        self.params: dict[str, float] = {}
        self.masses = np.zeros(2)
        self.forces: list[Array] = []
        self.needed: list[float] = []

    def start(self, q0: Array) -> None:
        self.inner.start(q0)

    def set_parameters(self, params: Mapping[str, float]) -> None:
        self.params = dict(params)
        self.inner.set_parameters(params)

    def set_payload(self, masses: Array) -> None:
        self.masses = np.asarray(masses, dtype=np.float64)
        self.inner.set_payload(masses)

    def set_faults(self, traction_loss: Array, torque_limit: Array) -> None:
        self.inner.set_faults(traction_loss, torque_limit)

    def actuate(self, tau: Array) -> list[float]:
        applied = self.inner.actuate(tau)
        forces = self.monitor.forces(self.inner.q, self.inner.wheels()[1],
                                     np.array(applied), self.params)
        self.forces.append(forces)
        self.needed.append(self.monitor.friction_needed(forces, self.masses))
        return applied

    def advance(self, tau: list[float], dt: float, nsub: int) -> bool:
        return self.inner.advance(tau, dt, nsub)

    @property
    def q(self) -> Array:
        return self.inner.q

    def wheels(self) -> tuple[Array, Array]:
        return self.inner.wheels()
