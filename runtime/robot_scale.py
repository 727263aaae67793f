"""A robot's size as its generated code sees it, and the paper's experiment scaled to it.

Everything is measured on the generated model at q = 0, so it holds for any robot:

* wheel radius r: the root's speed when both driven wheels turn at 1 rad/s;
* track b: 2 r / θ̇ when they turn at ±1 rad/s (θ̇ = 2 r / b for a differential drive);
* effective mass m_e = (1, 1) M̄ (1, 1)ᵀ / r²: the inertia the motors feel in straight
  motion, wheels and towed bodies included (Drishti: m + 2 I_w / r² = 51.2 kg).

The paper's setting (Drishti, h = 0.1 s) is scaled by ``size`` = b / 0.414 m and
``heft`` = m_e / 51.2 kg: paths by ``size`` (so accelerations scale by ``size`` too),
payloads by ``heft`` (the same fraction of the robot), their positions by ``size``,
torque limit and friction by ``heft · size · r / 0.096 m`` (the torque the same
fractional acceleration needs). A field an experiment file sets keeps its value: only the
fields left at the paper's default are scaled.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from typing import Any

import numpy as np

from runtime.closed_loop import velocities
from runtime.experiment import ControllerSettings, Experiment, PlantSettings
from runtime.generated_modules import RobotCode
from runtime.paper.paths import DRISHTI_MASS, DRISHTI_RADIUS, DRISHTI_TRACK


@dataclass(frozen=True)
class RobotScale:
    """Driven-wheel radius, track and effective mass (see the module docstring)."""

    wheel_radius: float
    track: float
    mass: float

    @property
    def size(self) -> float:
        """Length ratio to Drishti (track / 0.414 m)."""
        return self.track / DRISHTI_TRACK

    @property
    def heft(self) -> float:
        """Effective-mass ratio to Drishti."""
        return self.mass / DRISHTI_MASS

    @property
    def inverse_size(self) -> float:
        """1 / size: a gain per metre of path (the PI tracker's k_theta)."""
        return 1.0 / self.size

    @property
    def inverse_area(self) -> float:
        """1 / size²: a gain per square metre of path (the PI tracker's k_y)."""
        return 1.0 / self.size**2

    @property
    def torque(self) -> float:
        """Torque ratio to Drishti for the same path scaled by ``size``."""
        return self.heft * self.size * self.wheel_radius / DRISHTI_RADIUS


def robot_scale(code: RobotCode, params: dict[str, float]) -> RobotScale:
    """Radius, track and effective mass of a two-wheel-driven robot from its generated code."""
    if code.nu != 2:
        raise ValueError(
            f"robot '{code.name}': the paper's experiment scales to a differential drive "
            f"(two driven wheels); it has {code.nu}"
        )
    q = np.zeros(code.nq)
    forward = velocities(code, q, np.array([1.0, 1.0]), params)
    spin = velocities(code, q, np.array([1.0, -1.0]), params)
    r = float(np.hypot(forward[0], forward[1]))
    turn = abs(float(spin[2]))
    if r <= 0 or turn <= 0:
        raise ValueError(f"robot '{code.name}': its driven wheels neither drive nor turn it")
    ones = np.ones(2)
    mass = float(ones @ code.model.minimal_mass_matrix(q, params) @ ones) / r**2
    return RobotScale(r, 2 * r / turn, mass)


def inertial_keys(code: RobotCode, params: dict[str, float]) -> tuple[str, ...]:
    """The parameters the kinematics does not depend on (masses, inertias, first moments):
    the ones an uncertainty box or a payload changes."""
    rng = np.random.default_rng(3)
    q = rng.uniform(-1.0, 1.0, code.nq)
    eta = rng.uniform(-1.0, 1.0, code.nu)
    base = velocities(code, q, eta, params)
    keys = []
    for key in params:
        moved = {**params, key: params[key] * 1.5 + 0.1}
        if np.allclose(velocities(code, q, eta, moved), base, rtol=1e-14, atol=1e-14):
            keys.append(key)
    return tuple(keys)


_SCALED = {
    "pi_ky": "inverse_area",
    "pi_ktheta": "inverse_size",
    "tau_max": "torque",
    "viscous": "torque",
    "coulomb": "torque",
    "fixed_payload": "heft",
    "extra_payload": "heft",
    "fixed_payload_x": "size",
    "fixed_payload_y": "size",
    "extra_payload_x": "size",
    "extra_payload_y": "size",
}


def scaled_experiment(exp: Experiment, scale: RobotScale) -> tuple[Experiment, list[str]]:
    """``exp`` with every scaled field that is still at the paper's default multiplied by its
    ratio, and one line per field saying what was done."""
    lines = [
        f"robot scale: wheel radius {scale.wheel_radius:.4g} m, track {scale.track:.4g} m, "
        f"effective mass {scale.mass:.4g} kg (Drishti: {DRISHTI_RADIUS} m, {DRISHTI_TRACK} m, "
        f"{DRISHTI_MASS:.4g} kg)",
        f"paths: circle radius and lawn-mower legs x {scale.size:.4g} (size)",
    ]
    sections: dict[str, tuple[Any, Any]] = {
        "controller": (exp.controller, ControllerSettings()),
        "plant": (exp.plant, PlantSettings()),
    }
    changed: dict[str, dict[str, Any]] = {"controller": {}, "plant": {}}
    for section, (settings, default) in sections.items():
        for f in fields(settings):
            if f.name not in _SCALED:
                continue
            value, paper = getattr(settings, f.name), getattr(default, f.name)
            ratio_name = _SCALED[f.name]
            if paper == 0:
                continue
            if value != paper:
                lines.append(f"{section}.{f.name} = {value:g} (set by the experiment; kept)")
                continue
            ratio = float(getattr(scale, ratio_name))
            changed[section][f.name] = paper * ratio
            lines.append(
                f"{section}.{f.name} = {paper * ratio:.4g} (paper {paper:g} x {ratio:.4g}, "
                f"{ratio_name})"
            )
    out = replace(exp, controller=replace(exp.controller, **changed["controller"]),
                  plant=replace(exp.plant, **changed["plant"]))
    return out, lines
