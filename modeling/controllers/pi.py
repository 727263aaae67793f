"""The wheel-velocity PI baseline: the controller a mobile-robot user deploys, beside the
paper's four (no model of the dynamics; the kinematics only)."""

from __future__ import annotations

import sympy as sp

from modeling.controllers.common import vec
from modeling.controllers.declaration import (
    ControllerSpec,
    Estimate,
    Kernel,
    KernelArg,
    LawState,
)
from modeling.controllers.fields import Check, ConfigField
from modeling.controllers.model import Formulation
from modeling.robot_model import RobotModel


def wheel_pi_law(
    model: RobotModel,
) -> tuple[sp.Matrix, sp.Matrix, dict[str, tuple[sp.Symbol, ...]]]:
    """The baseline a mobile-robot user deploys: ros2_control's ``diff_drive_controller``
    structure (a wheel-velocity PI loop per driven wheel) under a pose-correcting path
    tracker (Kanayama et al. 1990), generic over robots whose root body carries two driven
    wheels. With the root's pose (x, y, θ) = q[0], q[1], q[heading] and its reference:

      e_x = cos θ Δx + sin θ Δy,  e_y = −sin θ Δx + cos θ Δy,  e_θ = θ_d − θ
      v_d = cos θ_d ẋ_d + sin θ_d ẏ_d,  ω_d = θ̇_d                (the reference's feed-forward)
      v_c = v_d cos e_θ + k_x e_x,  ω_c = ω_d + v_d (k_y e_y + k_θ sin e_θ)
      η_c = A(q)⁻¹ (v_c, ω_c),  A = [[cos θ, sin θ, 0], [0, 0, 1]] S_root(q)

    (A maps the driven-wheel rates η to the root's forward speed and yaw rate, from the
    derived kinematics q̇ = S(q) η; for a differential drive [[r/2, r/2], [r/b, −r/b]]), and
    the wheel-velocity PI with the integral kept in torque units and clamped to ±τ_max (anti
    wind-up):  I⁺ = clamp(I + k_i h (η_c − η), ±τ_max),  τ = k_p (η_c − η) + I⁺.

    Returns (τ, I⁺, input symbols). No model of the dynamics is used: only the kinematics
    (wheel radius and track through the nominal parameters)."""
    if model.nu != 2:
        raise ValueError(f"robot '{model.name}': the wheel-velocity PI controller needs two "
                         f"driven wheels on the root body; it has {model.nu}")
    n = model.nq
    q, qdot = sp.Matrix(model.q), sp.Matrix(model.qdot)
    q_des, qdot_des = vec("qd_", n), vec("qdd_", n)
    integral = vec("I_", model.nu)
    kx, ky, kth, kp, ki = sp.symbols("kx ky ktheta kp ki", real=True)
    h, tau_max = sp.symbols("h tau_max", positive=True)
    th_i = list(model.q).index(model.heading)
    th, thd = q[th_i], q_des[th_i]
    dx, dy = q_des[0] - q[0], q_des[1] - q[1]
    ex = sp.cos(th) * dx + sp.sin(th) * dy
    ey = -sp.sin(th) * dx + sp.cos(th) * dy
    eth = thd - th
    vd = sp.cos(thd) * qdot_des[0] + sp.sin(thd) * qdot_des[1]
    wd = qdot_des[th_i]
    vc = vd * sp.cos(eth) + kx * ex
    wc = wd + vd * (ky * ey + kth * sp.sin(eth))
    s_root = model.system.null_space.extract([0, 1, th_i], list(range(model.nu)))
    rows = sp.Matrix([[sp.cos(th), sp.sin(th), 0], [0, 0, 1]])
    a = (rows * s_root).applyfunc(model.system.simplify)
    eta_c = (a.adjugate() / a.det()).applyfunc(model.system.simplify) * sp.Matrix([vc, wc])
    eta = sp.Matrix([qdot[i] for i in model.actuated])
    err = eta_c - eta
    i_next = sp.Matrix([sp.Min(sp.Max(integral[j] + ki * h * err[j], -tau_max), tau_max)
                        for j in range(model.nu)])
    tau = sp.Matrix([kp * err[j] + i_next[j] for j in range(model.nu)])
    symbols = {"q_des": tuple(q_des), "qdot_des": tuple(qdot_des), "integral": tuple(integral),
               "gains": (kx, ky, kth, kp, ki), "limits": (h, tau_max)}
    return tau, i_next, symbols


