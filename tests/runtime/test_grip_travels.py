"""The grip verdict travels (issue 45): ``wmr freeze``'s header and the campaign's summary
carry ``wmr stability``'s saturation and grip verdict (``slips``: time, wheel, margin and
the ``traction_mu`` to set), from the same function
(:func:`runtime.stability.saturation.saturation_verdict`), not a second implementation.

The case: Drishti, h = 0.25 s, TDROC in the paper formulation on a μ = 1 floor (linearly
stable, the wheels slip from about 3.25 s; ``traction_mu`` = 1 keeps grip), the one
tests/runtime/test_grip_verdict.py pins for ``wmr stability``. Each test compares the
carried line with the verdict computed here, so dropping it, or recomputing it otherwise,
fails. About 15 s on one core (gcc builds the generated C once for freeze).
"""

from __future__ import annotations

import shutil
from dataclasses import replace
from pathlib import Path

import pytest

from runtime.bindings.generated import load_robot_code
from runtime.campaign.prediction import Prediction, grip_verdicts
from runtime.campaign.runner import target
from runtime.campaign.spec import parse_campaign
from runtime.campaign.summary import markdown
from runtime.commands.freeze import main as freeze_main
from runtime.experiment.settings import Experiment
from runtime.stability.saturation import grip_data, grip_line, saturation_verdict

DRISHTI = load_robot_code("")
NOMINAL = dict(DRISHTI.params)
H = 0.25
CAMPAIGN = """\
runs = 1
controllers = ["tdroc"]
formulation = "paper"
path = "circle"
duration = 30.0
"""


def _exp() -> Experiment:
    exp = Experiment()
    return replace(exp, controller=replace(exp.controller, h=H))


@pytest.fixture(scope="module")
def verdict() -> object:
    v = saturation_verdict(DRISHTI, "tdroc", "paper", NOMINAL, _exp(), simulate=True)
    assert v.verdict == "slips" and v.slip is not None and v.traction_mu == 1.0, v
    return v


@pytest.mark.skipif(shutil.which("gcc") is None, reason="wmr freeze builds the C with gcc")
def test_the_frozen_header_carries_the_grip_verdict(verdict: object, tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    experiment = tmp_path / "exp.toml"
    experiment.write_text(f"[controller]\nh = {H}\n", encoding="utf-8")
    out = tmp_path / "fw"
    assert freeze_main(["--controller", "tdroc", "--formulation", "paper", "--experiment",
                        str(experiment), "--out", str(out)]) == 0
    line = f"Grip verdict: {grip_line(verdict)}"  # type: ignore[arg-type]
    assert "slips" in line and "wheel '" in line and "traction_mu = 1" in line
    header = next(out.glob("*_tdroc_frozen.h")).read_text(encoding="utf-8")
    assert " ".join(line.split()) in " ".join(header.split())
    assert f"warning: {line}" in capsys.readouterr().err
    # the sampled-data line does not call it stable where a wheel slips
    assert "tdroc/paper stable:" not in header
    assert "tdroc/paper linearly stable but slips" in header


def test_the_campaign_summary_carries_the_grip_verdict(verdict: object) -> None:
    campaign = replace(parse_campaign(CAMPAIGN, "c.toml", NOMINAL), experiment=_exp())
    tgt = target(None)
    grip = grip_verdicts(campaign, tgt)
    assert grip["tdroc"] == grip_data(verdict)  # type: ignore[arg-type]
    data = grip["tdroc"]
    slip = data["slip"]
    assert isinstance(slip, dict) and slip["wheel"] in ("right", "left") and slip["t"] > 0
    assert data["traction_mu"] == 1.0 and data["verdict"] == "slips"
    summary = {"runs": 0, "controllers": {}, "agreement": None, "prediction": "none",
               "grip": grip}
    text = markdown(summary, campaign, "<test>", [])
    assert f"- TDROC: {grip_line(verdict)}" in text  # type: ignore[arg-type]
    assert Prediction({}, grip=grip).grip == grip
