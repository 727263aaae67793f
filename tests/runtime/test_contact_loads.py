"""The one load model (``modeling.contact_loads``) against the engine that realises it.

* The MJCF's contact stiffness: MuJoCo's inverse weight of every contact body
  (``body_invweight0``), which scales its contact stiffness, is the one
  ``modeling.mjcf_export.engine_inverse_weights`` computes to set each contact's time
  constant (measured: 1e-12 relative; Drishti, the trailer, the 2 kg robot, point and
  capsule tyres).
* The loads at rest: MuJoCo's contact forces (``mj_contactForce``) within 2 % of the
  stated ones on every contact (measured: Drishti with the fixed payload 0.02 % on the
  wheels, 0.3 % on the light rear support; it was 13 % before the time constants were
  set per contact); with both payloads on, the rear support lifts off in both.
* Lift-off is never a negative load; load transfer moves load rearward under forward
  acceleration and keeps the total.
About 3 s on one core.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import mujoco
import numpy as np
import pytest

from modeling.contact_loads import support_loads
from modeling.mjcf_command import planar_robot
from modeling.mjcf_export import GRAVITY, ContactSettings, engine_inverse_weights, mjcf
from modeling.planar_robot import PlanarBody, PlanarRobot, PlanarWheel
from runtime.bindings.robots import resolve
from runtime.experiment.settings import parse_experiment
from runtime.plant_comparison import engine_loads
from runtime.setting.layout import robot_layout

ROOT = Path(__file__).resolve().parents[2]
ROBOTS = {
    "drishti": ROOT / "modeling" / "robots" / "drishti" / "drishti.toml",
    "trailer": ROOT / "modeling" / "robots" / "trailer" / "trailer.toml",
    "small_robot": ROOT / "tests" / "robots" / "small_robot.toml",
}
EXP = parse_experiment('[plant]\nmodel = "mujoco"\n')
LOAD_RTOL = 0.02  # the bound on the engine's loads at rest


@pytest.mark.parametrize("name", sorted(ROBOTS))
@pytest.mark.parametrize("width", [0.0, 0.04])
def test_the_exporters_inverse_weights_are_mujocos(name: str, width: float) -> None:
    robot = planar_robot(ROBOTS[name])
    contact = ContactSettings(tyre_width=width, payloads=((-0.05, 0.0), (0.1, 0.12)))
    model = mujoco.MjModel.from_xml_string(mjcf(robot, contact))
    ours = engine_inverse_weights(robot, contact)
    assert set(ours) == {*(b.name for b in robot.bodies),
                         *(f"wheel_{w.name}" for w in robot.wheels)}
    for body, weight in ours.items():
        engine = float(model.body_invweight0[model.body(body).id][0])
        assert abs(weight - engine) <= 1e-9 * engine, (body, weight, engine)


def _payloads(masses: tuple[float, float]) -> tuple[tuple[float, float, float], ...]:
    pl = EXP.plant
    return ((masses[0], pl.fixed_payload_x, pl.fixed_payload_y),
            (masses[1], pl.extra_payload_x, pl.extra_payload_y))


@pytest.mark.parametrize("name", ["drishti", "trailer"])
def test_the_engine_carries_the_stated_loads_at_rest(name: str) -> None:
    setup = resolve(ROBOTS[name])
    robot = robot_layout(setup.code, setup.plant)
    masses = (EXP.plant.fixed_payload, 0.0) if name == "drishti" else (0.0, 0.0)
    stated = support_loads(robot, _payloads(masses))
    measured = engine_loads(setup.code, EXP, setup.plant, masses)
    assert not stated.lifted
    assert set(measured) == set(stated.loads)
    for contact, load in stated.loads.items():
        assert abs(measured[contact] - load) <= LOAD_RTOL * load, (contact, load, measured)
    total = GRAVITY * (robot.total_mass() + sum(masses))
    assert abs(sum(stated.loads.values()) - total) < 1e-9 * total


def test_a_support_in_tension_lifts_off_in_the_model_and_the_engine() -> None:
    """Drishti with both payloads on (and bare): the equal-spring plane would pull the rear
    support down (−1.9 N with both payloads); it lifts off, the other three carry the
    weight (determinate), and MuJoCo's rear support carries nothing."""
    setup = resolve(ROBOTS["drishti"])
    robot = robot_layout(setup.code, setup.plant)
    for masses in ((EXP.plant.fixed_payload, EXP.plant.extra_payload), (0.0, 0.0)):
        stated = support_loads(robot, _payloads(masses))
        assert stated.lifted == ("support_rear",)
        assert stated["support_rear"] == 0.0 and min(stated.loads.values()) >= 0.0
        measured = engine_loads(setup.code, EXP, setup.plant, masses)
        assert measured.get("support_rear", 0.0) < 0.01 * stated["support_front"]
        for contact in ("right", "left", "support_front"):
            assert abs(measured[contact] - stated[contact]) <= LOAD_RTOL * stated[contact], (
                contact, stated, measured)


