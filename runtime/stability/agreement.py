"""The verdicts of ``wmr stability`` against the outcome on MuJoCo (docs/MUJOCO.md).

For each sampling time h of :data:`HS` and floor μ of :data:`FRICTIONS`, each controller
and formulation of the robot gets its one-word verdict from
:func:`runtime.stability.analysis.analyse` (the linear verdict, the saturation and grip
verdict with its simulations on the model plant: ``stable``, ``slips``, ``winds up``,
``saturates``, ``unstable``) and is run on MuJoCo (``--plant mujoco``, floor μ) on both
paths. The outcome: ``slips`` if a driven wheel's slip exceeds
``runtime.plant_comparison.SLIP_THRESHOLD`` on either path, else ``unstable`` if a run is
off path or stopped (``runtime.sim.outcome``), else ``ok``. A verdict agrees with its
outcome when ``stable`` meets ``ok``, ``slips`` meets ``slips``, and any other verdict (the
loop is predicted to fail) meets an outcome that is not ``ok``. The engine integrates at
1 kHz at every h (``plant.substeps`` = h / 1 ms).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

from runtime.bindings.generated import RobotCode
from runtime.experiment.settings import Experiment
from runtime.sim import paths
from runtime.stability.analysis import analyse
from runtime.stability.sampled_loop import FORMULATIONS, refusal

HS = (0.1, 0.15, 0.2, 0.25, 0.3)  # s
FRICTIONS = (1.0, 0.3, 0.15, 0.1)
ENGINE_STEP = 0.001  # s


@dataclass(frozen=True)
class Case:
    """One controller and formulation at one h and μ: the verdict and the outcome."""

    h: float
    mu: float
    controller: str
    formulation: str
    verdict: str
    reason: str  # the verdict's (the linear one, else the saturation and grip one)
    outcome: str
    detail: str  # per path: outcome, slip onset
    friction_needed: float | None  # the verdict's simulated largest |F|/N

    @property
    def agrees(self) -> bool:
        if self.verdict == "stable":
            return self.outcome == "ok"
        if self.verdict == "slips":
            return self.outcome == "slips"
        return self.outcome != "ok"


def experiment_at(exp: Experiment, h: float, mu: float, model: str) -> Experiment:
    """``exp`` sampled at h on a floor μ, the engine at :data:`ENGINE_STEP`."""
    return replace(exp, controller=replace(exp.controller, h=h),
                   plant=replace(exp.plant, friction=mu, model=model,
                                 substeps=max(1, round(h / ENGINE_STEP))))


def cases(code: RobotCode, nominal: dict[str, float], exp: Experiment,
          engine_run: Callable[[Experiment, str, str, str], tuple[str, str]],
          hs: Sequence[float] = HS, frictions: Sequence[float] = FRICTIONS,
          progress: bool = False, only: Sequence[tuple[str, str]] | None = None
          ) -> tuple[Case, ...]:
    """Every case of the robot ``code`` whose controllers' model is ``nominal``, around the
    experiment ``exp`` (see the module docstring; ``only``: these (controller, formulation));
    ``engine_run(exp, path, formulation, controller)`` gives one MuJoCo run's (status,
    detail): status ``slips``, ``unstable`` or ``ok``."""
    out = []
    for h in hs:
        for mu in frictions:
            model_exp = experiment_at(exp, h, mu, "generated")
            engine_exp = experiment_at(exp, h, mu, "mujoco")
            for info in code.controller_infos:
                if refusal(info):
                    continue
                for form in info.formulations:
                    if form not in FORMULATIONS or (
                            only is not None and (info.name, form) not in only):
                        continue
                    row = analyse(code, info.name, form, nominal, model_exp,
                                  saturation=True)
                    reason = row.reason or row.saturation_reason
                    runs = [engine_run(engine_exp, name, form, info.name)
                            for name in paths.PATHS]
                    statuses = [s for s, _ in runs]
                    outcome = ("slips" if "slips" in statuses
                               else "unstable" if "unstable" in statuses else "ok")
                    detail = "; ".join(f"{name}: {d}" for name, (_, d)
                                       in zip(paths.PATHS, runs, strict=True))
                    needed = _needed(row.saturation_reason)
                    out.append(Case(h, mu, info.name, form, row.verdict, reason, outcome,
                                    detail, needed))
                    if progress:
                        print(f"[agreement] h = {h:g} μ = {mu:g} {info.label} {form}: "
                              f"{row.verdict} / {outcome}", flush=True)
    return tuple(out)


def _needed(reason: str) -> float | None:
    """The simulated μ needed the saturation reason states, if any."""
    marker = "μ needed "
    if marker not in reason:
        return None
    word = reason.split(marker, 1)[1].split()[0].rstrip(",;")
    try:
        return float(word)
    except ValueError:
        return None


def markdown(found: Sequence[Case], labels: dict[str, str]) -> list[str]:
    """The section of docs/MUJOCO.md: the table, the agreement rate, every disagreement."""
    if not found:
        return []
    hs = sorted({c.h for c in found})
    mus = sorted({c.mu for c in found}, reverse=True)
    runs = list(dict.fromkeys((c.controller, c.formulation) for c in found))
    by = {(c.h, c.mu, c.controller, c.formulation): c for c in found}
    agree = sum(c.agrees for c in found)
    lines = [
        "## Verdicts against the engine", "",
        "`wmr stability`'s one-word verdict (the linear verdict, then the saturation and "
        "grip verdict: the tracked path's and the simulated torque against min(τ_max, "
        "μ N r) per wheel) at each sampling time h and floor μ, against the outcome of the "
        "same controller on MuJoCo at that h and μ on both paths (sample-instant rates, "
        "1 kHz engine): ok, slips (a wheel's slip above the threshold on either path), "
        "unstable (off path or stopped). Agreement: stable with ok, slips with slips, any "
        "other verdict with an outcome that is not ok (`runtime/stability/agreement.py`). "
        "Cells: verdict / outcome; **bold** where they disagree.", "",
        f"Agreement: **{agree} of {len(found)}** ({agree / len(found):.0%}).", "",
        "| h (s) | μ | " + " | ".join(f"{labels[ctrl]} {f}" for ctrl, f in runs) + " |",
        "|---|---|" + "---|" * len(runs),
    ]
    for h in hs:
        for mu in mus:
            cells = []
            for ctrl, f in runs:
                case = by.get((h, mu, ctrl, f))
                if case is None:
                    cells.append("")
                    continue
                text = f"{case.verdict} / {case.outcome}"
                cells.append(text if case.agrees else f"**{text}**")
            lines.append(f"| {h:g} | {mu:g} | " + " | ".join(cells) + " |")
    wrong = [case for case in found if not case.agrees]
    if wrong:
        lines += ["", "Every disagreement (the verdict's reason; the engine's runs):", ""]
        for w in wrong:
            need = "" if w.friction_needed is None else f", μ needed {w.friction_needed:.3g}"
            lines.append(f"* h = {w.h:g} s, μ = {w.mu:g}, {labels[w.controller]} "
                         f"{w.formulation}: {w.verdict} against {w.outcome}{need}. "
                         f"Verdict: {w.reason or '—'}. Engine: {w.detail}.")
    return lines
