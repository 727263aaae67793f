"""The wheel-velocity PI controller with a pose-correcting path tracker, typed by hand in
NumPy for the paper's differential drive (Drishti: the pose is that of the point C, d
ahead of the axle; wheel radius r, track b). Independent of ``modeling/``, ``codegen/``
and ``generated/``: the witness the generated ``wmr_pi`` is compared with.

It is the structure of ros2_control's ``diff_drive_controller`` (wheel-velocity loops on
the driven wheels) under a Kanayama et al. (1990) path tracker, as documented for the
generated controller (``generated/c/wmr_laws.h``, ``minimal_pi_law``):

  e_x = cos θ (x_d − x) + sin θ (y_d − y),  e_y = −sin θ (x_d − x) + cos θ (y_d − y),
  e_θ = θ_d − θ;  v_d = cos θ_d ẋ_d + sin θ_d ẏ_d,  ω_d = θ̇_d;
  v_c = v_d cos e_θ + k_x e_x,  ω_c = ω_d + v_d (k_y e_y + k_θ sin e_θ);
  the wheel rates of (v_c, ω_c): η_r = (v_c + ω_c b/2)/r, η_l = (v_c − ω_c b/2)/r
  (C's forward speed is the axle's: C moves sideways at d ω only);
  I⁺ = clamp(I + k_i h (η_c − η), ±τ_max),  τ = clamp(k_p (η_c − η) + I⁺, ±τ_max).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

Vec = NDArray[np.float64]


@dataclass(frozen=True)
class WheelPIGains:
    kx: float  # 1/s
    ky: float  # 1/m^2
    ktheta: float  # 1/m
    kp: float  # N m s/rad
    ki: float  # N m/rad


class WheelPI:
    """One controller instance: ``step`` returns τ and keeps the integral."""

    def __init__(self, gains: WheelPIGains, r: float, b: float, h: float,
                 tau_max: float) -> None:
        self.g, self.r, self.b, self.h, self.tau_max = gains, r, b, h, tau_max
        self.integral = np.zeros(2)

    def wheel_rates(self, q: Vec, q_des: Vec, qdot_des: Vec) -> Vec:
        """(η_r, η_l) the path tracker asks for."""
        g = self.g
        x, y, th = q[0], q[1], q[2]
        dx, dy = q_des[0] - x, q_des[1] - y
        ex = math.cos(th) * dx + math.sin(th) * dy
        ey = -math.sin(th) * dx + math.cos(th) * dy
        eth = q_des[2] - th
        vd = math.cos(q_des[2]) * qdot_des[0] + math.sin(q_des[2]) * qdot_des[1]
        wd = qdot_des[2]
        vc = vd * math.cos(eth) + g.kx * ex
        wc = wd + vd * (g.ky * ey + g.ktheta * math.sin(eth))
        return np.array([(vc + wc * self.b / 2) / self.r, (vc - wc * self.b / 2) / self.r])

    def step(self, q: Vec, qdot: Vec, q_des: Vec, qdot_des: Vec) -> Vec:
        err = self.wheel_rates(q, q_des, qdot_des) - np.asarray(qdot[3:5], dtype=float)
        self.integral = np.clip(self.integral + self.g.ki * self.h * err, -self.tau_max,
                                self.tau_max)
        return np.clip(self.g.kp * err + self.integral, -self.tau_max, self.tau_max)
