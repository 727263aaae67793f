"""Campaign throughput: runs per second with 1 and 2 LocalCluster workers, and the wall time
of a large campaign (docs/CAMPAIGN.md quotes its output).

    python -m runtime.tooling.bench.campaign_throughput [--runs 400] [--rounds 2]
                                                        [--big 10000] [--json FILE]

The default campaign (the paper's setting, every parameter ±30 %, circle of 30 s, the four
controllers in turn). Worker counts are interleaved (1, 2, 1, 2, …) in one session so that
the machine's other load affects both alike; the rate is the runs over the time from the
first submission to the last part written (cluster start and the workers' one-time library
load excluded, as :func:`runtime.campaign.execution.connect` does them before). Also the
in-process rate of one run without Dask (the per-worker ceiling), the CPU seconds the
workers and this process used (runs per worker CPU second do not depend on the machine's
other load), and with ``--big N`` the wall time of an N-run campaign on 2 workers, from the
command line's start to its summary.
Not part of ``make bench``: the default takes several minutes.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import tempfile
import time
from pathlib import Path
from typing import Any

from runtime.campaign import store
from runtime.campaign.execution import connect, execute
from runtime.campaign.runner import base_values, run_one, target
from runtime.commands.campaign import resolve_campaign


def in_process_rate(runs: int) -> float:
    """Runs per second of :func:`runtime.campaign.runner.run_one` in this process."""
    campaign, tgt = resolve_campaign(None, None, runs)
    base = base_values(campaign, tgt.plant, tgt.physical)
    run_one(campaign, 0, tgt, base)  # library, first reference
    t0 = time.perf_counter()
    for i in range(runs):
        run_one(campaign, i, tgt, base)
    return runs / (time.perf_counter() - t0)


def cluster_rate(workers: int, runs: int) -> dict[str, float]:
    """Runs per wall second, and the CPU seconds the workers and this process (client,
    scheduler, Parquet writing) used: on a machine shared with other work the wall rate
    falls, runs per worker CPU second does not."""
    campaign, _ = resolve_campaign(None, None, runs)
    cluster = connect(None, workers, None)
    try:
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp)
            store.prepare(out, campaign)
            cpu0 = cluster.client.run(time.process_time)
            main0 = time.process_time()
            t0 = time.perf_counter()
            n = execute(cluster, campaign, list(range(runs)), out, progress=False)
            wall = time.perf_counter() - t0
            main_cpu = time.process_time() - main0
            cpu1 = cluster.client.run(time.process_time)
            worker_cpu = sum(cpu1[w] - cpu0[w] for w in cpu0)
            return {"runs_per_s": n / wall, "wall_s": wall, "worker_cpu_s": worker_cpu,
                    "runs_per_worker_cpu_s": n / worker_cpu, "main_cpu_s": main_cpu}
    finally:
        cluster.close()


def big_campaign(runs: int, workers: int) -> float:
    """Wall time of ``python -m runtime campaign --runs N`` (summary and map included)."""
    from runtime.commands.campaign import main

    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        assert main(["--runs", str(runs), "--workers", str(workers), "--out", tmp,
                     "--quiet"]) == 0
        return time.perf_counter() - t0


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    p.add_argument("--runs", type=int, default=400, help="runs per measurement")
    p.add_argument("--rounds", type=int, default=2, help="interleaved rounds of 1 and 2")
    p.add_argument("--big", type=int, default=0, help="also time a campaign of this size")
    p.add_argument("--json", type=Path, default=None, help="write the numbers here")
    args = p.parse_args(argv)
    target(None)
    result: dict[str, Any] = {
        "machine": f"{platform.machine()}, {os.cpu_count()} CPUs, {platform.system()}, "
                   f"Python {platform.python_version()}",
        "load_average_at_start": os.getloadavg(),
        "runs_per_measurement": args.runs,
        "in_process": in_process_rate(min(args.runs, 100)),
        "rates": {"1": [], "2": []},
    }
    print(f"in process (no Dask): {result['in_process']:.1f} runs/s", flush=True)
    for _ in range(args.rounds):
        for w in (1, 2):
            m = cluster_rate(w, args.runs)
            result["rates"][str(w)].append(m)
            print(f"{w} worker{'s' if w > 1 else ''}: {m['runs_per_s']:.1f} runs/s "
                  f"({m['runs_per_worker_cpu_s']:.1f} runs per worker CPU second, "
                  f"client+scheduler {m['main_cpu_s']:.1f} CPU s, load average "
                  f"{os.getloadavg()[0]:.1f})", flush=True)
    best = {w: max(m["runs_per_s"] for m in v) for w, v in result["rates"].items()}
    result["speedup"] = best["2"] / best["1"]
    print(f"best: 1 worker {best['1']:.1f}, 2 workers {best['2']:.1f} runs/s, "
          f"speed-up {result['speedup']:.2f}x", flush=True)
    if args.big:
        result["big"] = {"runs": args.big, "workers": 2, "wall_s": big_campaign(args.big, 2)}
        print(f"{args.big}-run campaign on 2 workers: {result['big']['wall_s']:.0f} s wall",
              flush=True)
    result["load_average_at_end"] = os.getloadavg()
    if args.json:
        args.json.write_text(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