def pi_kernel(formulation: Formulation, model: RobotModel) -> Kernel:
    tau, i_next, sym = wheel_pi_law(model)
    return Kernel(
        "wheel-velocity PI under a pose-correcting path tracker (the ros2_control\n"
        "diff_drive_controller structure): eta_c = A(q)^-1 (v_c, w_c) from the root's pose\n"
        "error (Kanayama), I+ = clamp(I + ki h (eta_c - eta), +-tau_max),\n"
        "tau = kp (eta_c - eta) + I+.", (),
        (KernelArg("q", "q", tuple(model.q)), KernelArg("qdot", "qdot", tuple(model.qdot)),
         KernelArg("q_des", "q_des", sym["q_des"], "reference q"),
         KernelArg("qdot_des", "qdot_des", sym["qdot_des"], "reference qdot"),
         KernelArg("integral", "integral", sym["integral"], "the integral term [N m]"),
         KernelArg("gains", "config", sym["gains"], "kx, ky, ktheta, kp, ki"),
         KernelArg("limits", "config", sym["limits"], "h, tau_max")),
        (KernelArg("u", "u", tuple(tau)), KernelArg("integral_next", "integral", tuple(i_next))),
    )


# The path tracker's and the PI's gains (their sources: the runtime's PI settings).
KX_FIELD = ConfigField("kx", "real", Check.NONNEGATIVE_GAIN, "BAD_GAINS", "1/s",
                       "path tracker: along-track gain k_x [1/s], [0, GAIN_MAX]",
                       "experiment.controller.pi_kx", "1.0", field_id=32,
                       about="the path tracker's along-track gain")
KY_FIELD = ConfigField("ky", "real", Check.NONNEGATIVE_GAIN, "BAD_GAINS", "1/m^2",
                       "path tracker: cross-track gain k_y [1/m^2], [0, GAIN_MAX]",
                       "experiment.controller.pi_ky", "8.0", field_id=33,
                       about="the path tracker's cross-track gain")
KTHETA_FIELD = ConfigField("ktheta", "real", Check.NONNEGATIVE_GAIN, "BAD_GAINS", "1/m",
                           "path tracker: heading gain k_theta [1/m], [0, GAIN_MAX]",
                           "experiment.controller.pi_ktheta", "4.0", field_id=34,
                           about="the path tracker's heading gain")
KP_FIELD = ConfigField("kp", "real", Check.GAIN, "BAD_GAINS", "N m s/rad",
                       "wheel-velocity PI: proportional gain [N m s/rad], [GAIN_MIN, GAIN_MAX]",
                       "pi_kp", "2.0", field_id=35,
                       about="the wheel-velocity PI's proportional gain")
KI_FIELD = ConfigField("ki", "real", Check.NONNEGATIVE_GAIN, "BAD_GAINS", "N m/rad",
                       "wheel-velocity PI: integral gain [N m/rad], [0, GAIN_MAX]", "pi_ki",
                       "2.0", field_id=36, about="the wheel-velocity PI's integral gain")

PI = ControllerSpec(
    "pi", "PI", "wheel-velocity PI with a pose-correcting path tracker",
    "none (the ros2_control diff_drive_controller structure; Kanayama et al. 1990)",
    pi_kernel, Estimate.NONE, error_dynamics=False, states=(LawState.INTEGRAL,),
    own_fields=(KX_FIELD, KY_FIELD, KTHETA_FIELD, KP_FIELD, KI_FIELD),
    formulations=("minimal",),
)
