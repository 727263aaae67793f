"""One campaign run through the generated C: what a Dask worker executes.

A run draws its parameters (:mod:`runtime.campaign.sampling`), applies them to the base
experiment (``section.field``) and to the simulated robot (``robot.KEY``; the controllers
keep the nominal model), and simulates its controller on the campaign's path:

* the paper's differential drive (Drishti, or a ``[lumped]``/``[physical]`` robot file):
  :func:`runtime.paper.simulate.run`, the RK4 plant in C, without the configuration checks
  (a campaign records what happens, the prediction is compared afterwards);
* a robot file of bodies and wheels: :func:`runtime.robot_simulation.run` on its generated
  code, with the experiment scaled to it as ``reproduce --robot`` does.

The compiled library, the references and ROC's bounds are cached per worker process
(module level): a worker compiles or loads the C once, not per run.

Outcome of a run (``status``): ``ok``; ``init_refused`` (the C init's status code in
``status_code``); ``diverged`` (a step failed, the plant became non-finite, or the position
error exceeded ``diverged_error``); ``error`` (any exception, its text in ``error``).
``stable`` is the simulated verdict the stability map compares with the prediction: ``ok``
and no sampled-data limit cycle, i.e. ``chatter`` = RMS(Δτ)/RMS(τ) over the second half of
the run below ``chatter_limit`` (an oscillating switching term alternates τ sample to
sample: chatter ≈ 2; a stable loop's torque varies slowly: chatter ≪ 1).
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass, replace
from functools import cache, lru_cache
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from runtime.campaign.sampling import base_values, controller_of, draw, run_seed
from runtime.campaign.spec import Campaign, Value, from_payload, with_values
from runtime.experiment import Experiment, check_sample_count, check_sensing

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Target:
    """The robot a campaign runs: its nominal model and simulated robot before drawing."""

    name: str
    kind: str  # "paper": the wmr_ code through runtime.paper.simulate; "described"
    nominal: dict[str, float]
    plant: dict[str, float]  # the simulated robot's parameters (robot.KEY may be drawn)
    inertial: tuple[str, ...]
    track: float
    robot_file: str | None
    sha256: str | None


@cache
def target(robot_file: str | None) -> Target:
    """Drishti (``None``) or the robot of a robot file (cached per process)."""
    if robot_file is None:
        from runtime.generated_modules import robot

        params = {k: float(v) for k, v in robot.PARAMS.items()}
        return Target(robot.NAME, "paper", params, params, ("m", "I", "K", "Iw"), params["b"],
                      None, None)
    from modeling.robot_io import is_description, read_robot_text, text_digest
    from runtime.robot_scale import inertial_keys, robot_scale
    from runtime.robot_source import resolve

    path = Path(robot_file)
    setup = resolve(path)
    digest = text_digest(read_robot_text(path))
    if is_description(path):
        scale = robot_scale(setup.code, setup.nominal)
        return Target(setup.name, "described", setup.nominal, setup.plant,
                      inertial_keys(setup.code, setup.nominal), scale.track, robot_file, digest)
    return Target(setup.name, "paper", setup.nominal, setup.nominal, ("m", "I", "K", "Iw"),
                  setup.nominal["b"], robot_file, digest)


@lru_cache(maxsize=8)
def _campaign(text: str) -> Campaign:
    return from_payload(json.loads(text))


# ----------------------------------------------------------------------------- references


@lru_cache(maxsize=256)
def _paper_reference(path: str, nominal: tuple[tuple[str, float], ...], h: float,
                     duration: float) -> Any:
    from runtime.paper import references

    make = references.circle if path == "circle" else references.lawnmower
    return make(dict(nominal), h, duration)


@lru_cache(maxsize=256)
def _described_reference(robot_file: str, path: str, h: float, duration: float) -> Any:
    from runtime import robot_paths
    from runtime.robot_scale import robot_scale

    tgt = target(robot_file)
    code = _described_code(robot_file)
    scale = robot_scale(code, tgt.nominal)
    make = robot_paths.circle if path == "circle" else robot_paths.lawnmower
    return make(code, scale, tgt.nominal, h, duration).ref


@cache
def _described_code(robot_file: str) -> Any:
    from runtime.robot_source import resolve

    return resolve(Path(robot_file)).code


@cache
def _described_library(robot_file: str) -> Any:
    from runtime import cbuild

    code = _described_code(robot_file)
    return cbuild.build(c_dir=code.c_dir, prefix=code.prefix)


@lru_cache(maxsize=64)
def _roc_bounds(nominal: tuple[tuple[str, float], ...], uncertainty: float,
                formulation: str) -> tuple[float, float]:
    from runtime.paper.nominal_check import roc_bounds

    return roc_bounds(dict(nominal), uncertainty, formulation)


@lru_cache(maxsize=64)
def _model_bounds(robot_file: str, uncertainty: float, formulation: str) -> Any:
    from runtime.paper.paths import DRISHTI_RADIUS, ROC_MAX_RATE
    from runtime.robot_model_checks import model_bounds
    from runtime.robot_scale import robot_scale

    code, tgt = _described_code(robot_file), target(robot_file)
    scale = robot_scale(code, tgt.nominal)
    max_rate = ROC_MAX_RATE * scale.size * DRISHTI_RADIUS / scale.wheel_radius
    return model_bounds(code, tgt.nominal, uncertainty, formulation, max_rate)


def warm_up(robot_file: str | None) -> str:
    """Load the robot and its compiled library in this process; the project's location (a
    worker's answer proves it imports the project and can build the C)."""
    import runtime

    tgt = target(robot_file)
    if tgt.kind == "paper":
        from runtime.paper.simulate import sim_library

        sim_library(False)
    else:
        assert robot_file is not None
        _described_library(robot_file)
    return str(Path(runtime.__file__).parent)