def test_load_transfer_and_tipping() -> None:
    robot = PlanarRobot("cart", (PlanarBody("body", 10.0, 1.0, (0.0, 0.0)),), (),
                        tuple(PlanarWheel(n, "body", (x, y), 0.1, 0.01, 0.0, 0.0, True)
                              for n, x, y in (("fl", 0.3, 0.2), ("fr", 0.3, -0.2),
                                              ("rl", -0.3, 0.2), ("rr", -0.3, -0.2))))
    rest = support_loads(robot)
    assert all(abs(v - 10 * GRAVITY / 4) < 1e-9 for v in rest.loads.values())
    ahead = support_loads(robot, accel=(2.0, 0.0))
    # Σ N x = −m a h: 4 × 0.3 ΔN = 10 × 2 × 0.1 on each side's pair
    shift = 10 * 2.0 * 0.1 / (4 * 0.3)
    assert abs(ahead["rl"] - rest["rl"] - shift) < 1e-9
    assert abs(ahead["fl"] - rest["fl"] + shift) < 1e-9
    turn = support_loads(robot, accel=(0.0, 9.0))  # to the left: the right wheels load
    assert abs(turn["fr"] - rest["fr"] - 10 * 9.0 * 0.1 / (4 * 0.2)) < 1e-9
    # A payload far out on the left: the right pair would pull, it lifts off, the left pair
    # carries everything (and, alone on a line, cannot hold the moment: it tips).
    with pytest.raises(ValueError, match="tips over"):
        support_loads(robot, ((20.0, 0.0, 1.0),))
    # 30 kg near the front-left wheel: the plane puts −1.875 g on the rear right, which
    # lifts off; the other three are determinate.
    leaning = support_loads(robot, ((30.0, 0.25, 0.15),))
    assert leaning.lifted == ("rr",) and leaning["rr"] == 0.0
    for wheel, load in (("fl", 23.75), ("fr", 8.75), ("rl", 7.5)):
        assert abs(leaning[wheel] - load * GRAVITY) < 1e-9, (wheel, leaning)
    with pytest.raises(ValueError, match="tips over"):
        support_loads(robot, accel=(0.0, 30.0))


def test_engine_loads_takes_the_payloads_it_is_given() -> None:
    setup = resolve(ROBOTS["drishti"])
    bare = engine_loads(setup.code, dataclasses.replace(EXP), setup.plant, (0.0, 0.0))
    loaded = engine_loads(setup.code, EXP, setup.plant, (6.0, 0.0))
    assert abs(sum(loaded.values()) - sum(bare.values()) - 6.0 * GRAVITY) < 0.05


def test_the_slip_monitor_transfers_load_as_the_engine_does() -> None:
    """Drishti from rest under constant wheel torques (a hard start and a turn) on MuJoCo
    (μ = 1): the normal load the monitor gives each driven wheel (:meth:`traction`: the
    load model under the acceleration ΣF/m of the generated contact forces) is the engine's
    within 3 % every 50 ms from 0.3 s (measured: 0.5 %; in the first 0.2 s of the sudden
    start the engine's wheels carry up to 5 % more: a transient the quasi-static model
    leaves out), where the loads at rest are more than 10 % off (the turn loads the
    outer wheel)."""
    from runtime.mujoco.plant import MujocoPlant
    from runtime.sim.payload import plant_params_at
    from runtime.sim.slip_monitor import SlipMonitor

    setup = resolve(None)
    code = setup.code
    robot = robot_layout(code, setup.plant)
    plant = MujocoPlant(code, EXP, robot)
    masses = np.array([EXP.plant.fixed_payload, 0.0])
    params = plant_params_at(code, EXP, 0.0, setup.plant)
    plant.set_payload(masses)
    plant.start(np.zeros(code.nq))
    plant.set_faults(np.zeros(2), np.full(2, np.inf))
    monitor = SlipMonitor(code, robot, EXP)
    rest = monitor.normal_loads(masses)
    torque = np.array([14.0, 8.0])
    static_off = 0.0
    m, d = plant.model, plant.data
    force = np.zeros(6)
    plant.advance(list(torque), 0.001, 250)
    for _ in range(14):
        plant.advance(list(torque), 0.001, 50)
        engine = {}
        for i in range(d.ncon):
            mujoco.mj_contactForce(m, d, i, force)
            engine[m.geom(d.contact[i].geom[1]).name or m.geom(d.contact[i].geom[0]).name] = (
                float(force[0]))
        _, loads = monitor.traction(plant.q, plant.wheels()[1], torque, params, masses)
        for i, wheel in enumerate(monitor.driven):
            measured = engine[f"tyre_{wheel}"]
            assert abs(loads[i] - measured) <= 0.03 * measured, (wheel, loads, engine)
            static_off = max(static_off, abs(rest[i] - measured) / measured)
    assert static_off > 0.1
