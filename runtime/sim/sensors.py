"""What the controllers measure: encoders on the driven wheels, their rates by the
experiment's sensing model, and every other coordinate by odometry.

* Encoders: the driven wheels' angles quantised to whole counts, 4 × ``encoder_ppr`` per
  revolution (quadrature), times ``gear_ratio`` for a motor-side encoder.
* Rates (``[sensing] velocity``, :class:`runtime.experiment.settings.SensingSettings`): the
  rate at the sample instant (``sample-instant``), the counts differenced over the sample
  (``encoder-average``, Δθ/h) or over the last ``window`` s (``motor-encoder``).
* Odometry: every coordinate that is not a driven wheel's angle (the pose, a hitch angle,
  passive wheels) integrated from the encoder increments through the generated kinematics
  q̇ = S(q) η of (31), which is linear in η: over a sample, Δq = S(q_mid) Δθ with the
  midpoint q_mid = q + S(q) Δθ / 2.
* q̇ as measured: S(q) applied to the measured rates.

``offset`` and ``window_offset`` are counts added to the encoder readings at the sample
instant and at the motor-encoder window's start (an encoder fault, ``runtime.experiment.faults``).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from runtime.bindings.generated import RobotCode
from runtime.experiment.settings import Experiment

Array = NDArray[np.float64]


class Sensors:
    """The measurements of one run, starting from the true configuration ``q0`` (the
    odometry's initial pose) with the nominal parameters ``params`` in the kinematics."""

    def __init__(self, code: RobotCode, q0: Array, exp: Experiment, params: dict[str, float]):
        self.code, self.params = code, params
        self.sensing = exp.sensing
        self.counts_per_rad = self.sensing.counts_per_wheel_rev() / (2 * math.pi)
        self.h = exp.controller.h
        self.window = self.sensing.rate_window(self.h)
        self.act = list(code.actuated)
        self.dep = list(code.dependent)
        self.offset = np.zeros(code.nu)
        self.window_offset = np.zeros(code.nu)
        self.q = np.array(q0, dtype=np.float64)
        self.angles = self.quantise(self.q[self.act])
        self.q[self.act] = self.angles

    def quantise(self, angles: Array, offset: Array | None = None) -> Array:
        """The encoder angles: whole counts, plus ``offset`` counts."""
        counts = np.floor(angles * self.counts_per_rad)
        if offset is not None:
            counts = counts + offset
        return np.asarray(counts / self.counts_per_rad)

    def rates(self, angles: Array, true_rates: Array, window_start: Array | None) -> Array:
        """Wheel rates as measured: at the instant, over the sample, or over the window."""
        v = self.sensing.velocity
        if v == "sample-instant":
            return true_rates.copy()
        if v == "encoder-average":
            return np.asarray((angles - self.angles) / self.h)
        assert window_start is not None, "motor-encoder needs the angles at t - window"
        return np.asarray((angles - self.quantise(window_start, self.window_offset))
                          / self.window)

    def measure(self, true_angles: Array, true_rates: Array,
                window_start: Array | None = None) -> tuple[Array, Array]:
        """(q, q̇) as the controller sees them at a sample instant, from the encoders'
        true angles and rates (``window_start``: their angles at the motor-encoder window's
        start)."""
        angles = self.quantise(true_angles, self.offset)
        delta = angles - self.angles
        kinematics, q = self.code.model.kinematics, self.q
        mid = q.copy()
        mid[self.dep] = q[self.dep] + 0.5 * kinematics(q, delta, self.params)
        q[self.dep] = q[self.dep] + kinematics(mid, delta, self.params)
        rates = self.rates(angles, true_rates, window_start)
        self.angles = angles
        q[self.act] = angles
        return q.copy(), self.code.velocities(q, rates, self.params)
