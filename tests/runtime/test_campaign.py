"""Campaigns on Dask: a LocalCluster of 2 workers, resume, a separately started scheduler
and worker on loopback, and the command's argument checks."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import campaign_reference as reference
import pyarrow.parquet as pq
import pytest

from runtime.campaign import store
from runtime.campaign.execution import Cluster, connect, execute, project_root
from runtime.campaign.prediction import predict
from runtime.commands.campaign import main, report, resolve_campaign

# Short runs, two controllers, a drawn ε wide enough to cross ROC's predicted boundary.
SPEC = """
seed = 11
controllers = ["tdc", "roc"]
duration = 6.0
chunk = 3
[vary."controller.eps"]
min = 0.005
max = 0.3
log = true
[vary."controller.h"]
spread = 0.2
step = 0.01
[vary."robot.m"]
spread = 0.3
[vary."plant.extra_payload_x"]
min = -0.15
max = 0.15
[map]
y = "controller.h"
grid = 2
"""
RUNS = 10


def rows(out: Path) -> list[dict[str, Any]]:
    """results.parquet or the parts, NaN made comparable."""
    path = out / store.RESULTS
    table = pq.read_table(path) if path.exists() else None
    if table is None:
        tables = [pq.read_table(p) for p in store.part_files(out)]
        import pyarrow as pa

        table = pa.concat_tables(tables).sort_by("index")
    return [{k: ("nan" if isinstance(v, float) and math.isnan(v) else v) for k, v in r.items()}
            for r in table.to_pylist()]


@pytest.fixture(scope="module")
def spec(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("spec") / "campaign.toml"
    path.write_text(SPEC)
    return path


@pytest.fixture(scope="module")
def cluster() -> Iterator[Cluster]:
    c = connect(None, 2, None)
    yield c
    c.close()


@pytest.fixture(scope="module")
def reference_run(spec: Path, cluster: Cluster, tmp_path_factory: pytest.TempPathFactory
                  ) -> Path:
    """The uninterrupted campaign of RUNS runs on the LocalCluster."""
    out = tmp_path_factory.mktemp("full")
    campaign, _ = resolve_campaign(spec, None, RUNS)
    assert store.prepare(out, campaign) == set()
    assert execute(cluster, campaign, list(range(RUNS)), out, progress=False) == RUNS
    return out


def test_small_campaign_on_two_local_workers(spec: Path, cluster: Cluster,
                                             reference_run: Path) -> None:
    assert cluster.workers == 2
    campaign, tgt = resolve_campaign(spec, None, RUNS)
    records = rows(reference_run)
    assert [r["index"] for r in records] == list(range(RUNS))
    assert {r["controller"] for r in records} == {"tdc", "roc"}
    assert len({r["seed"] for r in records}) == RUNS
    assert all(r["status"] in ("ok", "diverged", "init_refused", "error") for r in records)
    assert all(r["status"] != "error" for r in records), [r["error"] for r in records]
    ok = [r for r in records if r["status"] == "ok"]
    assert ok and all(0 < r["rms_error"] < 0.5 for r in ok)
    # Small ε makes ROC's switching term oscillate: simulated unstable, as predicted.
    roc_small = [r for r in records if r["controller"] == "roc" and r["p.controller.eps"] < 0.02]
    assert roc_small and all(not r["stable"] for r in roc_small)
    text = report(reference_run, campaign, tgt, cluster.where)
    assert "| TDC | 5 |" in text and "| ROC | 5 |" in text
    assert "Agreement:" in text and (reference_run / "stability_map.png").stat().st_size > 10_000
    # The summary against the records, recomputed apart (tests/runtime/test_campaign_summary.py has
    # a campaign with every outcome).
    stored = reference.records(reference_run)
    boundaries = {k: (b.y, b.eps_min) for k, b in predict(campaign, tgt).boundaries.items()}
    base = {"sensing.velocity": campaign.experiment.sensing.velocity}
    want = reference.expected_summary(
        stored, campaign.controllers, reference.verdicts(stored, boundaries, campaign.map_y, base))
    reference.check_json(json.loads((reference_run / "summary.json").read_text()), want)
    reference.check_markdown(text, want)


def test_resumed_campaign_equals_uninterrupted(spec: Path, cluster: Cluster,
                                               reference_run: Path, tmp_path: Path) -> None:
    campaign, _ = resolve_campaign(spec, None, RUNS)
    first = [0, 1, 2, 7]  # "killed" after these finished ...
    store.prepare(tmp_path, campaign)
    execute(cluster, campaign, first, tmp_path, progress=False)
    (tmp_path / store.PARTS / ".part-00000009.parquet.tmp").write_bytes(b"half a file")
    done = store.prepare(tmp_path, campaign)  # ... and restarted
    assert done == set(first)
    assert not list((tmp_path / store.PARTS).glob(".*.tmp"))
    todo = [i for i in range(RUNS) if i not in done]
    assert execute(cluster, campaign, todo, tmp_path, progress=False) == RUNS - len(first)
    assert store.finished_indices(tmp_path) == set(range(RUNS))
    assert rows(tmp_path) == rows(reference_run)


def test_folder_of_another_spec_is_refused(spec: Path, reference_run: Path,
                                           tmp_path: Path) -> None:
    other = tmp_path / "other.toml"
    other.write_text(SPEC.replace("seed = 11", "seed = 12"))
    campaign, _ = resolve_campaign(other, None, RUNS)
    with pytest.raises(store.CampaignFolderError, match="another spec"):
        store.prepare(reference_run, campaign)


def run_main(argv: list[str]) -> int:
    """The command's exit status (argparse exits with 2 on a bad option value)."""
    try:
        return main(argv)
    except SystemExit as exc:
        return int(exc.code or 0)


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--runs", "0"], "--runs must be at least 1"),
        (["--workers", "two"], "--workers must be a whole number"),
        (["--scheduler", "tcp://127.0.0.1:9", "--workers", "2"], "--workers sizes"),
    ],
)
def test_bad_arguments_fail_before_work(extra: list[str], message: str, tmp_path: Path,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    assert run_main(["--out", str(tmp_path / "o"), *extra]) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "o" / store.SPEC_FILE).exists()


