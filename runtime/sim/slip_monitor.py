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

N_w is the wheel's normal load from the one load model (``modeling.contact_loads``: equal
contact springs, a support in tension lifted off), the payload on board included, and with
load transfer (:meth:`SlipMonitor.traction`, what :class:`MonitoredPlant` records): the
assembly's horizontal acceleration is the ground's total force on it over its mass (Newton:
the driven wheels' F_x along their bodies' headings and every axle's F_y along its axle;
passive wheels roll freely and the supports are frictionless), and the inertia at the
axle height moves load across the contacts. The wheel keeps grip while
√(F_x² + F_y²) ≤ μ N_w; the margin
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

from modeling.contact_loads import support_loads
from modeling.planar_robot import PlanarRobot
from runtime.bindings.generated import RobotCode
from runtime.experiment.settings import Experiment
from runtime.sim.payload import payload_masses, plant_params_at
from runtime.sim.plant import COULOMB_SPEED, Plant
from runtime.sim.reference import Reference

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
        order = robot.coordinate_order()
        yaw = {c[4:]: i for i, c in enumerate(order) if c.startswith("yaw:")}
        body = {w.name: w.body for w in robot.wheels}
        root = yaw[robot.root.name]
        # where each force's body heading sits in q, relative to the root's
        self._driven_yaw = [(yaw[body[w]], root) for w in self.driven]
        self._row_yaw = [(yaw[body[r[0]]], root) for r in self.rows]
        self._mass = robot.total_mass()

    def _loads(self, masses: Array, accel: tuple[float, float] = (0.0, 0.0)
               ) -> tuple[Array, Array]:
        """(N_w of each driven wheel, the share of its axle's lateral force it takes:
        a (driven × rows) matrix), with the payloads of ``masses`` on board and the
        assembly accelerating at ``accel`` (root frame; at rest: cached)."""
        key = tuple(float(m) for m in masses)
        if accel == (0.0, 0.0) and key in self._cache:
            return self._cache[key]
        try:
            loads = support_loads(self.robot, tuple((m, x, y) for m, (x, y)
                                                    in zip(key, self.points, strict=True)),
                                  accel).loads
        except ValueError:  # it would tip over: no wheel can count on its load
            loads = dict.fromkeys((w.name for w in self.robot.wheels), 0.0)
        share = np.zeros((len(self.driven), len(self.rows)))
        for k, row in enumerate(self.rows):
            total = sum(loads[w] for w in row)
            for i, w in enumerate(self.driven):
                if w in row and total > 0:
                    share[i, k] = loads[w] / total
        out = (np.array([loads[w] for w in self.driven]), share)
        if accel == (0.0, 0.0):
            self._cache[key] = out
        return out

    def normal_loads(self, masses: Array) -> Array:
        """N_w (N) of each driven wheel with the experiment's payloads of ``masses`` (kg:
        fixed, extra) on board."""
        return self._loads(masses)[0]

    def shares(self, masses: Array) -> Array:
        """Each driven wheel's share of its axle's lateral force, N_w / Σ_axle N (the
        ``shares`` input of the generated ``<prefix>_traction_check``)."""
        return np.asarray(self._loads(masses)[1].sum(axis=1))

    def _multipliers(self, q: Array, rates: Array, tau: Array,
                     params: Mapping[str, float]) -> tuple[Array, Array]:
        """(F_x of each driven wheel, F_y of each axle row) from the generated forces."""
        rates = np.asarray(rates, dtype=np.float64)
        friction = self.viscous * rates + self.coulomb * np.tanh(rates / COULOMB_SPEED)
        net = np.asarray(tau, dtype=np.float64) - friction
        fx, fy = self.code.model.wheel_contact_forces(q, rates, net, dict(params))
        return (np.asarray(fx, dtype=np.float64),
                np.asarray(fy, dtype=np.float64).reshape(-1))

    def contact_forces(self, q: Array, rates: Array, tau: Array, params: Mapping[str, float],
                       masses: Array) -> tuple[Array, Array]:
        """(F_x, F_y) (N) of each driven wheel at the true state (q, driven-wheel rates)
        under the applied torque ``tau``, with the true parameters ``params``: the generated
        contact forces, the axle's lateral force split by the loads at rest (module
        docstring; :meth:`traction` splits it by the loads under load transfer)."""
        fx, rows = self._multipliers(q, rates, tau, params)
        return fx, self._loads(masses)[1] @ rows

    def acceleration(self, q: Array, fx: Array, rows: Array, masses: Array
                     ) -> tuple[float, float]:
        """The assembly's horizontal acceleration (m/s², root frame): the ground's force on
        it (driven wheels' F_x along their bodies' headings, each axle's F_y along its
        axle) over its mass, payloads of ``masses`` included."""
        total = np.zeros(2)
        for f, (i, r) in zip(fx, self._driven_yaw, strict=True):
            a = float(q[i] - q[r])
            total += f * np.array([np.cos(a), np.sin(a)])
        for f, (i, r) in zip(rows, self._row_yaw, strict=True):
            a = float(q[i] - q[r])
            total += f * np.array([-np.sin(a), np.cos(a)])
        m = self._mass + float(np.sum(masses))
        return float(total[0] / m), float(total[1] / m)

    def traction_parts(self, q: Array, rates: Array, tau: Array,
                       params: Mapping[str, float], masses: Array
                       ) -> tuple[Array, Array, Array]:
        """(F_x, F_y, N_w) (N) of each driven wheel with load transfer (module docstring)."""
        fx, rows = self._multipliers(q, rates, tau, params)
        n, share = self._loads(masses, self.acceleration(q, fx, rows, masses))
        return fx, share @ rows, n

    def traction(self, q: Array, rates: Array, tau: Array, params: Mapping[str, float],
                 masses: Array) -> tuple[Array, Array]:
        """(|F_w|, N_w) (N) of each driven wheel with load transfer (module docstring):
        the force it must transmit to roll and the normal load it has for it."""
        fx, fy, n = self.traction_parts(q, rates, tau, params, masses)
        return np.asarray(np.hypot(fx, fy)), n

    def along(self, ref: Reference, nominal: Mapping[str, float], exp: Experiment
              ) -> tuple[Array, Array, Array]:
        """(F_x, F_y, N_w) (samples × driven wheels, N) of a robot that tracks ``ref``
        exactly: the torque of the minimal-form inverse dynamics, M̄ η̇_d + H̄, with the
        payload the experiment's schedule has on board at each sample (its point masses
        on ``nominal``), and the load transfer of that motion."""
        act = list(self.code.actuated)
        base = {**self.code.plant_defaults, **nominal}
        out: tuple[list[Array], list[Array], list[Array]] = ([], [], [])
        for t, q, qd, qdd in zip(ref.t, ref.q, ref.qdot, ref.qddot, strict=True):
            params = plant_params_at(self.code, exp, float(t), base)
            model = {k: v for k, v in params.items() if k in nominal}
            m_bar = np.asarray(self.code.model.minimal_mass_matrix(q, model),
                               dtype=np.float64)
            h_bar = np.asarray(self.code.model.minimal_bias_forces(q, qd[act], model))
            rates = qd[act]
            # the plant's bearing friction on top: the monitor takes it off again
            tau = (m_bar @ qdd[act] + h_bar + self.viscous * rates
                   + self.coulomb * np.tanh(rates / COULOMB_SPEED))
            parts = self.traction_parts(q, rates, tau, params, payload_masses(exp, float(t)))
            for acc, part in zip(out, parts, strict=True):
                acc.append(part)
        return np.array(out[0]), np.array(out[1]), np.array(out[2])

    def forces(self, q: Array, rates: Array, tau: Array, params: Mapping[str, float],
               masses: Array | None = None) -> Array:
        """|F| (N) each driven wheel must transmit to roll: √(F_x² + F_y²)."""
        fx, fy = self.contact_forces(q, rates, tau, params,
                                     np.zeros(2) if masses is None else masses)
        return np.asarray(np.hypot(fx, fy))

    def margin(self, forces: Array, mu: float, masses: Array,
               loads: Array | None = None) -> Array:
        """μ N_w − |F_w| (N): negative where the wheel needs more traction than it has
        (N_w: ``loads``, else the loads at rest)."""
        n = self.normal_loads(masses) if loads is None else loads
        return np.asarray(mu * n - np.abs(forces))

    def friction_needed(self, forces: Array, masses: Array,
                        loads: Array | None = None) -> float:
        """The smallest μ at which every driven wheel keeps grip: max_w |F_w| / N_w
        (N_w: ``loads``, else the loads at rest); inf if a driven wheel lifted off."""
        n = self.normal_loads(masses) if loads is None else loads
        return float(np.max(np.abs(forces) / n)) if np.all(n > 0) else math.inf


class MonitoredPlant:
    """Any plant with the slip monitor on it: at every sample, when the actuators deliver
    a torque, the traction each driven wheel needs (``forces``, N), its normal load under
    load transfer (``loads``, N) and the friction coefficient that needs (``needed``) at
    the plant's true state and parameters."""

    def __init__(self, inner: Plant, monitor: SlipMonitor) -> None:
        self.inner, self.monitor = inner, monitor
        self.nq, self.nu = inner.nq, inner.nu
        self.params: dict[str, float] = {}
        self.masses = np.zeros(2)
        self.forces: list[Array] = []
        self.loads: list[Array] = []
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
        forces, loads = self.monitor.traction(self.inner.q, self.inner.wheels()[1],
                                              np.array(applied), self.params, self.masses)
        self.forces.append(forces)
        self.loads.append(loads)
        self.needed.append(self.monitor.friction_needed(forces, self.masses, loads))
        return applied

    def advance(self, tau: list[float], dt: float, nsub: int) -> bool:
        return self.inner.advance(tau, dt, nsub)

    @property
    def q(self) -> Array:
        return self.inner.q

    def wheels(self) -> tuple[Array, Array]:
        return self.inner.wheels()
