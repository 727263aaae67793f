"""The true robot of a closed loop: the :class:`Plant` protocol and its first implementation.

A plant is anything that advances the true robot under zero-order hold and says what its
sensors would read; the loop (``runtime.sim.loop``) never knows which. The protocol is
small on purpose (a physics engine, MuJoCo in ``runtime.mujoco.plant``, implements the same
calls):

* :meth:`Plant.start`: the robot at rest at a configuration q0, no slip;
* :meth:`Plant.set_parameters`: the true parameters (the robot's, its payload included,
  keyed as the generated ``PLANT_PARAMS``), called again whenever the payload changes;
* :meth:`Plant.set_payload`: the masses of the experiment's payloads (fixed, extra) at
  their stated points; a plant whose parameters already carry them ignores it;
* :meth:`Plant.set_faults`: the actuator and contact faults of the coming sample: the
  fraction of each driven wheel's traction lost and each actuator's torque limit;
* :meth:`Plant.actuate`: the torque the actuators deliver for a commanded one (the limit);
* :meth:`Plant.advance`: the robot under that torque, held, for ``nsub`` steps of ``dt``;
  False if its state became non-finite;
* :attr:`Plant.q` and :meth:`Plant.wheels`: the true configuration, and the driven wheels'
  angles and rates as encoders on them see them (rolling plus slip).

Which plant a loop runs is the experiment's ``[plant] model``: the registry
:data:`runtime.plants.PLANTS`, above every plant, builds it. A new plant is a module with its
class, one entry there and its name in ``runtime.experiment.settings.PLANT_MODELS``; the loop
does not change.

:class:`GeneratedPlant` integrates the robot's generated ``<prefix>_plant_state_derivative``
(x = (q, driven-wheel rates), the constrained dynamics in the minimal form) with fixed-step
RK4 in C (``csrc/plant_rk4.c``, compiled for the robot's prefix beside its generated code:
:func:`sim_library`), with viscous and tanh-smoothed Coulomb friction on each driven wheel,
unknown to the controllers, and the slip proxy of a traction loss (see
``runtime.experiment.faults``) with each driven wheel's spin inertia (:func:`spin_inertia_keys`).
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import cache
from pathlib import Path
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from runtime.bindings import cbuild
from runtime.bindings.generated import RobotCode
from runtime.experiment.settings import Experiment

Array = NDArray[np.float64]
CSRC = Path(__file__).resolve().parent / "csrc"
COULOMB_SPEED = 0.05  # rad/s: the Coulomb friction's tanh reaches 76 % of its level here


class Plant(Protocol):
    """The true robot under zero-order hold (see the module docstring)."""

    nq: int  # coordinates of q
    nu: int  # driven wheels (inputs)

    def start(self, q0: Array) -> None: ...

    def set_parameters(self, params: Mapping[str, float]) -> None: ...

    def set_payload(self, masses: Array) -> None: ...

    def set_faults(self, traction_loss: Array, torque_limit: Array) -> None: ...

    def actuate(self, tau: Array) -> list[float]: ...

    def advance(self, tau: list[float], dt: float, nsub: int) -> bool: ...

    @property
    def q(self) -> Array: ...

    def wheels(self) -> tuple[Array, Array]: ...


@cache
def sim_library(c_dir: Path, prefix: str, float32: bool = False) -> cbuild.CLibrary:
    """A robot's generated C (in ``c_dir``, C prefix ``prefix``) with the RK4 plant helper,
    as one library (cached per process; the objects are cached on disk by ``cbuild``)."""
    return cbuild.build(
        float32,
        extra_sources=(CSRC / "plant_rk4.c",),
        extra_headers=((CSRC / "plant_rk4.h").resolve(),),
        c_dir=c_dir,
        prefix=prefix,
        extra_defines=(f"-DSIM_PREFIX={prefix}", f"-DSIM_PREFIX_UPPER={prefix.upper()}",
                       f'-DSIM_PLANT_H="{prefix}_plant.h"'),
    )


def library_for(code: RobotCode, float32: bool = False) -> cbuild.CLibrary:
    """:func:`sim_library` of a robot's generated code."""
    return sim_library(code.c_dir.resolve(), code.prefix, float32)


@cache
def spin_inertia_keys(code: RobotCode) -> tuple[str, ...] | None:
    """Per driven wheel, the parameter that is its spin inertia: the one that adds exactly
    itself to that wheel's diagonal entry of M̄ = Sᵀ M S and nothing elsewhere (Drishti: Iw
    for both wheels; a described robot: J_<wheel angle>). None if a wheel has none (no
    traction-loss fault on that robot)."""
    p = dict(code.params)
    rng = np.random.default_rng(2)
    qs = (np.zeros(code.nq), rng.uniform(-1.0, 1.0, code.nq))
    base = [np.asarray(code.model.minimal_mass_matrix(q, p), dtype=np.float64) for q in qs]
    keys: list[str | None] = [None] * code.nu
    for key in p:
        moved = {**p, key: p[key] + 1.0}
        diffs = [np.asarray(code.model.minimal_mass_matrix(q, moved), dtype=np.float64) - b
                 for q, b in zip(qs, base, strict=True)]
        diag = np.diag(diffs[0])
        unit = (all(np.allclose(d, np.diag(diag), atol=1e-9) for d in diffs)
                and bool(np.all((np.abs(diag) < 1e-9) | (np.abs(diag - 1.0) < 1e-9))))
        for i in range(code.nu):
            if unit and abs(diag[i] - 1.0) < 1e-9 and keys[i] is None:
                keys[i] = key
    return None if any(k is None for k in keys) else tuple(k for k in keys if k)


