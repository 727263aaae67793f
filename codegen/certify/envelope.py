"""The operating envelope the float32 certificates are stated for (issue 50): one
declaration, read by the certifier (``codegen.backends.c.certify.boxes`` maps each input of
a generated function to its range here) and by the generator (the run-time check of the
robust steps' conditions, :mod:`codegen.certify.runtime_check`, which every backend renders).
Imports no backend, so the generator may import it."""

from __future__ import annotations

import math
from dataclasses import dataclass

Interval = tuple[float, float]


@dataclass(frozen=True)
class Envelope:
    """The operating envelope the certificates are stated for (SI units)."""

    # parameters: the robot file's value x [1 - u, 1 + u]. At ±20 % (the cross-checks')
    # Drishti's forward dynamics are proved only with the divisors' enclosures
    # (codegen/backends/c/certify/divisors.py).
    uncertainty: float = 0.1
    angle: float = 2 * math.pi  # |q| of an angle, rad (two turns either way)
    position: float = 100.0  # |q| of a position, m
    angle_rate: float = 30.0  # rad/s (wheels: ~2.9 m/s at r = 0.096 m)
    position_rate: float = 3.0  # m/s
    torque: float = 50.0  # N m per wheel (|tau|, |u_prev|: the crosscheck's largest tau_max)
    error: float = 0.5  # |e|: m or rad
    error_rate: float = 2.0  # |edot|
    accel_des: float = 5.0  # |qddot_des|
    gain: Interval = (1.0, 8.0)  # K1, K2 entries (crosscheck: U(1, 8))
    weight: Interval = (0.5, 2.0)  # Q entries
    span: Interval = (0.01, 0.4)  # s: h or 2 h of the estimated acceleration
    h1hat: float = 100.0  # |H1hat| (TDE's estimate of the lumped uncertainty), and Omega
    adaptive_gain: Interval = (0.0, 100.0)  # k-hat (TDROC), ASMC's gain
    eps: Interval = (0.02, 0.5)  # boundary layer
    alpha: Interval = (0.0, 0.6)  # ROC's bounds
    phi: Interval = (0.0, 3.0)
    gamma: Interval = (0.0, 5.0)  # ASMC adaptation rate
    h: Interval = (0.01, 0.2)  # s, sampling time
    norm: Interval = (0.0, 10.0)  # ||Mhat^-1||, window difference norms
    force: float = 500.0  # |contact force|, N
    mu: Interval = (0.1, 1.5)
    load: Interval = (10.0, 500.0)  # N
    pi_gains: tuple[Interval, ...] = ((0.5, 2.0), (4.0, 16.0), (2.0, 8.0), (0.1, 2.0),
                                      (0.1, 5.0))  # kx, ky, ktheta, kp, ki
    integral: float = 10.0
    payload_mass: Interval = (0.0, 20.0)  # kg
    payload_offset: float = 0.5  # m


ENVELOPE = Envelope()
