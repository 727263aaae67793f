"""A robot's size as its generated code sees it, and an experiment scaled to it.

Everything is measured on the generated model at q = 0, so it holds for any robot with two
driven wheels:

* wheel radius r: the root's speed when both driven wheels turn at 1 rad/s;
* track b: 2 r / θ̇ when they turn at ±1 rad/s (θ̇ = 2 r / b for a differential drive);
* offset d: how far ahead of the driven axle the root's frame origin is (its lateral
  speed / θ̇ when the wheels turn at ±1 rad/s; Drishti's C);
* effective mass m_e = (1, 1) M̄ (1, 1)ᵀ / r²: the inertia the motors feel in straight
  motion, wheels and towed bodies included (Drishti: m + 2 I_w / r²).

The experiment's defaults are the paper's setting for ``settings.PAPER_ROBOT`` (Drishti);
:func:`scaled_experiment` scales them to a robot by the ratios of its measures to that
robot's, measured the same way (so Drishti's are exactly 1): ``size`` = b / b_paper,
``heft`` = m_e / m_e,paper, ``torque`` = heft · size · r / r_paper (the torque the same
fractional acceleration needs), ``speed`` = size · r_paper / r (wheel rates that give
Drishti's speeds times ``size``). Paths and payload positions scale by ``size`` (so
accelerations scale by ``size`` too), payloads by ``heft``, torque limit and friction by
``torque``, the lawn mower's and ROC's wheel rates by ``speed``, the PI path tracker's
gains in 1/m and 1/m² by 1/size and 1/size². A field an experiment file sets keeps its
value: only the fields left at the paper's default are scaled.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from functools import cache
from typing import Any

import numpy as np

from runtime.bindings.generated import RobotCode
from runtime.bindings.robots import code_in, generated_folder
from runtime.experiment.settings import (
    PAPER_ROBOT,
    ControllerSettings,
    Experiment,
    PathSettings,
    PlantSettings,
)


@dataclass(frozen=True)
class RobotScale:
    """Driven-wheel radius, track, offset of the root's frame origin ahead of the driven
    axle and effective mass (see the module docstring)."""

    wheel_radius: float
    track: float
    offset: float
    mass: float


def robot_scale(code: RobotCode, params: dict[str, float]) -> RobotScale:
    """Radius, track, offset and effective mass of a two-wheel-driven robot from its
    generated code."""
    if code.nu != 2:
        raise ValueError(
            f"robot '{code.name}': the paper's experiment scales to a differential drive "
            f"(two driven wheels); it has {code.nu}"
        )
    q = np.zeros(code.nq)
    forward = code.velocities(q, np.array([1.0, 1.0]), params)
    spin = code.velocities(q, np.array([1.0, -1.0]), params)
    r = float(np.hypot(forward[0], forward[1]))
    turn = abs(float(spin[2]))
    if r <= 0 or turn <= 0:
        raise ValueError(f"robot '{code.name}': its driven wheels neither drive nor turn it")
    ones = np.ones(2)
    mass = float(ones @ code.model.minimal_mass_matrix(q, params) @ ones) / r**2
    return RobotScale(r, 2 * r / turn, float(spin[1]) / float(spin[2]), mass)


@cache
def paper_scale() -> RobotScale:
    """The measures of the robot the experiment's defaults are written for."""
    code = code_in(generated_folder(PAPER_ROBOT))
    return robot_scale(code, code.params)


@dataclass(frozen=True)
class Ratios:
    """A robot's measures over the paper robot's (see the module docstring)."""

    size: float
    heft: float
    torque: float
    speed: float
    inverse_size: float
    inverse_size_squared: float


def ratios(scale: RobotScale, paper: RobotScale | None = None) -> Ratios:
    ref = paper_scale() if paper is None else paper
    size = scale.track / ref.track
    heft = scale.mass / ref.mass
    return Ratios(size, heft, heft * size * scale.wheel_radius / ref.wheel_radius,
                  size * ref.wheel_radius / scale.wheel_radius, 1 / size, 1 / size**2)


# field -> the ratio it scales by (a Ratios attribute); fields not named are not scaled
_SCALED = {
    "tau_max": "torque",
    "viscous": "torque",
    "coulomb": "torque",
    "fixed_payload": "heft",
    "extra_payload": "heft",
    "fixed_payload_x": "size",
    "fixed_payload_y": "size",
    "extra_payload_x": "size",
    "extra_payload_y": "size",
    "circle_radius": "size",
    "lawnmower_fast": "speed",
    "lawnmower_slow": "speed",
    "roc_max_rate": "speed",
    "pi_ky": "inverse_size_squared",
    "pi_ktheta": "inverse_size",
}


def scaled_experiment(exp: Experiment, scale: RobotScale) -> tuple[Experiment, list[str]]:
    """``exp`` with every scaled field that is still at the paper's default multiplied by its
    ratio, and one line per field saying what was done (identity for the paper's robot)."""
    ref = paper_scale()
    k = ratios(scale, ref)
    lines = [
        f"robot scale: wheel radius {scale.wheel_radius:.4g} m, track {scale.track:.4g} m, "
        f"effective mass {scale.mass:.4g} kg (the paper's {PAPER_ROBOT}: "
        f"{ref.wheel_radius:.4g} m, {ref.track:.4g} m, {ref.mass:.4g} kg)",
    ]
    sections: dict[str, tuple[Any, Any]] = {
        "controller": (exp.controller, ControllerSettings()),
        "plant": (exp.plant, PlantSettings()),
        "paths": (exp.paths, PathSettings()),
    }
    changed: dict[str, dict[str, Any]] = {name: {} for name in sections}
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
            ratio = float(getattr(k, ratio_name))
            changed[section][f.name] = paper * ratio
            lines.append(
                f"{section}.{f.name} = {paper * ratio:.4g} (paper {paper:g} x {ratio:.4g}, "
                f"{ratio_name.replace('_', ' ')})"
            )
    out = replace(exp, **{name: replace(settings, **changed[name])
                          for name, (settings, _) in sections.items()})
    return out, lines
