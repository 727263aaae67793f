"""One campaign run through the generated C: what a Dask worker executes.

A run draws its parameters (:mod:`runtime.campaign.sampling`), applies them to the base
experiment (``section.field``; the experiment is already scaled to the robot, as every
command scales it) and to the simulated robot (``robot.KEY``; the controllers keep the
nominal model), and simulates its controller on the campaign's path with the one closed
loop, :func:`runtime.sim.loop.run`, without the configuration checks (a campaign records
what happens, the prediction is compared afterwards). Any robot: Drishti, a
``[lumped]``/``[physical]`` or bodies-and-wheels robot file, a generated folder
(:func:`runtime.bindings.robots.resolve`).

The compiled library, the references and ROC's bounds are cached per worker process
(module level): a worker compiles or loads the C once, not per run.

Outcome of a run (``status``): ``ok``; ``init_refused`` (the C init's status code in
``status_code``); ``diverged`` (a step failed, the plant became non-finite, the position
error exceeded ``diverged_error``, or the run left its path: final or RMS error beyond
:data:`runtime.sim.outcome.OFF_PATH_FRACTION` of the path's scale); ``error`` (any
exception, its text in ``error``). ``stable`` is the simulated verdict the stability map
compares with the prediction: ``ok`` and no sampled-data limit cycle, i.e. ``chatter`` =
RMS(Δτ)/RMS(τ) over the second half of the run below ``chatter_limit`` (an oscillating
switching term alternates τ sample to sample: chatter ≈ 2; a stable loop's torque varies
slowly: chatter ≪ 1).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, replace
from functools import cache, lru_cache
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from runtime.bindings.robots import RobotSetup, resolve
from runtime.campaign.physical_draws import drawn, physical_params
from runtime.campaign.sampling import base_values, controller_of, draw, run_seed
from runtime.campaign.spec import Campaign, Value, from_payload, with_values
from runtime.experiment.settings import (
    ControllerSettings,
    Experiment,
    PathSettings,
    check_sample_count,
    check_sensing,
)

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Target:
    """The robot a campaign runs: its nominal model and simulated robot before drawing."""

    setup: RobotSetup
    inertial: tuple[str, ...]
    track: float

    @property
    def name(self) -> str:
        return self.setup.name

    @property
    def nominal(self) -> dict[str, float]:
        return self.setup.nominal

    @property
    def plant(self) -> dict[str, float]:
        """The simulated robot's parameters (``robot.KEY`` may be drawn)."""
        return self.setup.plant

    @property
    def sha256(self) -> str | None:
        return self.setup.sha256

    @property
    def physical(self) -> dict[str, float]:
        """The robot file's physical quantities (``physical.KEY`` may be drawn; none for a
        ``[lumped]`` robot)."""
        phys = getattr(self.setup.code.robot, "PHYSICAL", None) or {}
        return {k: float(v[0]) for k, v in phys.items()}


@cache
def target(robot: str | None, generated: str | None = None) -> Target:
    """The robot ``--robot`` names (None: Drishti), its code under ``generated`` (cached
    per process)."""
    from runtime.bindings.uncertainty import inertial_keys
    from runtime.setting.scale import robot_scale

    setup = resolve(robot, Path(generated) if generated is not None else None)
    scale = robot_scale(setup.code, setup.nominal)
    return Target(setup, inertial_keys(setup.code, setup.nominal), scale.track)


@lru_cache(maxsize=8)
def _campaign(text: str) -> Campaign:
    return from_payload(json.loads(text))


def reference(c: Campaign, tgt: Target, exp: Experiment) -> Any:
    """The campaign's path for the experiment (cached on what it depends on: h, [paths])."""
    return _reference(c.robot, c.generated, c.path, tuple(sorted(tgt.nominal.items())),
                      exp.controller.h, exp.paths)


@lru_cache(maxsize=256)
def _reference(robot: str | None, generated: str | None, path: str,
               nominal: tuple[tuple[str, float], ...], h: float, settings: PathSettings) -> Any:
    from runtime.sim import paths

    exp = replace(Experiment(), controller=replace(ControllerSettings(), h=h), paths=settings)
    return paths.reference(target(robot, generated).setup.code, dict(nominal), exp, path)


def warm_up(robot: str | None, generated: str | None = None) -> str:
    """Load the robot and its compiled library in this process; the project's location (a
    worker's answer proves it imports the project and can build the C)."""
    import runtime
    from runtime.sim.plant import library_for

    library_for(target(robot, generated).setup.code)
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


def _outcome(rec: dict[str, Any], result: Any, failed_at: float | None,
             campaign: Campaign) -> None:
    """Status and simulated stability of a run that ran (``result``: its
    :class:`runtime.sim.outcome.Outcome`)."""
    too_far = not (rec["max_error"] <= campaign.diverged_error)
    diverged = not result.ok or too_far
    if failed_at is not None:
        rec["failed_at"] = float(failed_at)
    if not result.ok:
        rec["error"] = result.describe()
    elif too_far:
        rec["error"] = (f"position error {rec['max_error']:.3g} m > diverged_error "
                        f"{campaign.diverged_error:g} m")
    rec["status"] = "diverged" if diverged else "ok"
    rec["stable"] = (not diverged) and bool(rec["chatter"] < campaign.chatter_limit)


# ----------------------------------------------------------------------------- one run


def _run(rec: dict[str, Any], c: Campaign, tgt: Target, exp: Experiment,
         plant: dict[str, float], physical: dict[str, float] | None = None) -> None:
    """One run of controller ``rec["controller"]`` on the campaign's path; ``physical``:
    the run's drawn physical quantities (the same robot on either plant:
    :mod:`runtime.campaign.physical_draws`)."""
    from runtime.campaign.physical_draws import physical_layout
    from runtime.mujoco.plant import MujocoPlant
    from runtime.plants import plant_for
    from runtime.sim import loop
    from runtime.sim.outcome import outcome

    setup = tgt.setup
    ref = reference(c, tgt, exp)
    if physical and exp.plant.model == "mujoco":
        engine: Any = MujocoPlant(setup.code, exp, physical_layout(setup.code, physical))
    else:
        engine = plant_for(setup.code, exp, tgt.nominal, plant)
    r = loop.run(setup.code, rec["controller"], c.formulation, ref, tgt.nominal, exp,
                 plant_params=plant, plant=engine)
    if r.init_status != 0:
        rec.update(status="init_refused", status_code=r.init_status, error=r.stop_reason)
        return
    rec.update(metrics(r.t, r.position_error, r.tau, r.gain))
    rec["saturated_steps"] = int(r.saturated)
    _outcome(rec, outcome(r, ref.scale), r.failed_at, c)


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
        physical = drawn(values)
        if physical:
            plant = physical_params(tgt.setup.code, physical)
        _run(rec, c, tgt, exp, plant, physical)
    except Exception as exc:  # recorded, not dropped: the campaign goes on
        rec.update(status="error", error=f"{type(exc).__name__}: {exc}", stable=False)
    for k in METRICS:
        rec[k] = float(rec[k]) if isinstance(rec[k], int | float) else math.nan
    return rec


def run_chunk(payload: str, indices: list[int]) -> list[dict[str, Any]]:
    """The Dask task: the runs ``indices`` of the campaign ``payload`` (its JSON)."""
    c = _campaign(payload)
    tgt = target(c.robot, c.generated)
    base = base_values(c, tgt.plant, tgt.physical)
    return [run_one(c, i, tgt, base) for i in indices]
