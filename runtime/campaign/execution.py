"""Running a campaign on Dask: a LocalCluster on this machine, or any existing cluster.

The runs to do are cut into chunks of ``campaign.chunk`` runs, one Dask task each
(:func:`runtime.campaign.runner.run_chunk`), so that task overhead stays small next to the
simulations; each finished task's records are written at once as a Parquet part
(:mod:`runtime.campaign.store`) and a progress bar counts the runs. The same code runs on a
``LocalCluster`` and on ``--scheduler tcp://HOST:PORT``: workers only need to import this
project (same environment, or ``PYTHONPATH``) — :func:`connect` checks they can, and has
every worker load the compiled C once before any task.
"""

from __future__ import annotations

import json
import logging
import os
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from runtime.campaign import store
from runtime.campaign.runner import empty_record, run_chunk, warm_up
from runtime.campaign.spec import Campaign


class CampaignExecutionError(RuntimeError):
    """The cluster cannot run the campaign; the message says why."""


@dataclass
class Cluster:
    """A connected Dask client and the local cluster it owns (None for --scheduler)."""

    client: Any
    local: Any | None
    workers: int
    where: str

    def close(self) -> None:
        self.client.close()
        if self.local is not None:
            self.local.close()


def project_root() -> Path:
    import runtime

    return Path(runtime.__file__).resolve().parent.parent


def connect(scheduler: str | None, workers: int, robot: str | None,
            generated: str | None = None, timeout: float = 10.0) -> Cluster:
    """A client on a new LocalCluster of ``workers`` single-threaded processes, or on the
    scheduler at ``scheduler``; every worker has loaded the robot's compiled C."""
    from dask.distributed import Client, LocalCluster

    local = None
    try:
        if scheduler is None:
            # Workers are new processes: make sure they import this project's code.
            root = str(project_root())
            paths = os.environ.get("PYTHONPATH", "").split(os.pathsep)
            if root not in paths:
                os.environ["PYTHONPATH"] = os.pathsep.join([root, *filter(None, paths)])
            local = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                 dashboard_address=None, silence_logs=logging.ERROR)
            client = Client(local)
            where = f"LocalCluster, {workers} worker{'s' if workers > 1 else ''}"
        else:
            client = Client(scheduler, timeout=f"{timeout}s")
            where = f"scheduler {scheduler}"
    except (OSError, TimeoutError) as exc:
        if local is not None:
            local.close()
        raise CampaignExecutionError(
            f"--scheduler {scheduler}: cannot connect ({str(exc).splitlines()[0]})"
            if scheduler else f"cannot start a local Dask cluster: {exc}") from None
    cluster = Cluster(client, local, workers, where)
    try:
        client.wait_for_workers(1, timeout=3 * timeout)
        answers = client.run(warm_up, robot, generated)
    except TimeoutError:
        cluster.close()
        raise CampaignExecutionError(f"{where}: no worker joined within {3 * timeout:g} s "
                                     "(start one with `dask worker ADDRESS`)") from None
    except Exception as exc:
        cluster.close()
        raise CampaignExecutionError(
            f"{where}: a worker cannot run the campaign ({type(exc).__name__}: {exc}); start "
            f"workers in this project's environment with PYTHONPATH={project_root()}"
        ) from None
    cluster.workers = len(answers)
    return cluster


def chunks(indices: Sequence[int], size: int) -> list[list[int]]:
    return [list(indices[i : i + size]) for i in range(0, len(indices), size)]


def execute(cluster: Cluster, campaign: Campaign, todo: Sequence[int], out: Path,
            progress: bool = True) -> int:
    """Run ``todo`` (run indices) on the cluster, writing each finished task's records as
    a part in ``out``; returns the number of runs written."""
    from dask.distributed import as_completed
    from tqdm import tqdm

    payload = json.dumps(campaign.to_payload(), sort_keys=True)
    sch = store.schema(campaign)
    futures, chunk_of = [], {}
    for chunk in chunks(todo, campaign.chunk):
        fut = cluster.client.submit(run_chunk, payload, chunk, pure=False)
        futures.append(fut)
        chunk_of[fut.key] = chunk
    finished = as_completed(futures)
    del futures  # as_completed holds them; each is released once written
    written = 0
    bar = tqdm(total=len(todo), unit="run", desc="campaign", disable=not progress,
               file=sys.stderr, smoothing=0.05)
    try:
        for fut in finished:
            chunk = chunk_of.pop(fut.key)
            try:
                records = fut.result()
            except Exception as exc:  # the task itself failed (e.g. its worker died)
                records = []
                for i in chunk:
                    rec = empty_record(campaign, i)
                    rec["error"] = f"task failed: {type(exc).__name__}: {exc}"
                    records.append(rec)
            store.write_part(out, records, sch)
            written += len(records)
            bar.update(len(records))
            fut.release()
    finally:
        bar.close()
    return written
