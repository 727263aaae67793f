"""The generated plant's integrator (runtime/sim/csrc/plant_rk4.c: classical RK4 in C) against
SciPy's DOP853 at tight tolerance on the same right-hand side (the generated NumPy
``plant_state_derivative``), and its order of convergence.

Drishti from rest under a constant torque that drives it forward and turns it, no wheel
friction (so the right-hand side is the generated one alone), for 1 s. RK4's global error is
O(dt⁴): at dt = 10 ms it is far below 1e-7, and halving dt divides it by about 16. A
wrong stage weight or a wrong half step leaves a first- or second-order method, whose error
is orders of magnitude larger and shrinks by 2 or 4.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from runtime.bindings.generated import load_robot_code
from runtime.sim.plant import GeneratedPlant, library_for

CODE = load_robot_code("")
PARAMS = {**CODE.plant_defaults, **CODE.params}
TAU = np.array([1.0, 0.3])
T_END = 1.0


def _rk4_state(dt: float) -> np.ndarray:
    plant = GeneratedPlant(CODE, library_for(CODE, False), viscous=0.0, coulomb=0.0)
    plant.set_parameters(PARAMS)
    plant.start(np.zeros(CODE.nq))
    assert plant.advance([float(t) for t in TAU], dt, round(T_END / dt))
    return np.array(plant.lib.ffi.unpack(plant.x, plant.nx), dtype=np.float64)


def _reference() -> np.ndarray:
    x0 = np.zeros(CODE.nq + CODE.nu)
    sol = solve_ivp(lambda _t, x: np.asarray(CODE.plant.plant_state_derivative(x, TAU, PARAMS)),
                    (0.0, T_END), x0, method="DOP853", rtol=1e-13, atol=1e-13)
    assert sol.success
    return np.asarray(sol.y[:, -1])


def test_rk4_agrees_with_dop853_and_converges_at_fourth_order() -> None:
    ref = _reference()
    assert np.linalg.norm(ref[:2]) > 0.02 and abs(ref[2]) > 0.02  # it moved and turned
    errors = [float(np.max(np.abs(_rk4_state(dt) - ref))) for dt in (0.02, 0.01)]
    assert errors[1] < 1e-7, errors
    order = np.log2(errors[0] / errors[1])
    assert 3.5 < order < 4.5, (errors, order)
