"""The hand-written comparison, for the robot whose equations are typed by hand in
``runtime/tooling/witness`` (the paper's robot, Drishti): derivation self-checks, the model
functions and the four controllers of every implementation (generated NumPy, C double and
float32, CasADi) against the hand-written equations.
"""

from __future__ import annotations

import time
from collections.abc import Mapping

import numpy as np

from runtime.tooling.crosscheck.controller_checks import check_controllers
from runtime.tooling.crosscheck.inputs import Sequence_, closed_loop, model_samples, random_sequence
from runtime.tooling.crosscheck.model_checks import check_models, self_checks
from runtime.tooling.crosscheck.report import Report
from runtime.tooling.crosscheck.targets import Target
from runtime.tooling.witness import controllers as hc
from runtime.tooling.witness import model as hw

#: The generated robot the hand-written equations describe (its robot.py NAME).
HANDWRITTEN_ROBOT = "drishti"


def applies_to(target: Target) -> bool:
    """Whether ``target`` is the robot of the hand-written equations (name and parameters)."""
    keys = tuple(target.code.controllers.PARAM_KEYS)
    return target.name == HANDWRITTEN_ROBOT and keys == hw.PARAM_KEYS


def handwritten_crosscheck(
    target: Target,
    seed: int = 20170316,
    quick: bool = False,
    perturb: Mapping[str, Mapping[str, float]] | None = None,
) -> Report:
    """Every implementation of ``target`` against the hand-written equations; ``quick``:
    fewer samples and shorter sequences."""
    if not applies_to(target):
        raise ValueError(f"{target.label}: the hand-written equations describe "
                         f"{HANDWRITTEN_ROBOT!r} only")
    pert: dict[str, dict[str, float]] = {k: dict(v) for k, v in (perturb or {}).items()}
    t0 = time.perf_counter()
    rng = np.random.default_rng(seed)
    n_samples = 40 if quick else 200
    loop_seconds, rand_steps = (3.0, 15) if quick else (6.0, 40)
    samples = model_samples(rng, n_samples)
    checks = self_checks(samples)
    model_rows = check_models(target, samples, pert)
    sequences: list[tuple[hc.Kind, Sequence_]] = []
    for kind in hc.KINDS:
        for form in hc.FORMULATIONS:
            sequences.append((kind, closed_loop(target, kind, form, loop_seconds)))
            for near in (True, False):
                sequences.append((kind, random_sequence(rng, kind, form, near, rand_steps)))
    ctrl_rows, cover = check_controllers(target, sequences, pert)
    return Report(
        checks, model_rows, ctrl_rows, cover, n_samples, len(sequences),
        sum(len(s.q) for _, s in sequences), time.perf_counter() - t0, pert,
    )  # fmt: skip
