"""The letters the paper writes Drishti's dynamics in, as SymPy symbols.

The robot's own symbols (q, q̇, q̈, τ and the lumped parameters) are those of
:mod:`modeling.robots.drishti.model` under the paper's short names; added here are what
only the printed equations use: the multipliers λ, the printed auxiliaries Ω1, Ω2 of
(11)–(12) and k1…k5 of (14), and the shorthands (θ̈r + θ̈l), (θ̇r² − θ̇l²) of (10)–(14).
"""

from __future__ import annotations

import sympy as sp

from modeling.robots.drishti import model as wmr

x_c, y_c, theta, theta_r, theta_l = wmr.q
xd, yd, thd, thd_r, thd_l = wmr.qdot
xdd, ydd, thdd, thdd_r, thdd_l = wmr.qddot
tau_r, tau_l = wmr.tau
m, I, K, I_w, r, b, d = wmr.m, wmr.I_z, wmr.K, wmr.I_w, wmr.r, wmr.b, wmr.d
lam1, lam2, lam3 = sp.symbols("lambda_1 lambda_2 lambda_3", real=True)
LAMBDA = sp.Matrix([lam1, lam2, lam3])
Omega1, Omega2 = sp.symbols("Omega_1 Omega_2", real=True)
k1, k2, k3, k4, k5 = sp.symbols("k_1 k_2 k_3 k_4 k_5", real=True)
SIN, COS = sp.sin(theta), sp.cos(theta)

# Shorthands of the printed (10)–(14), used to present residuals in the printed terms.
WHEEL_ACC_SUM = sp.Symbol("Sigma_acc", real=True)  # θ̈_r + θ̈_l
WHEEL_SQ_DIFF = sp.Symbol("Delta_sq", real=True)  # θ̇_r² − θ̇_l²
