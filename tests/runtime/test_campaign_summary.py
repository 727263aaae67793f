"""A campaign's summary.json and summary.md against its run records, recomputed apart
(``tests/campaign_reference.py``): counts per outcome, failure and unstable rates, the
percentiles and worst run, and the agreement with the predicted boundary.

The campaign is small (24 runs of 6 s, run in this process through the function a Dask
task runs, ``runner.run_chunk``, and written as parts as ``execute`` writes them) and has
every outcome: ``ok``; ``diverged`` (a tight ``diverged_error``); ``error`` (a drawn
motor-encoder window longer than a drawn sample time, refused by the experiment checks);
``init_refused``. No drawn setting reaches the C init with a configuration it refuses (the
experiment checks come first), so the C init is handed a negative torque limit for the
runs whose drawn payload offset is below ``REFUSE_BELOW``: the real init refuses them.
"""

from __future__ import annotations

import inspect
import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from campaign_reference import (
    STATUSES,
    Boundaries,
    Row,
    check_json,
    check_markdown,
    expected_summary,
    records,
    verdicts,
)

from runtime.campaign import store
from runtime.campaign.execution import chunks
from runtime.campaign.prediction import predict
from runtime.campaign.runner import run_chunk
from runtime.campaign.spec import Campaign
from runtime.commands.campaign import report, resolve_campaign

SPEC = """
seed = 11
controllers = ["tdc", "roc"]
duration = 6.0
chunk = 5
diverged_error = 0.02
[vary."controller.eps"]
min = 0.005
max = 0.3
log = true
[vary."controller.h"]
choices = [0.05, 0.1]
[vary."sensing.velocity"]
choices = ["sample-instant", "motor-encoder"]
[vary."sensing.window"]
choices = [0.01, 0.08]
[vary."robot.m"]
spread = 0.3
[vary."plant.extra_payload_x"]
min = -0.15
max = 0.15
[map]
y = "controller.h"
grid = 2
"""
RUNS = 24
REFUSE_BELOW = -0.1  # m: drawn plant.extra_payload_x below this gets a refused init


@pytest.fixture(scope="module")
def campaign_run(tmp_path_factory: pytest.TempPathFactory) -> Iterator[
        tuple[Path, Campaign, Any]]:
    """The campaign's folder after its runs and report, its campaign and robot target."""
    import runtime.sim.loop as sim_loop

    folder = tmp_path_factory.mktemp("campaign")
    spec = folder / "campaign.toml"
    spec.write_text(SPEC)
    campaign, tgt = resolve_campaign(spec, None, RUNS)
    out = folder / "out"
    out.mkdir()
    store.prepare(out, campaign)
    real_config = sim_loop.controller_config

    def refused_for_some(*args: Any, **kwargs: Any) -> Any:
        cfg = real_config(*args, **kwargs)
        exp = inspect.signature(real_config).bind(*args, **kwargs).arguments["exp"]
        if exp.plant.extra_payload_x < REFUSE_BELOW:
            cfg.tau_max = -1.0  # the C init's WMR_ERR_BAD_TORQUE_LIMIT
        return cfg

    payload = json.dumps(campaign.to_payload(), sort_keys=True)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(sim_loop, "controller_config", refused_for_some)
        for chunk in chunks(range(RUNS), campaign.chunk):
            store.write_part(out, run_chunk(payload, chunk), store.schema(campaign))
    report(out, campaign, tgt, "this process", plots=False)
    yield out, campaign, tgt


@pytest.fixture(scope="module")
def recomputed(campaign_run: tuple[Path, Campaign, Any]
               ) -> tuple[list[Row], dict[str, Any], Boundaries]:
    """The stored records, the summary recomputed from them, and the predicted boundary
    (the summary's input: ε_min at the map's grid points)."""
    out, campaign, tgt = campaign_run
    rows = records(out)
    boundaries = {key: (b.y, b.eps_min) for key, b in predict(campaign, tgt).boundaries.items()}
    predicted = verdicts(rows, boundaries, campaign.map_y, {})
    return rows, expected_summary(rows, campaign.controllers, predicted), boundaries


def test_campaign_has_every_outcome(recomputed: tuple[list[Row], dict[str, Any], Boundaries]
                                    ) -> None:
    """What the checks below rest on: each outcome occurs, the ok runs' numbers differ
    (a swapped percentile shows), and the prediction is both right and wrong."""
    rows, want, _ = recomputed
    assert [r["index"] for r in rows] == list(range(RUNS))
    assert {r["status"] for r in rows} == set(STATUSES)
    refused = [r for r in rows if r["status"] == "init_refused"]
    assert all(r["p.plant.extra_payload_x"] < REFUSE_BELOW and r["status_code"] == -13
               for r in refused)
    errors = [r for r in rows if r["status"] == "error"]
    assert all("'sensing.window'" in r["error"] for r in errors)
    for ctrl, s in want["controllers"].items():
        assert s["ok"] >= 4 and 0 < s["failure_rate"] < 1, ctrl
        p = s["rms_error_m"]
        assert p["p50"] < p["p90"] < p["p99"] < p["max"], ctrl
    a = want["agreement"]
    assert 0 < a["agree"] < a["runs"] and a["agree"] != a["runs"] - a["agree"]


def test_summary_json_matches_the_records(
        campaign_run: tuple[Path, Campaign, Any],
        recomputed: tuple[list[Row], dict[str, Any], Boundaries]) -> None:
    out = campaign_run[0]
    check_json(json.loads((out / "summary.json").read_text()), recomputed[1])


def test_summary_md_matches_the_records(
        campaign_run: tuple[Path, Campaign, Any],
        recomputed: tuple[list[Row], dict[str, Any], Boundaries]) -> None:
    out = campaign_run[0]
    check_markdown((out / "summary.md").read_text(), recomputed[1])


def test_reference_computation_sees_a_changed_record(
        campaign_run: tuple[Path, Campaign, Any],
        recomputed: tuple[list[Row], dict[str, Any], Boundaries]) -> None:
    """The comparison is not vacuous: one ok run recorded as diverged changes what the
    summary must say."""
    out, campaign, _ = campaign_run
    rows, want, boundaries = recomputed
    ok = next(r for r in rows if r["status"] == "ok")
    changed = [dict(r, status="diverged") if r is ok else r for r in rows]
    other = expected_summary(changed, campaign.controllers,
                             verdicts(changed, boundaries, campaign.map_y, {}))
    summary = json.loads((out / "summary.json").read_text())
    check_json(summary, want)
    with pytest.raises(AssertionError):
        check_json(summary, other)