class GeneratedPlant:
    """The robot's generated plant integrated by RK4 in C, with wheel friction ``viscous``
    (N m s/rad) and ``coulomb`` (N m) and the slip proxy (see the module docstring)."""

    def __init__(self, code: RobotCode, lib: cbuild.CLibrary, viscous: float,
                 coulomb: float) -> None:
        self.code, self.lib = code, lib
        self.nq, self.nu = code.nq, code.nu
        ffi, pre = lib.ffi, code.prefix
        real = f"{pre}_real_t"
        self.nx = code.nq + code.nu
        self.x = ffi.new(f"{real}[{self.nx}]")
        self.slip = ffi.new(f"{real}[{2 * code.nu}]")  # slip angles, then their rates
        self.loss = ffi.new(f"{real}[{code.nu}]")
        self.spin = ffi.new(f"{real}[{code.nu}]")
        self.tau = ffi.new(f"{real}[{code.nu}]")
        self.pp = ffi.new(f"{pre}_plant_params_t *")
        self.friction = ffi.new("sim_friction_t *", [viscous, coulomb, COULOMB_SPEED])
        self.act = list(code.actuated)
        self.slipping = False
        self.limit = np.full(code.nu, np.inf)
        self.spin_keys = spin_inertia_keys(code)

    def start(self, q0: Array) -> None:
        self.x[0:self.nx] = [*(float(v) for v in q0), *([0.0] * self.nu)]
        self.slip[0:2 * self.nu] = [0.0] * (2 * self.nu)

    def set_parameters(self, params: Mapping[str, float]) -> None:
        cbuild.fill_params(self.pp, params, self.code.controllers.C_FIELD_NAMES)
        if self.spin_keys is not None:
            self.spin[0:self.nu] = [float(params[k]) for k in self.spin_keys]

    def set_payload(self, masses: Array) -> None:
        """Nothing: the payload is in the parameters (``plant_params_with_payload``)."""

    def set_faults(self, traction_loss: Array, torque_limit: Array) -> None:
        """Traction lost per wheel (0: none) and torque limits (inf: none) for the coming
        sample. A wheel whose traction is back stops spinning at once (the contact
        dissipates the spin); its slip angle stays in the encoder count."""
        self.slipping = bool(np.any(traction_loss > 0))
        if self.slipping:
            if self.spin_keys is None:
                raise ValueError(f"robot '{self.code.name}': no parameter is its driven "
                                 "wheels' spin inertia; a traction loss cannot be simulated")
            self.loss[0:self.nu] = [float(v) for v in traction_loss]
        for i in range(self.nu):
            if traction_loss[i] == 0:
                self.slip[self.nu + i] = 0.0
        self.limit = torque_limit

    def actuate(self, tau: Array) -> list[float]:
        lim = self.limit
        return [float(np.clip(tau[i], -lim[i], lim[i])) for i in range(self.nu)]

    def advance(self, tau: list[float], dt: float, nsub: int) -> bool:
        if nsub == 0:
            return True
        self.tau[0:self.nu] = tau
        clib = self.lib.lib
        if self.slipping:
            status = clib.sim_plant_advance_slip(self.pp, self.friction, self.spin, self.x,
                                                 self.slip, self.tau, self.loss, dt, nsub)
        else:
            status = clib.sim_plant_advance(self.pp, self.friction, self.x, self.tau, dt, nsub)
        return bool(status == 0)

    @property
    def q(self) -> Array:
        return np.array(self.lib.ffi.unpack(self.x, self.nq), dtype=np.float64)

    def wheels(self) -> tuple[Array, Array]:
        x = self.lib.ffi.unpack(self.x, self.nx)
        slip = self.lib.ffi.unpack(self.slip, 2 * self.nu)
        angles = np.array([x[i] for i in self.act]) + np.array(slip[:self.nu])
        rates = np.array(x[self.nq:]) + np.array(slip[self.nu:])
        return angles, rates


def plant_base(code: RobotCode, nominal: Mapping[str, float],
               plant_params: Mapping[str, float] | None = None) -> dict[str, float]:
    """The simulated robot's plant parameters before payload: ``plant_params``, else the
    nominal model with the plant-only parameters at the robot's defaults (e.g. K_lat = 0)."""
    return dict({**code.plant_defaults, **nominal} if plant_params is None else plant_params)


def generated_plant(code: RobotCode, lib: cbuild.CLibrary, exp: Experiment) -> GeneratedPlant:
    """The ``[plant] model = "generated"`` plant: the generated model with the experiment's
    wheel friction."""
    return GeneratedPlant(code, lib, exp.plant.viscous, exp.plant.coulomb)
