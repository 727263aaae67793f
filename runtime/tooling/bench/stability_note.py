"""The any-robot stability note (issue 29): per robot, per sensing model, what
``wmr stability`` predicts and what simulation finds → ``docs/STABILITY.md``.

For each robot (the shipped ladder Drishti, trailer, trailer2, trailer3; the small robot of
tests/robots; the swivel-caster robot of tests/robots, generated into a temporary folder)
and each sensing model, with the paper's experiment scaled to the robot:

* every controller and formulation: the largest stable k/ε (``max_stable_gain``), the
  verdict at the setting (k̂ measured in closed loop), TDROC's ε_min, the largest tolerated
  delay, the reason of a refusal; the wall time of the whole ``analyse_all``;
* TDROC in its first formulation: the predicted boundary against the simulated one (k̂ held,
  bisection, :mod:`runtime.stability.verification`);
* TDC in the minimal formulation, sample-instant rates: the predicted largest delay against
  the simulated one (TDROC with k̂ held at 0 is TDC; bisection on the delay of the loop);
* the saturation, wind-up and grip verdict of every controller (sample-instant rates),
  predicted and simulated (:mod:`runtime.stability.saturation`: ``ok``, ``saturates``,
  ``winds up`` or ``slips``, the grip margin min(μ N r − torque) at the experiment's floor
  and the μ the simulated runs needed on each path).

Run: ``python -m runtime.tooling.bench.stability_note [--out FILE] [--robots a,b]``
(about ten minutes on one core; the tests check the same things on cheaper cases).
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from dataclasses import replace
from pathlib import Path

from runtime.bindings.generated import RobotCode
from runtime.experiment.settings import VELOCITY_MODELS, Experiment
from runtime.setting.robot import robot_setting
from runtime.stability import verification
from runtime.stability.analysis import analyse_all
from runtime.stability.sampled_loop import max_delay, pencil, setting
from runtime.stability.saturation import saturation_verdict

ROOT = Path(__file__).resolve().parents[3]
ROBOTS = {
    "drishti": (None, None),
    "trailer": ("trailer", None),
    "trailer2": ("trailer2", None),
    "trailer3": ("trailer3", None),
    "small_robot": (str(ROOT / "tests" / "robots" / "small_robot.toml"), None),
    "caster_robot": (str(ROOT / "tests" / "robots" / "caster_robot.toml"), "generate"),
}


def _fmt(x: float | None, unit: str = "", scale: float = 1.0) -> str:
    if x is None:
        return ""
    if math.isnan(x):
        return "—"
    if math.isinf(x):
        return "∞"
    return f"{x * scale:.4g}{unit}"


def simulated_delay(code: RobotCode, nominal: dict[str, float], exp: Experiment,
                    guess: float, rel_tol: float = 0.03) -> tuple[float, float]:
    """(largest delay seen stable, smallest seen unstable) of TDC in the minimal formulation,
    simulated (bisection from a bracket around ``guess``)."""
    def unstable(d: float) -> bool:
        e = replace(exp, controller=replace(exp.controller, delay_time=d))
        return verification.simulated_unstable(code, 0.0, "minimal", nominal, e)

    lo, hi = 0.5 * guess, min(1.8 * guess, 3.9 * exp.controller.h)
    while unstable(lo) and lo > 1e-4:
        lo, hi = 0.5 * lo, lo
    while not unstable(hi):
        lo, hi = hi, 1.5 * hi
        if hi > 3.9 * exp.controller.h:
            return lo, math.inf
    while hi - lo > rel_tol * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if unstable(mid) else (mid, hi)
    return lo, hi


def robot_section(name: str, robot: str | None, generated: Path | None) -> list[str]:
    lines = [f"## {name}", ""]
    head = ("| sensing | controller | form | max stable k/ε | g at setting | stable | "
            "ε > | max delay | reason |")
    rows = [head, "|---|---|---|---:|---:|---|---:|---:|---|"]
    sat: list[str] = []
    checks = ["", "| sensing | TDROC k̂/ε predicted | simulated | difference | TDC delay "
              "predicted | simulated |", "|---|---:|---:|---:|---:|---:|"]
    for velocity in VELOCITY_MODELS:
        base = Experiment()
        base = replace(base, sensing=replace(base.sensing, velocity=velocity))
        s = robot_setting(robot, generated, base)
        code, nominal, exp = s.robot.code, s.robot.nominal, s.experiment
        start = time.perf_counter()
        result = analyse_all(code, nominal, exp, delays=True)
        took = time.perf_counter() - start
        for r in result:
            rows.append(f"| {velocity} | {r.controller} | {r.formulation} "
                        f"| {_fmt(r.max_stable_gain)} | {_fmt(r.gain_at_setting)} "
                        f"| {'yes' if r.stable else '**no**'} | {_fmt(r.eps_min)} "
                        f"| {_fmt(r.max_delay, ' ms', 1e3)} | {r.reason} |")
        # TDROC in the first formulation with a stable loop (the small robot's paper one is
        # unstable before any switching gain: nothing to bisect)
        gains = {f: pencil(setting(code, "tdroc", f, nominal, exp)).max_stable_gain()
                 for f in code.controller("tdroc").formulations}
        form = next((f for f, g in gains.items() if 0 < g < math.inf), "minimal")
        predicted = gains[form]
        sim = verification.simulated_boundary(code, form, nominal, exp, predicted)
        diff = abs(sim.estimate - predicted) / sim.estimate if sim.estimate > 0 else math.nan
        delay_cell = ["", ""]
        if velocity == "sample-instant":
            d_pred = max_delay(setting(code, "tdc", "minimal", nominal, exp), 0.0)
            lo, hi = simulated_delay(code, nominal, exp, d_pred)
            delay_cell = [_fmt(d_pred, " ms", 1e3),
                          f"{_fmt(lo, '', 1e3)}–{_fmt(hi, ' ms', 1e3)}"]
        checks.append(f"| {velocity} | {predicted:.4g} ({form}) | {sim.estimate:.4g} "
                      f"| {100 * diff:.1f} % | {delay_cell[0]} | {delay_cell[1]} |")
        lines.append(f"- {velocity}: `analyse_all` with the largest delays took {took:.1f} s "
                     f"({len(result)} rows, {code.nq} coordinates).")
        if velocity == "sample-instant":
            sat = ["", f"| controller | form | saturation and grip at μ = {exp.plant.friction:g} "
                   "(predicted; simulated) |", "|---|---|---|"]
            for form, info in code.runs():
                v = saturation_verdict(code, info.name, form, nominal, exp, simulate=True)
                sat.append(f"| {info.name} | {form} | {v.verdict}: {v.reason} |")
    return [*lines, "", *rows, *checks, *sat, ""]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m runtime.tooling.bench.stability_note")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "STABILITY.md")
    parser.add_argument("--robots", default=",".join(ROBOTS))
    args = parser.parse_args(argv)
    out = ["# Sampled-data stability on every robot: predicted and simulated", "",
           "Written by `python -m runtime.tooling.bench.stability_note` (issue 29). The "
           "paper's experiment scaled to each robot (h = 0.1 s, K1 = K2 = 4 I, ε = 0.1), "
           "nominal robot, the experiment's circle. Max delay: the largest constant "
           "delay from a sample to its torque at the wheels with the loop stable at the "
           "setting's gain (∞: beyond 2 h). TDROC k̂/ε simulated: k̂ held, bisection "
           "between diverging and bounded runs (`runtime/stability/verification.py`); "
           "TDC delay simulated: bisection on the delay the closed loop applies. "
           "Saturation and grip: `wmr stability`'s verdict (`ok`, `saturates`, `winds up`, "
           "`slips`) against min(τ_max, μ N r) per driven wheel, μ the experiment's "
           "`[plant] friction` (1 here), N from the one load "
           "model (`modeling.contact_loads`, the robot file's supports); grip margin: the "
           "smallest μ N r − torque along the tracked paths; μ needed: the simulated runs' "
           "largest |F|/N on each path. Where grip ends (h = 0.25 s TDROC, μ = 0.1 floors) "
           "see tests/runtime/test_grip_verdict.py and docs/MUJOCO.md.", ""]
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.robots.split(","):
            robot, gen = ROBOTS[name]
            folder = None
            if gen == "generate":
                from runtime.cli import main as wmr

                folder = Path(tmp) / name
                assert wmr(["model", "--robot", str(robot), "--out", str(folder)]) == 0
            out += robot_section(name, robot, folder)
            print(f"{name} done", flush=True)
    # The jitter section is written by runtime.tooling.bench.jitter_note: kept as it is.
    old = args.out.read_text(encoding="utf-8") if args.out.exists() else ""
    begin = old.find("## Jitter")
    kept = ["", old[begin:].rstrip("\n"), ""] if begin >= 0 else []
    args.out.write_text("\n".join(out + kept), encoding="utf-8")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
