"""Every fault kind run on the MuJoCo plant (``[plant] model = "mujoco"``), with its effect
measured: a fault the engine ignored would report a faulted row of ``wmr faults --plant
mujoco`` as fault-free.

Drishti, TDC, paper formulation, a 6 s circle; each fault starts at 3 s. Before it the run
is the fault-free run, sample for sample (the engine is deterministic); from it on:

* ``traction-loss`` (ice on the right wheel for 1 s): the engine's tyre loses its grip, the
  robot leaves the path by far more than the fault-free run's error (on the engine the
  fault scales the tyre's friction coefficient: half the grip is still more than the
  circle needs);
* ``torque-saturation`` (0.2 N m on the left wheel for 1 s): the actuator delivers at most
  that while the controller asks for more;
* ``encoder-glitch`` (+50 counts on the right wheel, persistent): the measured angle is 50
  counts off the engine's wheel angle from then on;
* ``dropped-sample`` (0.2 s): the step is not called and the torque is held;
* ``repeated-sample`` (0.2 s): the controller is given the previous measurement again.
"""

from __future__ import annotations

import math
from dataclasses import replace
from functools import cache

import numpy as np
import pytest

from runtime.bindings.generated import load_robot_code
from runtime.experiment.faults import Fault
from runtime.experiment.settings import Experiment
from runtime.plants import plant_for
from runtime.sim import loop, paths
from runtime.sim.loop import NOT_CALLED, Run

CODE = load_robot_code("")
ROBOT = dict(CODE.params)
EXP = replace(Experiment(), plant=replace(Experiment().plant, model="mujoco"))
H = EXP.controller.h
START = 3.0
K0 = round(START / H)


@cache
def reference() -> object:
    return paths.circle(CODE, ROBOT, replace(EXP, paths=replace(EXP.paths, circle_duration=6.0)))


def run(*faults: Fault) -> Run:
    """A run on a new engine (the plant carries the faults' state)."""
    return loop.run(CODE, "tdc", "paper", reference(), ROBOT, EXP,  # type: ignore[arg-type]
                    faults=faults, plant=plant_for(CODE, EXP, ROBOT))


@cache
def base() -> Run:
    return run()


def window(r: Run, duration: float) -> slice:
    return slice(K0, K0 + max(1, round(duration / H)))


def _untouched_until_the_fault(r: Run) -> None:
    assert np.array_equal(r.q[:K0], base().q[:K0])
    assert np.array_equal(r.tau[:K0], base().tau[:K0])


def test_the_fault_free_run_tracks() -> None:
    assert base().failed_at is None and float(base().position_error.max()) < 0.05


def test_traction_loss_loses_the_grip_on_the_engine() -> None:
    r = run(Fault("traction-loss", START, 1.0, 1.0, "right"))
    _untouched_until_the_fault(r)
    assert float(r.position_error.max()) > 10 * float(base().position_error.max())
    # On the engine a loss scales the tyre's friction coefficient (1 -> 0.5 here): the
    # circle needs about 0.2 of it, so half the grip still holds and nothing changes (on
    # the model plant the same fault transmits half the torque: docs/FAULTS.md).
    half = run(Fault("traction-loss", START, 1.0, 0.5, "right"))
    assert float(half.position_error.max()) == pytest.approx(
        float(base().position_error.max()), abs=1e-9)


def test_torque_saturation_clips_the_delivered_torque() -> None:
    limit = 0.2
    r = run(Fault("torque-saturation", START, 1.0, limit, "left"))
    _untouched_until_the_fault(r)
    w = window(r, 1.0)
    assert np.all(np.abs(r.tau_applied[w, 1]) <= limit + 1e-12)
    assert float(np.abs(r.tau[w, 1]).max()) > 2 * limit  # the controller asked for more
    assert np.array_equal(r.tau_applied[w, 0], r.tau[w, 0])  # the other wheel untouched


def test_encoder_glitch_miscounts_the_engine_wheel() -> None:
    r = run(Fault("encoder-glitch", START, 0.0, 50, "right"))
    _untouched_until_the_fault(r)
    cpr = EXP.sensing.counts_per_wheel_rev() / (2 * math.pi)
    off = np.round(r.q_meas[:, 3:5] * cpr - np.floor(r.q[:, 3:5] * cpr))
    assert np.all(off[:K0] == 0)
    assert np.all(off[K0:, 0] == 50) and np.all(off[K0:, 1] == 0)


@pytest.mark.parametrize("kind", ["dropped-sample", "repeated-sample"])
def test_sample_faults(kind: str) -> None:
    r = run(Fault(kind, START, 0.2))
    _untouched_until_the_fault(r)
    w = window(r, 0.2)
    if kind == "dropped-sample":
        assert np.all(r.status[w] == NOT_CALLED)
        assert np.all(r.tau[w] == r.tau[K0 - 1])  # zero-order hold
    else:
        assert np.all(r.status[w] != NOT_CALLED)
        assert np.array_equal(r.q_meas[K0], r.q_meas[K0 - 1])
        assert not np.array_equal(base().q_meas[K0], base().q_meas[K0 - 1])
    assert not np.allclose(r.q[-1], base().q[-1])
