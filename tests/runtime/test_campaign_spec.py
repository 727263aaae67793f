"""Campaign files and per-run sampling (no Dask, no simulation)."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import pytest

from runtime.bindings.generated import robot
from runtime.campaign.sampling import base_values, draw, run_seed
from runtime.campaign.spec import (
    Campaign,
    CampaignSpecError,
    default_campaign,
    from_payload,
    parse_campaign,
)

ROBOT = {k: float(v) for k, v in robot.PARAMS.items()}
SPEC = """
seed = 5
controllers = ["tdroc", "roc"]
duration = 10.0
[vary."controller.eps"]
min = 0.01
max = 0.5
log = true
[vary."controller.h"]
spread = 0.3
step = 0.005
[vary."robot.m"]
spread = 0.3
[vary."sensing.velocity"]
choices = ["sample-instant", "encoder-average"]
[map]
y = "controller.h"
"""


def parse(text: str) -> Campaign:
    return parse_campaign(text, "c.toml", ROBOT)


@pytest.mark.parametrize(
    ("text", "field"),
    [
        ("sedd = 1", "'sedd'"),
        ("runs = 0", "'runs'"),
        ("chunk = 2.5", "'chunk'"),
        ("controllers = ['tdc', 'pid']", "'controllers'"),
        ("path = 'square'", "'path'"),
        ('[vary."controller.epsilon"]\nspread = 0.3', 'vary."controller.epsilon"'),
        ('[vary."robot.mass"]\nspread = 0.3', 'vary."robot.mass"'),
        ('[vary."controller.eps"]\nspread = 1.5', 'vary."controller.eps".spread'),
        ('[vary."controller.eps"]\nmin = 0.5\nmax = 0.1', 'vary."controller.eps"'),
        ('[vary."controller.eps"]\nspread = 0.3\nmin = 0.1\nmax = 0.2', 'vary."controller.eps"'),
        ('[vary."controller.eps"]\nspred = 0.3', 'vary."controller.eps".spred'),
        ('[vary."controller.eps"]\nmin = 0.0\nmax = 0.2\nlog = true', 'vary."controller.eps"'),
        ('[vary."controller.h"]\nmin = -0.1\nmax = 0.2', "controller.h"),
        ('[vary."sensing.velocity"]\nchoices = ["sampled"]', "sensing.velocity"),
        ('[vary."sensing.velocity"]\nspread = 0.3', 'vary."sensing.velocity"'),
        ('[vary."controller.a"]\nmin = 0.5\nmax = 1.5', "controller.a"),
        ("[map]\nx = 'controller.h'", "'map.x'"),
        ("[map]\ny = 'plant.viscous'", "'map.y'"),
        ("[map]\ngrid = 1", "'map.grid'"),
    ],
)
def test_bad_field_is_named(text: str, field: str) -> None:
    with pytest.raises(CampaignSpecError) as err:
        parse(text)
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith("c.toml: ") and field in msg


def test_spec_round_trips_and_identity_ignores_runs_and_chunk() -> None:
    c = parse(SPEC)
    assert from_payload(c.to_payload()) == c
    bigger = parse(SPEC + "\n").__class__(**{**c.__dict__, "runs": 7, "chunk": 3})
    assert bigger.digest() == c.digest()
    assert parse(SPEC.replace("seed = 5", "seed = 6")).digest() != c.digest()


def test_draws_are_per_index_and_in_range() -> None:
    c = parse(SPEC)
    base = base_values(c, ROBOT)
    first = [draw(c, i, base) for i in range(50)]
    again = [draw(c, i, base) for i in reversed(range(50))][::-1]
    assert first == again
    assert first[0] != first[1] and run_seed(5, 0) != run_seed(5, 1)
    for d in first:
        assert 0.01 <= d["controller.eps"] <= 0.5
        assert 0.07 - 1e-12 <= d["controller.h"] <= 0.13 + 1e-12
        assert math.isclose(d["controller.h"] / 0.005, round(d["controller.h"] / 0.005))
        assert 0.7 * ROBOT["m"] <= d["robot.m"] <= 1.3 * ROBOT["m"]
    assert {d["sensing.velocity"] for d in first} == {"sample-instant", "encoder-average"}


def test_default_campaign_draws_payload_position_and_every_parameter() -> None:
    c = default_campaign(ROBOT, ("m", "I", "K", "Iw"), ROBOT["b"])
    names = dict(c.vary)
    for key in ("robot.m", "plant.viscous", "plant.extra_payload", "controller.eps",
                "controller.h", "controller.k1"):
        assert names[key].spread == pytest.approx(0.3)
    assert names["plant.extra_payload_y"].low == pytest.approx(-0.36 * ROBOT["b"])


def test_experiment_file_is_read_relative_to_the_spec(tmp_path: Path) -> None:
    (tmp_path / "exp.toml").write_text("[controller]\neps = 0.2\n")
    spec = tmp_path / "c.toml"
    spec.write_text('experiment = "exp.toml"\n')
    from runtime.campaign.spec import load_campaign

    assert load_campaign(spec, ROBOT).experiment.controller.eps == 0.2
    spec.write_text('experiment = "missing.toml"\n')
    with pytest.raises(CampaignSpecError, match="'experiment'"):
        load_campaign(spec, ROBOT)


def test_a_failing_run_is_recorded_with_its_error() -> None:
    from runtime.campaign.runner import run_one, target

    # A motor-encoder window that is not a whole number of integration steps at the drawn h.
    c = parse('[vary."controller.h"]\nmin = 0.0951\nmax = 0.0999\n'
              '[vary."sensing.velocity"]\nchoices = ["motor-encoder"]\n')
    tgt = target(None)
    rec = run_one(c, 3, tgt, base_values(c, tgt.plant))
    assert rec["status"] == "error" and rec["index"] == 3 and not rec["stable"]
    assert "sensing.window" in rec["error"] and rec["p.sensing.velocity"] == "motor-encoder"
    assert math.isnan(rec["rms_error"])


def test_robot_of_bodies_on_mujoco_draws_what_the_engine_can_carry(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A bodies-and-wheels robot is its description on MuJoCo: the default campaign draws
    its bodies' masses and yaw inertias instead of its base parameters (and says so) and
    its runs complete on the engine; a campaign file drawing a base parameter is refused
    before any run, naming the field."""
    from runtime.campaign.runner import run_one
    from runtime.campaign.spec import CampaignSpecError
    from runtime.commands.campaign import resolve_campaign

    trailer = Path(__file__).resolve().parents[2] / "modeling/robots/trailer/trailer.toml"
    default, tgt = resolve_campaign(None, trailer, 2, plant="mujoco")
    drawn = dict(default.vary)
    assert default.experiment.plant.model == "mujoco"
    assert not [k for k in drawn if k.startswith("robot.")] and "plant.extra_payload" in drawn
    note = capsys.readouterr().err
    assert "draws each body's mass and yaw inertia" in note and "robot.J_theta_tractor" in note
    assert {"physical.mass_cart", "physical.yaw_inertia_tractor"} <= set(drawn)
    short = replace(default, duration=1.5, controllers=("tdroc",))
    for i in range(2):  # drawn payloads, friction, gains, h, ε, sensing: on the engine
        rec = run_one(short, i, tgt, base_values(short, tgt.plant, tgt.physical))
        assert rec["status"] != "error", rec["error"]  # not the engine refusing a draw
        assert rec["p.physical.mass_cart"] != 15.0
        assert rec["status"] == "ok" or "diverged_error" in rec["error"], rec
    spec = tmp_path / "c.toml"
    spec.write_text('[vary."robot.J_theta_tractor"]\nspread = 0.3\n')
    with pytest.raises(CampaignSpecError, match=r'vary\."robot\.J_theta_tractor".*MuJoCo'):
        resolve_campaign(spec, trailer, 1, plant="mujoco")
    on_model, _ = resolve_campaign(spec, trailer, 1)  # the generated plant draws it
    assert "robot.J_theta_tractor" in dict(on_model.vary)


