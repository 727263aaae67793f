"""``python -m runtime campaign``: a robustness campaign on Dask, resumable, summarised.

    wmr campaign [--spec FILE.toml] [--robot ROBOT] [--generated DIR] [--runs N]
                 [--scheduler tcp://HOST:PORT] [--workers N] --out DIR

Every argument is checked before any run (one-line error, exit status 2); then the runs not
yet in DIR run on a LocalCluster (``--workers``, default: the CPU count) or on the cluster of
``--scheduler``, each finished task is written to DIR/parts, and DIR gets ``results.parquet``,
``summary.md``, ``summary.json`` and ``stability_map.png``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

from runtime.bindings.physical_bounds import box_of
from runtime.campaign import store
from runtime.campaign.spec import (
    Campaign,
    CampaignSpecError,
    Distribution,
    default_campaign,
    load_campaign,
)
from runtime.commands.options import add_plant_option, add_robot_options, print_audit
from runtime.commands.output_folder import OutputFolderError, writable_folder
from runtime.experiment.settings import PLANT_MODELS, check_contact


def _positive_int(option: str) -> Any:
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"{option} must be a whole number, got {text!r}") from None
        if value < 1:
            raise argparse.ArgumentTypeError(f"{option} must be at least 1, got {value}")
        return value

    return parse


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="wmr campaign",
        description="Closed-loop runs over the uncertainty box through the generated C, on a "
        "local Dask cluster or an existing one; resumable; summary and stability map.")
    p.add_argument("--spec", type=Path, default=None, metavar="FILE.toml",
                   help="campaign file (default: the paper's setting, every parameter ±30 %%, "
                   "payload positions random)")
    add_robot_options(p)
    add_plant_option(p)
    p.add_argument("--runs", type=_positive_int("--runs"), default=None,
                   help="number of runs (default: the spec's runs, 1000)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="an existing Dask scheduler, e.g. tcp://10.0.0.5:8786 (default: a "
                   "LocalCluster on this machine)")
    p.add_argument("--workers", type=_positive_int("--workers"), default=None,
                   help="LocalCluster worker processes (default: the CPU count)")
    p.add_argument("--out", type=Path, required=True, metavar="DIR", help="output folder")
    p.add_argument("--no-plots", action="store_true", help="skip stability_map.png")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    return p


def with_plant(campaign: Campaign, model: str) -> Campaign:
    """``campaign`` run on the plant ``model`` (``--plant``)."""
    if model not in PLANT_MODELS:
        raise CampaignSpecError(f"--plant {model!r}: expected one of {', '.join(PLANT_MODELS)}")
    exp = campaign.experiment
    exp = replace(exp, plant=replace(exp.plant, model=model))
    check_contact(exp, "--plant")
    return replace(campaign, experiment=exp)


def engine_draws(campaign: Campaign, code: Any, default: bool) -> Campaign:
    """On MuJoCo a ``[lumped]`` or ``[physical]`` robot is built from each run's drawn
    parameters (``modeling.planar_robot.from_lumped``), but a bodies-and-wheels robot is
    its description's bodies and wheels (``runtime.setting.layout.robot_layout``): a drawn
    base parameter has no masses and inertias to become there. Its default campaign draws
    what the engine can carry (payload masses and places, bearing friction, gains, h, ε,
    sensing) and not ``robot.*``; a campaign file that draws ``robot.*`` is refused here,
    before any run, naming the field."""
    if (campaign.experiment.plant.model != "mujoco"
            or getattr(code.robot, "LAYOUT", None) is None):
        return campaign
    drawn = [k for k, _ in campaign.vary if k.startswith("robot.")]
    if not drawn:
        return campaign
    if not default:
        raise CampaignSpecError(
            f"{campaign.source}: vary.\"{drawn[0]}\": robot '{code.name}' runs on MuJoCo as "
            "its description's bodies and wheels, which a drawn base parameter cannot "
            "change; draw its physical quantities (physical.*, or [physical_uncertainty]: "
            "masses, inertias, centres of mass, as bodies on the engine and through the map "
            "on the generated plant)")
    print(f"note: robot '{code.name}' on MuJoCo: its description's bodies and wheels are "
          f"the engine's robot; the default campaign draws each body's mass and yaw inertia "
          f"(±30 %, physical.*) instead of {', '.join(drawn)}", file=sys.stderr)
    bodies = [b[0] for b in code.robot.LAYOUT["bodies"]]
    physical = [(f"physical.{f}_{b}", Distribution(spread=0.3)) for b in bodies
                for f in ("mass", "yaw_inertia")]
    return replace(campaign, vary=tuple(sorted(
        [(k, d) for k, d in campaign.vary if not k.startswith("robot.")] + physical)))


def resolve_campaign(spec: Path | None, robot: str | Path | None, runs: int | None,
                     generated: Path | None = None,
                     plant: str | None = None) -> tuple[Campaign, Any]:
    """The checked campaign and its robot target (raises ``CampaignSpecError`` or
    ``ValueError`` with a one-line message). The campaign's experiment is scaled to the
    robot as every command scales it (identity for the paper's robot). ``plant``
    (``--plant``) overrides the experiment's ``[plant] model`` (:func:`engine_draws`)."""
    from runtime.campaign.runner import target
    from runtime.setting.scale import robot_scale, scaled_experiment

    # an absolute path for the workers (a robot's name stays a name)
    named = str(robot) if robot is not None else None
    if named is not None and Path(named).exists():
        named = str(Path(named).resolve())
    folder = str(generated.resolve()) if generated is not None else None
    tgt = target(named, folder)
    print_audit(tgt.setup)
    code = tgt.setup.code

    def available(formulation: str) -> tuple[str, ...]:
        if formulation not in code.formulations:
            raise CampaignSpecError(f"field 'formulation': robot '{tgt.name}' has no "
                                    f"{formulation} formulation generated (it has "
                                    f"{', '.join(code.formulations)})")
        return tuple(c.name for _, c in code.runs((formulation,)))

    if spec is None:
        campaign = default_campaign(tgt.plant, tgt.inertial, tgt.track,
                                    controllers=available(Campaign().formulation))
    else:
        box = ((lambda decl: box_of(code, decl))
               if getattr(code.robot, "PHYSICAL", None) else None)
        campaign = load_campaign(spec, tgt.plant, available, box)
    exp, _ = scaled_experiment(campaign.experiment, robot_scale(code, tgt.nominal))
    campaign = replace(campaign, experiment=exp, runs=runs or campaign.runs, robot=named,
                       generated=folder, robot_sha256=tgt.sha256,
                       source=str(spec) if spec else campaign.source)
    if plant is not None:
        campaign = with_plant(campaign, plant)
    return engine_draws(campaign, code, default=spec is None), tgt


def main(argv: list[str] | None = None) -> int:
    args = parser().parse_args(argv)
    start = time.perf_counter()
    if args.scheduler is not None and args.workers is not None:
        print("error: --workers sizes the local cluster; with --scheduler the cluster's own "
              "workers run the campaign", file=sys.stderr)
        return 2
    try:
        campaign, tgt = resolve_campaign(args.spec, args.robot, args.runs, args.generated,
                                         args.plant_model)
        out = writable_folder(args.out)
        store.check_folder(out, campaign)
    except (CampaignSpecError, OutputFolderError, store.CampaignFolderError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    from runtime.campaign.execution import CampaignExecutionError, connect, execute

    workers = args.workers or os.cpu_count() or 1
    try:
        cluster = connect(args.scheduler, workers, campaign.robot, campaign.generated)
    except CampaignExecutionError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    try:
        done = store.prepare(out, campaign)  # nothing is written before the cluster is up
        todo = [i for i in range(campaign.runs) if i not in done]
        if not args.quiet:
            print(f"campaign {campaign.digest()[:12]}: {campaign.runs} runs, "
                  f"{campaign.runs - len(todo)} already in {out}, {len(todo)} to run on "
                  f"{cluster.where} ({cluster.workers} workers)", file=sys.stderr, flush=True)
        t0 = time.perf_counter()
        written = execute(cluster, campaign, todo, out, progress=not args.quiet)
        seconds = time.perf_counter() - t0
    finally:
        cluster.close()
    text = report(out, campaign, tgt, cluster.where, plots=not args.no_plots)
    print(text)
    rate = written / seconds if seconds > 0 else math.nan
    print(f"wrote {out}: {written} runs in {seconds:.1f} s ({rate:.1f} runs/s), wall time "
          f"{time.perf_counter() - start:.1f} s")
    return 0


def report(out: Path, campaign: Campaign, tgt: Any, where: str, plots: bool = True) -> str:
    """results.parquet, the summary and the map from the parts in ``out``; the summary's
    Markdown."""
    import pyarrow.compute as pc

    from runtime.campaign.prediction import predict
    from runtime.campaign.summary import markdown, summarise

    sch = store.schema(campaign)
    table = store.read_results(out, sch)
    table = table.filter(pc.less(table.column("index"), campaign.runs))
    store.write_results(out, table)
    pred = predict(campaign, tgt)
    summary = summarise(table, campaign, pred)
    names = []
    if plots:
        from runtime.campaign.plots import stability_map

        stability_map(table, campaign, pred, summary, out / "stability_map.png")
        names.append("stability_map.png")
    text = markdown(summary, campaign, where, names, tgt.setup.warnings)
    store.atomic_write_text(out / "summary.md", text)
    store.atomic_write_text(out / "summary.json",
                            json.dumps(_json_safe(summary), indent=2, sort_keys=True))
    return text


def _json_safe(x: Any) -> Any:
    if isinstance(x, float) and not math.isfinite(x):
        return None if math.isnan(x) else ("inf" if x > 0 else "-inf")
    if isinstance(x, dict):
        return {k: _json_safe(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_json_safe(v) for v in x]
    return x


if __name__ == "__main__":
    sys.exit(main())
