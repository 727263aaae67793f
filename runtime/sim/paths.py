"""The paper's two paths for any robot with two driven wheels, from the experiment's
``[paths]`` (already scaled to the robot: ``runtime.setting.scale``).

Both are driven-wheel rate profiles integrated through the robot's generated kinematics
(:mod:`runtime.sim.reference`), so every body of the robot (a trailer too) follows a motion
it can make. The wheel rates come from the robot's geometry as measured on its generated
code (:func:`runtime.setting.scale.robot_scale`: wheel radius r, track b, offset d of the
root's frame origin ahead of the driven axle). The first driven wheel is the right one.

* Circle: the root's frame origin (Drishti's C) exactly on a circle of radius R =
  ``circle_radius`` at the angular rate θ̇_d = ``circle_rate``: the axle centre on the
  circle of radius √(R² − d²), heading tangent to it, wheel rates (v ± θ̇_d b/2)/r with
  v = θ̇_d √(R² − d²), after a start-up ramp from rest at (R, R) heading along +x (every
  other body aligned). Scale: R.
* Lawn mower: the paper's square-wave wheel rates made consistent: straight legs with both
  wheels at ``lawnmower_fast``, U-turns with one wheel at ``lawnmower_slow`` (alternately
  left and right), each turn lasting exactly π/ω so the legs are parallel, a leg and a turn
  every ``lawnmower_period`` / 2 on average; from rest at the origin. Scale: the spacing of
  the legs (the U-turn's diameter 2 v/ω of the axle centre).
"""

from __future__ import annotations

import math

import numpy as np

from runtime.bindings.generated import RobotCode
from runtime.experiment.settings import Experiment, PathSettings
from runtime.setting.scale import RobotScale, robot_scale
from runtime.sim.reference import START_AT, Reference, WheelProfile, integrate

PATHS = ("circle", "lawnmower")


def circle_rates(geometry: RobotScale, paths: PathSettings) -> tuple[float, float]:
    """The circle's steady (right, left) wheel rates."""
    radius, rate = paths.circle_radius, paths.circle_rate
    r, b, d = geometry.wheel_radius, geometry.track, geometry.offset
    if not radius > abs(d):
        raise ValueError(f"paths.circle_radius = {radius:g} m must exceed the offset {abs(d):g} "
                         "m of the root's frame origin from the driven axle")
    v = rate * math.sqrt(radius**2 - d**2)
    return (v + rate * b / 2) / r, (v - rate * b / 2) / r


def circle(code: RobotCode, params: dict[str, float], exp: Experiment) -> Reference:
    geometry = robot_scale(code, params)
    paths = exp.paths
    profile = WheelProfile((START_AT,), (circle_rates(geometry, paths),))
    start = np.zeros(code.nq)
    start[:2] = paths.circle_radius, paths.circle_radius
    return integrate(code, "circle", profile, start, params, exp.controller.h,
                     paths.circle_duration, paths.circle_radius)


def lawnmower_profile(geometry: RobotScale, paths: PathSettings,
                      duration: float) -> WheelProfile:
    """The lawn mower's wheel-rate switches up to ``duration``."""
    r, b = geometry.wheel_radius, geometry.track
    fast, slow = paths.lawnmower_fast, paths.lawnmower_slow
    turn_time = math.pi / (r * (fast - slow) / b)  # half a turn at rate ω
    leg = paths.lawnmower_period / 2 - turn_time / 2  # a full cycle lasts T on average
    times, jumps = [START_AT], [(fast, fast)]
    t, left = START_AT + leg, True
    while t < duration:
        drop = (0.0, slow - fast) if left else (slow - fast, 0.0)
        times += [t, t + turn_time]
        jumps += [drop, (-drop[0], -drop[1])]
        t += turn_time + leg
        left = not left
    return WheelProfile(tuple(times), tuple(jumps))


def leg_spacing(geometry: RobotScale, paths: PathSettings) -> float:
    """Distance between neighbouring legs: the U-turn's diameter 2 v/ω of the axle centre."""
    r, b = geometry.wheel_radius, geometry.track
    fast, slow = paths.lawnmower_fast, paths.lawnmower_slow
    v, w = r * (fast + slow) / 2, r * (fast - slow) / b
    return 2 * v / w


def lawnmower(code: RobotCode, params: dict[str, float], exp: Experiment) -> Reference:
    geometry = robot_scale(code, params)
    duration = exp.paths.lawnmower_duration
    profile = lawnmower_profile(geometry, exp.paths, duration)
    return integrate(code, "lawnmower", profile, np.zeros(code.nq), params, exp.controller.h,
                     duration, leg_spacing(geometry, exp.paths))


def reference(code: RobotCode, params: dict[str, float], exp: Experiment,
              path: str) -> Reference:
    """The path named ``path`` (one of :data:`PATHS`) for the robot and experiment."""
    if path not in PATHS:
        raise ValueError(f"path must be one of {', '.join(PATHS)}, got {path!r}")
    return circle(code, params, exp) if path == "circle" else lawnmower(code, params, exp)
