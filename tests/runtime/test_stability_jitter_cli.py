"""``wmr stability --jitter-replay`` (issue 46): the adversarial search's worst sequence in
the experiment's stated jitter range run in the closed loop on a chosen plant, and the
jitter results in ``--json`` beside the refusals; bad arguments get one line and exit 2.

Drishti, TDC minimal (``--only``), sample-instant rates, h = 0.1 s, latencies within
± 10 ms of 0 (so in [0, 10 ms]): proved, and its worst sequence stays bounded on the model
plant. A budget whose "inside" sequence diverges (a budget made up for the test: the 0/80 ms
alternation, beyond the constant-delay boundary, called proved) fails the command: the
replay can catch a wrong proof.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from runtime.commands import jitter_report
from runtime.commands import stability as stability_command
from runtime.stability.jitter import Budget, Search

EXPERIMENT = "[sensing]\nvelocity = 'sample-instant'\n[controller]\njitter_time = 0.01\n"


def test_replay_and_json(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    exp = tmp_path / "exp.toml"
    exp.write_text(EXPERIMENT, encoding="utf-8")
    assert stability_command.main(
        ["--experiment", str(exp), "--only", "tdc/minimal", "--no-measure", "--no-delay",
         "--no-saturation", "--jitter-replay", "generated", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert [(r["controller"], r["formulation"]) for r in data["controllers"]] == [
        ("tdc", "minimal")]
    assert "refused" in data
    (row,) = data["jitter"]
    (rng,) = row["ranges"]
    assert rng["range"] == "[controller] jitter" and rng["d_max"] == pytest.approx(0.01)
    assert rng["verdict"] == "proved" and rng["bound"] < 1.0 and rng["gap_bound"] > 0.0
    (rep,) = row["replays"]
    assert rep["plant"] == "generated" and rep["inside_proved"]
    assert not rep["diverged"] and not rep["contradiction"] and rep["growth"] <= 1.0
    assert {d for _, d in rep["sequence"]} <= {0.0, 0.01}


@pytest.mark.parametrize("argv, message", [
    (["--jitter-replay", "bullet"], "--jitter-replay: no plant 'bullet'"),
    (["--only", "pd"], "--only: no controller 'pd'"),
    (["--only", "tdc/cartesian"], "--only: tdc has no formulation 'cartesian'"),
])
def test_bad_arguments_get_one_line(argv: list[str], message: str,
                                    capsys: pytest.CaptureFixture[str]) -> None:
    assert stability_command.main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1, err


def test_a_divergence_inside_a_proved_budget_fails_the_command(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    wrong = Search(1.3, ((0.1, 0.0), (0.1, 0.08)))
    monkeypatch.setattr(jitter_report, "budget",
                        lambda s, g: Budget(0.08, 0.064, 0.061, 0.0, "", wrong, None))
    exp = tmp_path / "exp.toml"
    exp.write_text("[sensing]\nvelocity = 'sample-instant'\n", encoding="utf-8")
    assert stability_command.main(
        ["--experiment", str(exp), "--only", "tdc/minimal", "--no-measure", "--no-delay",
         "--no-saturation", "--jitter-budget", "--jitter-replay"]) == 1
    captured = capsys.readouterr()
    assert "diverged" in captured.out and "CONTRADICTS THE PROOF" in captured.out
    assert "inside a proved jitter range diverged" in captured.err
