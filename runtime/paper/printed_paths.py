"""The paper's printed path definitions, drawn beside our consistent references (which
``runtime.sim.paths`` builds from the experiment's ``[paths]``; docs/PAPER.md item 12).
Never fed to a controller: no robot obeying the constraints (6)–(8) can follow them.

* circle: printed x_d, y_d on R1 = 1.5 m with θ_d = θ0 + θ̇_d t, wheel rates assuming the
  axle centre is on R1;
* lawn mower: printed x_d = 0.1 t + 0.3 sin(0.4 t), y_d = 1.2 + 1.2 cos(0.2 t − T) with
  square-wave wheel rates (levels a = 3, b = 1.6 rad/s, T = 25 s): two different motions.

R1, θ̇_d, a, b and T are the paper's, as the experiment's defaults declare them
(:class:`runtime.experiment.settings.PathSettings`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from runtime.experiment.settings import PathSettings

PAPER_PATHS = PathSettings()
R1 = PAPER_PATHS.circle_radius
THETA_DOT = PAPER_PATHS.circle_rate
LAWN_A, LAWN_B, LAWN_T = (PAPER_PATHS.lawnmower_fast, PAPER_PATHS.lawnmower_slow,
                          PAPER_PATHS.lawnmower_period)


def printed_circle(t: NDArray[np.float64]) -> NDArray[np.float64]:
    """The printed circle's (x_d, y_d): centre (0, 1.5)... as printed, radius R1 = 1.5 m,
    starting at (1.5, 1.5) — shown beside ours, not used for control."""
    return np.stack([R1 * np.cos(THETA_DOT * t), 1.5 + R1 * np.sin(THETA_DOT * t)], axis=1)


def printed_lawnmower(t: NDArray[np.float64]) -> NDArray[np.float64]:
    """The printed lawn-mower (x_d, y_d) with T = 25 s — shown beside ours, not used."""
    return np.stack([0.1 * t + 0.3 * np.sin(0.4 * t), 1.2 + 1.2 * np.cos(0.2 * t - LAWN_T)], axis=1)


def printed_wheel_rates(t: NDArray[np.float64]) -> NDArray[np.float64]:
    """The printed lawn-mower wheel rates (Section 5, Figure 10): the Fourier series
    θ̇r = (a + b)/2 + 2(a − b)/π Σ_{p odd} sin(pπ/2)/p cos(2pπt/T), θ̇l the same half a
    period later (the odd harmonics change sign), summed to its limit: square waves between
    a = 3 and b = 1.6 rad/s, T = 25 s. Drawn beside ours only; never fed to a controller."""
    a, b, period = LAWN_A, LAWN_B, LAWN_T
    sq = np.sign(np.cos(2 * np.pi * t / period))
    return np.stack([(a + b) / 2 + (a - b) / 2 * sq, (a + b) / 2 - (a - b) / 2 * sq], axis=1)
