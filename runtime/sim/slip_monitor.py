"""A slip monitor from the constraint multipliers: the force each driven wheel must transmit,
against what friction lets it (μ N, a friction circle).

The forces are the generated ``<prefix>_wheel_contact_forces`` (``codegen.contact_forces``):
the multipliers λ of (9), M q̈ + H = B τ − Aᵀ λ, solved from its dependent rows with q̈
from the minimal forward dynamics (the route of (10)–(12)), in newtons. Per driven wheel:

* F_x, the ground's force along the wheel's heading (its rolling row's multiplier), given
  the net torque τ − τ_f (τ_f the bearing friction the plant applies: viscous and
  tanh-smoothed Coulomb, as ``runtime.sim.plant.GeneratedPlant``); it equals
  (τ − τ_f − J θ̈)/r, the wheel's own row of (9) (tests/generated/test_contact_forces.py);
* F_y, the ground's force along the axle (positive to the left): an axle's wheels share
  one no-side-slip row, whose multiplier is the axle's lateral force. The rigid model does
  not split it (statically indeterminate); **assumption**: it is split between that axle's
  wheels in proportion to their static normal loads, F_y,w = F_y,axle N_w / Σ_axle N
  (equal friction use across the axle; ``LATERAL_WHEELS`` of the generated robot.py says
  which wheels share a row).

N_w is the wheel's static load (``modeling.mjcf_export.static_loads``, the payload on
board included). The wheel keeps grip while √(F_x² + F_y²) ≤ μ N_w; the margin
μ N_w − √(F_x² + F_y²) (N) says how close each sample runs to slipping, and
max_w √(F_x² + F_y²)/N_w is the friction coefficient the sample needs. The true parameters
enter through the controllers' model (Drishti: the lateral first moment K_lat of an
off-axis payload is left out). :class:`MonitoredPlant` puts the monitor on any plant of
the loop and records it along a run; ``runtime.plant_comparison`` checks its predicted
onset of slip against the wheel slip MuJoCo measures.
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
from runtime.sim.plant import COULOMB_SPEED, Plant

Array = NDArray[np.float64]


class SlipMonitor:
    """The traction of a robot's driven wheels (see the module docstring)."""

    def __init__(self, code: RobotCode, robot: PlanarRobot, exp: Experiment) -> None:
        driven = getattr(code.robot, "DRIVEN_WHEELS", None)
        rows = getattr(code.robot, "LATERAL_WHEELS", None)
        if driven is None or rows is None or not hasattr(code.model, "wheel_contact_forces"):
            raise ValueError(f"robot '{code.name}': its generated code has no "
                             "wheel_contact_forces (generated before the slip monitor); "
                             "regenerate it with `wmr model`")
        names = {w.name for w in robot.wheels}
        unknown = [w for w in (*driven, *(w for r in rows for w in r)) if w not in names]
        if unknown:
            raise ValueError(f"robot '{code.name}': wheel '{unknown[0]}' of the generated "
                             "contact forces is not in the robot's layout")
        self.code, self.robot = code, robot
        self.driven: tuple[str, ...] = tuple(driven)
        self.rows: tuple[tuple[str, ...], ...] = tuple(tuple(r) for r in rows)
        self.viscous, self.coulomb = exp.plant.viscous, exp.plant.coulomb
        pl = exp.plant
        self.points = ((pl.fixed_payload_x, pl.fixed_payload_y),
                       (pl.extra_payload_x, pl.extra_payload_y))
        self._cache: dict[tuple[float, ...], tuple[Array, Array]] = {}

    def _loads(self, masses: Array) -> tuple[Array, Array]:
        """(N_w of each driven wheel, the share of its axle's lateral force it takes:
        a (driven × rows) matrix), with the payloads of ``masses`` on board."""
        key = tuple(float(m) for m in masses)
        if key not in self._cache:
            loads = static_loads(self.robot, tuple((m, x, y) for m, (x, y)
                                                   in zip(key, self.points, strict=True)))
            share = np.zeros((len(self.driven), len(self.rows)))
            for k, row in enumerate(self.rows):
                total = sum(loads[w] for w in row)
                for i, w in enumerate(self.driven):
                    if w in row:
                        share[i, k] = loads[w] / total
            self._cache[key] = (np.array([loads[w] for w in self.driven]), share)
        return self._cache[key]

    def normal_loads(self, masses: Array) -> Array:
        """N_w (N) of each driven wheel with the experiment's payloads of ``masses`` (kg:
        fixed, extra) on board."""
        return self._loads(masses)[0]

    def shares(self, masses: Array) -> Array:
        """Each driven wheel's share of its axle's lateral force, N_w / Σ_axle N (the
        ``shares`` input of the generated ``<prefix>_traction_check``)."""
        return np.asarray(self._loads(masses)[1].sum(axis=1))

    def contact_forces(self, q: Array, rates: Array, tau: Array, params: Mapping[str, float],
                       masses: Array) -> tuple[Array, Array]:
        """(F_x, F_y) (N) of each driven wheel at the true state (q, driven-wheel rates)
        under the applied torque ``tau``, with the true parameters ``params``: the generated
        contact forces, the axle's lateral force split by static load (module docstring)."""
        rates = np.asarray(rates, dtype=np.float64)
        friction = self.viscous * rates + self.coulomb * np.tanh(rates / COULOMB_SPEED)
        net = np.asarray(tau, dtype=np.float64) - friction
        fx, fy = self.code.model.wheel_contact_forces(q, rates, net, dict(params))
        share = self._loads(masses)[1]
        return (np.asarray(fx, dtype=np.float64),
                share @ np.asarray(fy, dtype=np.float64).reshape(-1))

    def forces(self, q: Array, rates: Array, tau: Array, params: Mapping[str, float],
               masses: Array | None = None) -> Array:
        """|F| (N) each driven wheel must transmit to roll: √(F_x² + F_y²)."""
        fx, fy = self.contact_forces(q, rates, tau, params,
                                     np.zeros(2) if masses is None else masses)
        return np.asarray(np.hypot(fx, fy))

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
                                     np.array(applied), self.params, self.masses)
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
