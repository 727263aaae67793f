"""The one closed loop (``runtime.sim``) and the bindings every command shares.

* the configuration builder knows every field source of every shipped robot's registry
  export, so a controller added to the registry needs nothing in the runtime;
* the loop runs any :class:`runtime.sim.plant.Plant`: a plant that wraps the generated one
  gives the very same run;
* the compiled plant is generic: each driven wheel's spin inertia is found in the parameter
  table of every shipped robot (the traction-loss fault needs it);
* a run that leaves its path is not ``ok`` (``runtime.sim.outcome``);
* every command takes ``--robot`` (a file, a generated folder or a name) and
  ``--generated`` and resolves them the same way.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pytest

from runtime.bindings.config import EXPERIMENT_SOURCE, SOURCES
from runtime.bindings.generated import GENERATED, RobotCode, load_robot_code
from runtime.bindings.robots import resolve
from runtime.experiment.settings import Experiment
from runtime.setting.robot import robot_setting
from runtime.sim import loop, paths
from runtime.sim.outcome import OFF_PATH_FRACTION, outcome
from runtime.sim.plant import GeneratedPlant, library_for, spin_inertia_keys

ROOT = Path(__file__).resolve().parents[2]
ROBOTS = ("", "trailer")  # generated/ and generated/trailer/
SHORT = Experiment()
SHORT = dataclasses.replace(SHORT, paths=dataclasses.replace(
    SHORT.paths, circle_duration=4.0, lawnmower_duration=4.0))


@pytest.mark.parametrize("folder", ROBOTS)
def test_every_field_source_is_known(folder: str) -> None:
    code = load_robot_code(folder)
    for info in code.controller_infos:
        for f in info.fields:
            if f.source.startswith(EXPERIMENT_SOURCE):
                section, _, name = f.source.removeprefix(EXPERIMENT_SOURCE).partition(".")
                assert hasattr(getattr(Experiment(), section), name), (info.name, f)
            else:
                assert f.source in SOURCES, (info.name, f)


@pytest.mark.parametrize("folder", ROBOTS)
def test_spin_inertia_is_found_for_every_driven_wheel(folder: str) -> None:
    code = load_robot_code(folder)
    keys = spin_inertia_keys(code)
    assert keys is not None and len(keys) == code.nu
    if folder == "":
        assert keys == ("Iw", "Iw")  # Drishti: one parameter for both wheels
    else:
        names = [code.robot.COORDINATES[i] for i in code.actuated]
        assert keys == tuple(f"J_{n}" for n in names)


class CountingPlant:
    """Another Plant: the generated one behind the protocol, counting the calls."""

    def __init__(self, inner: GeneratedPlant) -> None:
        self.inner, self.nq, self.nu = inner, inner.nq, inner.nu
        self.calls: dict[str, int] = {}

    def _count(self, name: str) -> None:
        self.calls[name] = self.calls.get(name, 0) + 1

    def start(self, q0: np.ndarray) -> None:
        self._count("start")
        self.inner.start(q0)

    def set_parameters(self, params: Mapping[str, float]) -> None:
        self._count("set_parameters")
        self.inner.set_parameters(params)

    def set_payload(self, masses: np.ndarray) -> None:
        self.inner.set_payload(masses)

    def set_faults(self, traction_loss: np.ndarray, torque_limit: np.ndarray) -> None:
        self.inner.set_faults(traction_loss, torque_limit)

    def actuate(self, tau: np.ndarray) -> list[float]:
        return self.inner.actuate(tau)

    def advance(self, tau: list[float], dt: float, nsub: int) -> bool:
        self._count("advance")
        return self.inner.advance(tau, dt, nsub)

    @property
    def q(self) -> np.ndarray:
        return self.inner.q

    def wheels(self) -> tuple[np.ndarray, np.ndarray]:
        return self.inner.wheels()


@pytest.mark.parametrize("folder", ROBOTS)
def test_the_loop_runs_any_plant(folder: str) -> None:
    code = load_robot_code(folder)
    ref = paths.circle(code, code.params, SHORT)
    base = loop.run(code, "tdroc", "minimal", ref, code.params, SHORT)
    inner = GeneratedPlant(code, library_for(code), SHORT.plant.viscous, SHORT.plant.coulomb)
    plant = CountingPlant(inner)
    other = loop.run(code, "tdroc", "minimal", ref, code.params, SHORT, plant=plant)
    for f in ("q", "q_meas", "tau", "gain", "status"):
        assert np.array_equal(getattr(base, f), getattr(other, f)), f
    assert plant.calls["start"] == 1 and plant.calls["advance"] == len(ref.t) - 1
    assert plant.calls["set_parameters"] >= 1


def test_a_run_off_its_path_is_not_ok() -> None:
    code = load_robot_code("")
    ref = paths.circle(code, code.params, SHORT)
    r = loop.run(code, "tdc", "minimal", ref, code.params, SHORT)
    assert outcome(r, ref.scale).ok
    # The same record with the robot moved a path's tenth (and a bit) away: off the path.
    moved = dataclasses.replace(r, q=r.q + np.array(
        [1.01 * OFF_PATH_FRACTION * ref.scale] + [0.0] * (code.nq - 1)))
    result = outcome(moved, ref.scale)
    assert result.status == "off path" and "10 % of the path's 1.5 m" in result.detail
    refused = loop.run(code, "roc", "minimal", ref, code.params, SHORT, bounds=(2.0, 1.0))
    assert refused.init_status != 0 and outcome(refused, ref.scale).status == "init refused"
    assert "BAD_BOUNDS" in (refused.stop_reason or "")


def test_robot_is_resolved_from_a_file_a_folder_or_a_name() -> None:
    trailer_file = ROOT / "modeling" / "robots" / "trailer" / "trailer.toml"
    by_file, by_folder, by_name = (resolve(trailer_file), resolve(GENERATED / "trailer"),
                                   resolve("trailer"))
    assert by_file.code.folder == by_folder.code.folder == by_name.code.folder
    assert by_file.nominal == by_folder.nominal == by_name.nominal
    drishti = resolve(None)
    assert drishti.name == "drishti" and drishti.code.prefix == "wmr"


def test_a_one_kilogram_robot_gets_its_own_payload_and_torque() -> None:
    """The experiment is scaled to the robot the same way everywhere (here: the small
    robot of tests/robots/, 2 kg): no 9 kg payload, no 40 N m."""
    setting = robot_setting(ROOT / "tests" / "robots" / "small_robot.toml", None, Experiment())
    exp = setting.experiment
    assert exp.plant.fixed_payload + exp.plant.extra_payload < 0.5
    assert exp.controller.tau_max < 1.0
    assert exp.paths.circle_radius < 1.0
    paper = robot_setting(None, None, Experiment())
    assert paper.is_paper_robot and paper.experiment == Experiment()


@pytest.mark.parametrize("module", ["runtime.commands.reproduce", "runtime.commands.faults",
                                    "runtime.commands.stability", "runtime.commands.campaign",
                                    "runtime.commands.freeze",
                                    "runtime.tooling.crosscheck.command"])
def test_every_command_takes_the_same_robot_options(module: str,
                                                     capsys: pytest.CaptureFixture[str]) -> None:
    import importlib

    main = importlib.import_module(module).main
    with pytest.raises(SystemExit):
        main(["--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "--robot ROBOT" in text and "--generated DIR" in text
    assert "python -m codegen" not in text


def test_code_carries_its_controllers() -> None:
    code: RobotCode = load_robot_code("")
    assert code.controller_names == tuple(c["name"] for c in code.robot.CONTROLLERS)
    for form, info in code.runs():
        assert form in info.formulations and form in code.formulations


def test_every_plant_model_has_a_factory() -> None:
    from runtime.experiment.settings import PLANT_MODELS
    from runtime.plants import PLANTS

    assert tuple(PLANTS) == PLANT_MODELS