def test_out_file_and_bad_spec_and_unreachable_scheduler(
        spec: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    afile = tmp_path / "afile"
    afile.write_text("x")
    assert main(["--out", str(afile)]) == 2
    assert "exists and is not a folder" in capsys.readouterr().err
    bad = tmp_path / "bad.toml"
    bad.write_text("[vary.'controller.eps']\nspread = 2\n")
    assert main(["--spec", str(bad), "--out", str(tmp_path / "o1")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "vary.\"controller.eps\".spread" in err
    # The connection is attempted with the campaign's own bounded timeout (not Dask's
    # default, nor none): the real Client is called, and what it was given is recorded.
    # No wall-clock assertion (a loaded machine is slow for no bug).
    import dask.distributed

    given: list[object] = []
    real_client = dask.distributed.Client

    def recording_client(*args: Any, **kwargs: Any) -> Any:
        given.append(kwargs.get("timeout"))
        return real_client(*args, **kwargs)

    monkeypatch.setattr(dask.distributed, "Client", recording_client)
    assert main(["--spec", str(spec), "--scheduler", "tcp://127.0.0.1:9", "--out",
                 str(tmp_path / "o2")]) == 2
    err = capsys.readouterr().err
    assert "--scheduler tcp://127.0.0.1:9: cannot connect" in err and err.count("\n") == 1
    assert not (tmp_path / "o2" / store.SPEC_FILE).exists()
    assert given == ["10.0s"], given


def _wait_for(path: Path, seconds: float) -> dict[str, Any]:
    """The JSON file ``path`` once it is complete (the scheduler creates it before it has
    written it: a read in between got an empty file on a loaded machine)."""
    end = time.time() + seconds
    while True:
        try:
            data: dict[str, Any] = json.loads(path.read_text())
            return data
        except (FileNotFoundError, json.JSONDecodeError):
            if time.time() > end:
                raise TimeoutError(f"{path} did not appear complete") from None
            time.sleep(0.2)


def test_campaign_on_separately_started_scheduler_and_worker(
        spec: Path, reference_run: Path, tmp_path: Path) -> None:
    dask = Path(sys.executable).parent / "dask"
    env = {**os.environ, "PYTHONPATH": str(project_root())}
    cwd = tmp_path / "elsewhere"  # the worker runs from another directory
    cwd.mkdir()
    sched_file = tmp_path / "scheduler.json"
    procs = [subprocess.Popen(
        [str(dask), "scheduler", "--host", "127.0.0.1", "--port", "0",
         "--no-dashboard", "--scheduler-file", str(sched_file)],
        cwd=cwd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        address = _wait_for(sched_file, 120)["address"]
        procs.append(subprocess.Popen(
            [str(dask), "worker", address, "--nworkers", "1", "--nthreads", "1",
             "--no-dashboard"],
            cwd=cwd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        out = tmp_path / "out"
        status = main(["--spec", str(spec), "--runs", str(RUNS), "--scheduler", address,
                       "--out", str(out), "--no-plots", "--quiet"])
        assert status == 0
        assert rows(out) == rows(reference_run)
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in procs:
            p.wait(timeout=30)


def test_campaign_on_the_mujoco_plant(spec: Path, tmp_path: Path,
                                      capsys: pytest.CaptureFixture[str]) -> None:
    """`--plant mujoco`: each run's drawn lumped parameters build the engine's robot; the
    stored campaign says which plant ran; a plant that does not exist is refused."""
    out = tmp_path / "mj"
    assert run_main(["--spec", str(spec), "--runs", "2", "--workers", "1", "--plant", "mujoco",
                     "--out", str(out), "--no-plots", "--quiet"]) == 0
    assert len(rows(out)) == 2
    assert '"model": "mujoco"' in (out / store.SPEC_FILE).read_text()
    capsys.readouterr()
    assert run_main(["--spec", str(spec), "--plant", "bullet", "--out",
                     str(tmp_path / "x")]) == 2
    assert "--plant 'bullet': expected one of generated, mujoco" in capsys.readouterr().err
