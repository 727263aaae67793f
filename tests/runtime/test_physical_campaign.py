"""Campaigns draw physical quantities on both plants (issue 48): run i is the same drawn
robot (masses, inertias, centres of mass) on the generated plant, through the generated
map, and on MuJoCo, as bodies; ROC runs on trailer2 with ±20 % on every body."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from runtime.bindings.physical_bounds import box_of
from runtime.campaign.runner import run_one, target
from runtime.campaign.sampling import base_values
from runtime.campaign.spec import CampaignSpecError, parse_campaign
from runtime.commands.campaign import with_plant

SPEC = """
seed = 3
runs = 2
controllers = ["{ctrl}"]
duration = 4.0
[physical_uncertainty]
mass = 0.2
yaw_inertia = 0.2
com = 0.02
"""


def _records(robot: str, ctrl: str, plant: str) -> list[dict[str, object]]:
    tgt = target(robot)
    code = tgt.setup.code
    c = parse_campaign(SPEC.format(ctrl=ctrl), "c.toml", tgt.plant,
                       available=lambda f: code.controller_names,
                       physical_box=lambda d: box_of(code, d))
    c = replace(with_plant(c, plant), robot=robot)
    base = base_values(c, tgt.plant, tgt.physical)
    return [run_one(c, i, tgt, base) for i in range(c.runs)]


def test_both_plants_run_the_same_drawn_robots() -> None:
    model = _records("trailer", "tdc", "generated")
    engine = _records("trailer", "tdc", "mujoco")
    for a, b in zip(model, engine, strict=True):
        drawn = sorted(k for k in a if k.startswith("p.physical."))
        assert "p.physical.mass_cart" in drawn and "p.physical.com_x_tractor" in drawn
        assert all(a[k] == b[k] for k in drawn)
        assert a["status"] == b["status"] == "ok", (a["error"], b["error"])
        # per-run agreement: the same robot tracks alike on both plants
        assert math.isclose(float(a["rms_error"]), float(b["rms_error"]), rel_tol=0.2,
                            abs_tol=0.01), (a["rms_error"], b["rms_error"])


def test_roc_runs_on_trailer2_with_20_percent_on_every_body() -> None:
    (rec, *_) = _records("trailer2", "roc", "generated")
    assert rec["status"] == "ok", rec["error"]


def test_the_drawn_robot_is_what_each_plant_simulates() -> None:
    from runtime.campaign.physical_draws import physical_layout, physical_params
    from runtime.experiment.settings import Experiment
    from runtime.mujoco.plant import MujocoPlant

    code = target("trailer").setup.code
    values = {"mass_cart": 19.0, "yaw_inertia_tractor": 1.2, "com_x_cart": -0.4}
    engine = MujocoPlant(code, Experiment(), physical_layout(code, values))
    assert engine.model.body_mass[engine.model.body("cart").id] == 19.0
    params = physical_params(code, values)
    assert params["J_x_tractor"] == code.params["J_x_tractor"] + 4.0
    assert params["K_theta_cart_x_tractor"] != code.params["K_theta_cart_x_tractor"]


def test_summary_says_which_draws_each_plant_took() -> None:
    from runtime.campaign.summary import physical_lines

    tgt = target("trailer")
    code = tgt.setup.code
    c = parse_campaign(SPEC.format(ctrl="tdc"), "c.toml", tgt.plant,
                       available=lambda f: code.controller_names,
                       physical_box=lambda d: box_of(code, d))
    (model,) = physical_lines(with_plant(c, "generated"))
    (engine,) = physical_lines(with_plant(c, "mujoco"))
    assert "physical.mass_cart" not in model and "mass_cart" in model
    assert "generated plant, through the generated map" in model
    assert "mujoco plant, as the bodies of the exported MJCF" in engine
    assert "mass ±20%" in engine


@pytest.mark.parametrize(("text", "message"), [
    ('[vary."physical.mass_trolley"]\nspread = 0.2\n',
     "unknown parameter 'vary.\"physical.mass_trolley\"' (the robot's physical quantities "
     "are physical.mass_tractor"),
    ('[vary."physical.mass_cart"]\nspread = 0.2\n[vary."robot.J_x_tractor"]\nspread = 0.2\n',
     "draw either the robot's physical quantities (physical.*) or its model parameters"),
    ("[physical_uncertainty]\nmass = 2.0\n",
     "field 'physical_uncertainty.mass' must be a relative half-width in [0, 1)"),
    ("[physical_uncertainty.carriage]\nmass = 0.1\n",
     "robot 'trailer' has no body or wheel 'carriage'"),
])
def test_bad_physical_campaigns_get_one_line(text: str, message: str) -> None:
    tgt = target("trailer")
    code = tgt.setup.code
    with pytest.raises(CampaignSpecError) as err:
        parse_campaign(text, "c.toml", tgt.plant, available=lambda f: code.controller_names,
                       physical_box=lambda d: box_of(code, d))
    assert str(err.value).startswith("c.toml: ") and message in str(err.value)
    assert "\n" not in str(err.value)


def test_a_lumped_robot_keeps_its_lumped_box() -> None:
    tgt = target(None)  # Drishti, a [lumped] robot: no physical quantities
    with pytest.raises(CampaignSpecError, match="needs a bodies-and-wheels robot"):
        parse_campaign("[physical_uncertainty]\nmass = 0.1\n", "c.toml", tgt.plant,
                       available=lambda f: tgt.setup.code.controller_names)


def test_the_declaration_travels_to_the_workers() -> None:
    """What a Dask worker rebuilds (``from_payload``) has the declaration (ROC's bounds)
    and the draws; the campaign's identity depends on it."""
    import json

    from runtime.campaign.spec import from_payload

    tgt = target("trailer")
    code = tgt.setup.code
    c = parse_campaign(SPEC.format(ctrl="roc"), "c.toml", tgt.plant,
                       available=lambda f: code.controller_names,
                       physical_box=lambda d: box_of(code, d))
    back = from_payload(json.loads(json.dumps(c.to_payload())))
    assert back.experiment.physical == c.experiment.physical
    assert back.vary == c.vary and back.digest() == c.digest()
    plain = replace(c, experiment=replace(c.experiment, physical=type(c.experiment.physical)()))
    assert plain.digest() != c.digest()


@pytest.mark.parametrize("plant", ["generated", "mujoco"])
def test_a_run_simulates_its_drawn_robot(plant: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """The runner hands the loop the drawn robot: the mapped parameters, and on MuJoCo the
    drawn bodies (not the robot file's)."""
    from runtime.campaign.physical_draws import physical_params
    from runtime.sim import loop

    seen: dict[str, object] = {}
    original = loop.run

    def spy(*args: object, **kwargs: object) -> object:
        seen.update(kwargs)
        return original(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(loop, "run", spy)
    tgt = target("trailer")
    code = tgt.setup.code
    c = parse_campaign(SPEC.format(ctrl="tdc").replace("duration = 4.0", "duration = 0.5"),
                       "c.toml", tgt.plant, available=lambda f: code.controller_names,
                       physical_box=lambda d: box_of(code, d))
    c = replace(with_plant(c, plant), robot="trailer")
    rec = run_one(c, 0, tgt, base_values(c, tgt.plant, tgt.physical))
    drawn = {k.removeprefix("p.physical."): float(v) for k, v in rec.items()
             if k.startswith("p.physical.")}
    assert seen["plant_params"] == physical_params(code, drawn)
    if plant == "mujoco":
        engine = seen["plant"]
        model = engine.model  # type: ignore[attr-defined]
        assert model.body_mass[model.body("cart").id] == drawn["mass_cart"]
