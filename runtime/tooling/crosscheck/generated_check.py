"""The comparison for any generated robot, the generated NumPy being the reference: every
model, law and plant function in C (double, float32) and CasADi
(:mod:`.generated_functions`), and the four C controllers (double, float32) against the
Python controller classes along closed-loop and random sequences
(:mod:`.generated_controllers`).
"""

from __future__ import annotations

import time
from collections.abc import Mapping

import numpy as np

from runtime.tooling.crosscheck.generated_controllers import check_controllers, sequences
from runtime.tooling.crosscheck.generated_functions import check_functions, random_samples
from runtime.tooling.crosscheck.report import GeneratedReport
from runtime.tooling.crosscheck.targets import Target


def generated_crosscheck(
    target: Target,
    seed: int = 20170316,
    quick: bool = False,
    perturb: Mapping[str, Mapping[str, float]] | None = None,
) -> GeneratedReport:
    """C double, C float32 and CasADi against the target's generated NumPy; ``quick``:
    100 random states (else 200) and shorter sequences."""
    perturb = perturb or {}
    t0 = time.perf_counter()
    rng = np.random.default_rng(seed)
    n_samples = 100 if quick else 200
    function_rows = check_functions(target, random_samples(target, rng, n_samples), perturb)
    runs = sequences(target, rng, quick)
    ctrl_rows, cover, n_steps = check_controllers(target, runs, perturb)
    return GeneratedReport(function_rows, ctrl_rows, cover, n_samples, len(runs), n_steps,
                           time.perf_counter() - t0)
