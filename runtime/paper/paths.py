"""The paper's paths as driven-wheel rate profiles, for any differential drive: smooth tanh
steps between constant wheel rates, the paper's path constants, and the paper robot's sizes
that the scaled experiment (:mod:`runtime.robot_scale`) measures other robots against. No
robot's generated code is imported here, so the generic runtime can use it whatever
``generated/`` holds.

:mod:`runtime.paper.references` integrates them through the paper robot's kinematics (31),
:mod:`runtime.robot_paths` through any generated robot's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

R1 = 1.5
THETA_DOT = 0.25
LAWN_A, LAWN_B, LAWN_T = 3.0, 1.6, 25.0
RAMP = 0.3  # s, tanh time constant of every wheel-rate switch
START_AT = 1.0  # s, centre of the start-up ramp
# The paper's robot (Drishti) as runtime.robot_scale measures a robot.
DRISHTI_RADIUS = 0.096  # m, r
DRISHTI_TRACK = 0.414  # m, b
DRISHTI_MASS = 36.0 + 2 * 0.07 / DRISHTI_RADIUS**2  # kg: m + 2 I_w / r²
ROC_MAX_RATE = 8.0  # rad/s: the wheel rates ROC's bounds are sampled over for Drishti


@dataclass(frozen=True)
class WheelProfile:
    """η(t) = Σ_k Δη_k s(t − t_k), s a tanh step: switches at times t_k by Δη_k."""

    times: tuple[float, ...]
    jumps: tuple[tuple[float, float], ...]

    def rates(self, t: float) -> NDArray[np.float64]:
        out = np.zeros(2)
        for tk, (dr, dl) in zip(self.times, self.jumps, strict=True):
            s = 0.5 * (1.0 + math.tanh((t - tk) / RAMP))
            out += s * np.array([dr, dl])
        return out

    def accels(self, t: float) -> NDArray[np.float64]:
        out = np.zeros(2)
        for tk, (dr, dl) in zip(self.times, self.jumps, strict=True):
            # d/dt of the tanh step: sech² written with exp(−2|x|), which cannot overflow
            # (cosh does, 710 ramps from a switch: a path of a few minutes)
            e = math.exp(-2.0 * abs((t - tk) / RAMP))
            ds = 0.5 / RAMP * 4.0 * e / (1.0 + e) ** 2
            out += ds * np.array([dr, dl])
        return out


def lawnmower_profile(
    params: dict[str, float], duration: float, rates: tuple[float, float] = (LAWN_A, LAWN_B)
) -> WheelProfile:
    """The lawn mower's square-wave wheel rates made consistent, for wheel radius
    ``params["r"]`` and track ``params["b"]``; ``rates`` = (straight, inner wheel in a turn)
    in rad/s (the paper's a, b by default)."""
    r, b = params["r"], params["b"]
    fast, slow = rates
    turn_time = math.pi / (r * (fast - slow) / b)  # half a turn at rate ω
    leg = LAWN_T / 2 - turn_time / 2  # straight legs: a full cycle lasts T on average
    times, jumps = [START_AT], [(fast, fast)]
    t, left = START_AT + leg, True
    while t < duration:
        drop = (0.0, slow - fast) if left else (slow - fast, 0.0)
        times += [t, t + turn_time]
        jumps += [drop, (-drop[0], -drop[1])]
        t += turn_time + leg
        left = not left
    return WheelProfile(tuple(times), tuple(jumps))