def test_robot_of_bodies_runs_and_draws_its_predicted_boundary(tmp_path: Path) -> None:
    from runtime.campaign.prediction import predict
    from runtime.campaign.runner import run_one
    from runtime.commands.campaign import resolve_campaign

    trailer = Path(__file__).resolve().parents[2] / "modeling/robots/trailer/trailer.toml"
    default, _ = resolve_campaign(None, trailer, 1)  # its inertial parameters drawn, none at 0
    assert "robot.J_theta_tractor" in dict(default.vary)
    spec = tmp_path / "c.toml"
    spec.write_text('duration = 1.5\ncontrollers = ["tdroc"]\n'
                    '[vary."robot.J_theta_tractor"]\nspread = 0.3\n')
    c, tgt = resolve_campaign(spec, trailer, 1)
    assert tgt.setup.code.name == "trailer" and c.robot_sha256
    rec = run_one(c, 0, tgt, base_values(c, tgt.plant))
    assert rec["status"] == "ok", rec["error"]
    assert 0 < rec["rms_error"] < 0.1
    prediction = predict(c, tgt)
    assert prediction.unavailable is None
    (boundary,) = prediction.boundaries.values()
    assert all(0 < e < math.inf for e in boundary.eps_min)  # TDROC: ε > k̂ / g_max