# ----------------------------------------------------------------------------- metrics

METRICS = ("rms_error", "max_error", "final_error", "rms_torque", "max_torque", "chatter",
           "median_gain", "failed_at")


def metrics(t: Array, position_error: Array, tau: Array, gain: Array) -> dict[str, float]:
    """Tracking, torque and chattering numbers of one run's samples."""
    nan = float("nan")
    if not len(t):
        return {k: nan for k in METRICS}
    late = tau[len(tau) // 2:]
    d = np.diff(late, axis=0)
    rms_late = float(np.sqrt(np.mean(late**2)))
    chatter = float(np.sqrt(np.mean(d**2))) / max(rms_late, 1e-9) if len(d) >= 2 else nan
    settled = t >= min(5.0, 0.5 * float(t[-1]))
    return {
        "rms_error": float(np.sqrt(np.mean(position_error**2))),
        "max_error": float(np.max(position_error)),
        "final_error": float(position_error[-1]),
        "rms_torque": float(np.sqrt(np.mean(tau**2))),
        "max_torque": float(np.max(np.abs(tau))),
        "chatter": chatter,
        "median_gain": float(np.median(gain[settled])),
        "failed_at": nan,
    }


def _outcome(rec: dict[str, Any], failed_at: float | None, failure: str,
             campaign: Campaign) -> None:
    """Status and simulated stability of a run that ran."""
    diverged = failed_at is not None or not (rec["max_error"] <= campaign.diverged_error)
    if failed_at is not None:
        rec["failed_at"] = float(failed_at)
        rec["error"] = failure
    elif diverged:
        rec["error"] = (f"position error {rec['max_error']:.3g} m > diverged_error "
                        f"{campaign.diverged_error:g} m")
    rec["status"] = "diverged" if diverged else "ok"
    rec["stable"] = (not diverged) and bool(rec["chatter"] < campaign.chatter_limit)


# ----------------------------------------------------------------------------- one run


def _run_paper(rec: dict[str, Any], c: Campaign, tgt: Target, exp: Experiment,
               plant: dict[str, float]) -> None:
    from runtime.generated_modules import load_robot_code
    from runtime.paper.simulate import run, sim_library
    from runtime.robot_simulation import controller_config

    name, form = rec["controller"], c.formulation
    lib = sim_library(False)
    nominal = tgt.nominal
    items = tuple(sorted(nominal.items()))
    bounds = _roc_bounds(items, exp.controller.uncertainty, form) if name == "roc" else None
    cfg = controller_config(lib, load_robot_code(""), name, form, nominal, exp, bounds)
    state = lib.ffi.new(f"wmr_{name}_state_t *")
    status = int(getattr(lib.lib, f"wmr_{name}_init")(state, cfg))
    if status != 0:
        rec.update(status="init_refused", status_code=status,
                   error=f"wmr_{name}_init returned {status}")
        return
    ref = _paper_reference(c.path, items, exp.controller.h, c.duration)
    r = run(name, form, ref, nominal, exp, check=False, plant=plant)
    rec.update(metrics(r.t, r.position_error, r.tau, r.gain))
    rec["saturated_steps"] = int(r.saturated)
    _outcome(rec, r.failed_at, "a controller step failed or the plant became non-finite", c)


def _run_described(rec: dict[str, Any], c: Campaign, tgt: Target, exp: Experiment,
                   plant: dict[str, float]) -> None:
    from runtime.robot_simulation import run

    assert tgt.robot_file is not None
    name, form = rec["controller"], c.formulation
    lib = _described_library(tgt.robot_file)
    code = _described_code(tgt.robot_file)
    ref = _described_reference(tgt.robot_file, c.path, exp.controller.h, c.duration)
    bounds = _model_bounds(tgt.robot_file, exp.controller.uncertainty, form)
    r = run(lib, code, name, form, c.path, ref, tgt.nominal, exp, bounds, plant_base=plant)
    if r.status.startswith("init refused"):
        match = re.search(r"\((-?\d+)\)$", r.status)
        rec.update(status="init_refused", status_code=int(match.group(1)) if match else -1,
                   error=r.status)
        return
    rec.update(metrics(r.t, r.position_error, r.tau, r.gain))
    rec["saturated_steps"] = int(r.saturated)
    _outcome(rec, r.failed_at, r.status, c)


def empty_record(c: Campaign, index: int) -> dict[str, Any]:
    rec: dict[str, Any] = {
        "index": index, "seed": run_seed(c.seed, index), "controller": controller_of(c, index),
        "formulation": c.formulation, "path": c.path, "status": "error", "status_code": 0,
        "error": "", "saturated_steps": 0, "stable": False,
    }  # fmt: skip
    rec.update({k: float("nan") for k in METRICS})
    return rec


def run_one(c: Campaign, index: int, tgt: Target, base: dict[str, Value]) -> dict[str, Any]:
    """Run ``index`` of campaign ``c`` on ``tgt``: its record (never raises)."""
    rec = empty_record(c, index)
    try:
        values = draw(c, index, base)
        rec.update({f"p.{k}": v for k, v in values.items()})
        exp = with_values(c.experiment, values)
        exp = replace(exp, paths=replace(exp.paths, circle_duration=c.duration,
                                         lawnmower_duration=c.duration))
        check_sensing(exp, "drawn setting")
        check_sample_count(exp, "drawn setting")
        plant = {**tgt.plant, **{k.removeprefix("robot."): float(v) for k, v in values.items()
                                 if k.startswith("robot.")}}
        if tgt.kind == "paper":
            _run_paper(rec, c, tgt, exp, plant)
        else:
            _run_described(rec, c, tgt, exp, plant)
    except Exception as exc:  # recorded, not dropped: the campaign goes on
        rec.update(status="error", error=f"{type(exc).__name__}: {exc}", stable=False)
    for k in METRICS:
        rec[k] = float(rec[k]) if isinstance(rec[k], int | float) else math.nan
    return rec


def run_chunk(payload: str, indices: list[int]) -> list[dict[str, Any]]:
    """The Dask task: the runs ``indices`` of the campaign ``payload`` (its JSON)."""
    c = _campaign(payload)
    tgt = target(c.robot)
    base = base_values(c, tgt.plant)
    return [run_one(c, i, tgt, base) for i in indices]
