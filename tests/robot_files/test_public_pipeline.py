"""The corpus's imported robots (tests/robots/public/, sources.toml) through the whole
pipeline: ``wmr import`` → ``wmr model`` (into a temporary folder) → ``wmr stability`` →
a short ``wmr reproduce`` (the circle and the lawn mower, 2 s each, sample-instant rates,
the generated plant, no plots).

Each robot is derived once (a module-scoped fixture, 4-16 s on a loaded machine; its
stability and reproduce 2-7 s each), and then:

* its verdict: ``wmr stability`` (h = 0.1 s, circle) finds TDROC in the minimal
  formulation stable, at the spectral radius recorded in sources.toml and README.md's
  table (three decimals);
* the short reproduce agrees with that verdict as docs/CONTROLLERS.md says it must: every
  run whose loop the verdict finds unstable before any switching gain is refused before it
  starts, and every other run is either refused for its own stated reason (the paper
  formulation's TDE condition over a ±30 % box) or ends ``ok`` (within 10 % of the path's
  scale); none fails or drifts off the path. (A switching gain beyond the stable one is
  warned about, not refused: the MiR100's ROC, predicted unstable at ρ/ε = 182 > 94.7,
  runs and tracks for these 2 s.) The counts of ``ok`` and refused runs are the recorded
  ones.

Six robots run here (``through = "reproduce"``); three are the same robot as one of them
under another file (the 2025 Burger, the 2025 Waffle and the Waffle Pi: ``same_as``):
:func:`test_a_same_robot_imports_to_the_same_numbers` checks that each imports to exactly
the numbers of the robot it names, so its recorded outcome is that robot's. All nine:
``WMR_PUBLIC_ALL=1 pytest -p no:xdist tests/robot_files/test_public_pipeline.py``
(about 2 minutes).
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import math
import os
import tomllib
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import pytest

from modeling.description import RobotDescription
from modeling.importers import import_robot
from runtime.cli import main as wmr

PUBLIC = Path(__file__).resolve().parents[1] / "robots" / "public"
ROBOTS: list[dict[str, Any]] = tomllib.loads((PUBLIC / "sources.toml").read_text())["robot"]
IMPORTED = [r for r in ROBOTS if r["outcome"] == "imported"]
RUN = [r for r in IMPORTED if r.get("through") == "reproduce"
       or (os.environ.get("WMR_PUBLIC_ALL") and "same_as" in r)]
SHORT = "[paths]\ncircle_duration = 2.0\nlawnmower_duration = 2.0\n"


@dataclass(frozen=True)
class Outcome:
    """What the pipeline gave one robot: ``wmr stability --json``'s rows by (controller,
    formulation), and the short reproduce's ``metrics.csv`` rows."""

    verdicts: dict[tuple[str, str], dict[str, Any]]
    runs: list[dict[str, str]]


@pytest.fixture(scope="module", params=RUN, ids=lambda r: r["file"])
def outcome(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory,
            ) -> tuple[dict[str, Any], Outcome]:
    entry: dict[str, Any] = request.param
    folder = tmp_path_factory.mktemp("public")
    robot, code = folder / "robot.toml", folder / "code"
    assert wmr(["import", str(PUBLIC / entry["file"]), "--out", str(robot)]) == 0
    assert wmr(["model", "--robot", str(robot), "--out", str(code)]) == 0
    printed = io.StringIO()  # capsys is per test; the fixture is per module
    with contextlib.redirect_stdout(printed):
        assert wmr(["stability", "--robot", str(robot), "--generated", str(code), "--json",
                    "--no-measure", "--no-delay", "--no-saturation"]) == 0
    rows = json.loads(printed.getvalue())["controllers"]
    experiment = folder / "short.toml"
    experiment.write_text(SHORT)
    results = folder / "reproduce"
    assert wmr(["reproduce", "--robot", str(robot), "--generated", str(code), "--experiment",
                str(experiment), "--sensing", "sample-instant", "--no-plots", "--out",
                str(results)]) == 0
    with (results / "metrics.csv").open(newline="") as f:
        runs = list(csv.DictReader(f))
    return entry, Outcome({(r["controller"], r["formulation"]): r for r in rows}, runs)


def test_tdroc_minimal_is_stable_at_the_recorded_radius(
        outcome: tuple[dict[str, Any], Outcome]) -> None:
    entry, got = outcome
    tdroc = got.verdicts[("tdroc", "minimal")]
    assert tdroc["stable"] and tdroc["h"] == 0.1 and tdroc["operating_point"] == "circle"
    assert round(tdroc["spectral_radius"], 3) == entry["tdroc_radius"]


def test_the_short_reproduce_agrees_with_the_verdict(
        outcome: tuple[dict[str, Any], Outcome]) -> None:
    entry, got = outcome
    assert {r["path"] for r in got.runs} == {"circle", "lawnmower"}
    for run in got.runs:
        verdict = got.verdicts[(run["controller"], run["formulation"])]
        where = f"{run['path']} {run['formulation']} {run['controller']}"
        if verdict["radius_without_switching"] >= 1:
            assert run["status"] == "refused", where
        else:
            assert run["status"] in ("ok", "refused"), where
        if run["status"] == "ok":
            assert math.isfinite(float(run["rms_error_m"])), where
    ok = sum(r["status"] == "ok" for r in got.runs)
    refused = sum(r["status"] == "refused" for r in got.runs)
    assert ok + refused == len(got.runs)
    assert (ok, refused) == (entry["runs_ok"], entry["runs_refused"])
    assert any(r["status"] == "ok" and (r["controller"], r["formulation"]) ==
               ("tdroc", "minimal") for r in got.runs)


def numbers(path: Path) -> RobotDescription:
    """An imported robot's description under no name (versions of a file name the robot
    differently); its equality compares every body, joint and wheel number."""
    return replace(import_robot(path).description, name="")


@pytest.mark.parametrize("entry", [r for r in IMPORTED if "same_as" in r],
                         ids=lambda r: r["file"])
def test_a_same_robot_imports_to_the_same_numbers(entry: dict[str, Any]) -> None:
    """A file recorded as the same robot as another (``same_as``) imports to its numbers
    exactly, so the pipeline's outcome there is its outcome."""
    other = next(r for r in IMPORTED if r["file"] == entry["same_as"])
    assert other.get("through") == "reproduce"
    assert numbers(PUBLIC / entry["file"]) == numbers(PUBLIC / other["file"])
    for key in ("tdroc_radius", "runs_ok", "runs_refused"):
        assert entry[key] == other[key], key


def test_every_imported_robot_has_an_outcome_in_the_table() -> None:
    table = (PUBLIC / "README.md").read_text()
    rows = {line.split("|")[1].strip(): line for line in table.splitlines()
            if line.startswith("| `")}
    for entry in IMPORTED:
        assert entry.get("through") == "reproduce" or "same_as" in entry, entry["file"]
        row = rows[f"`{entry['file']}`"]
        assert f"ρ {entry['tdroc_radius']:.3f}" in row, row
        assert f"{entry['runs_ok']} ok, {entry['runs_refused']} refused" in row, row
