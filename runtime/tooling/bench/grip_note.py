"""The grip measurements of issue 45, for the lead's note: the one load model against
``--plant mujoco`` per contact, and the friction each reproduction run needs, predicted
against measured.

For every reproduction run (both sensing models of ``runtime.plant_comparison``, both
paths, every controller and formulation; Drishti, the paper's experiment):

* **μ needed, predicted**: the slip monitor (``runtime.sim.slip_monitor``: the constraint
  multipliers' |F| over the load model's N with load transfer) on the model plant, its
  largest value over the run;
* **μ needed, measured**: MuJoCo at μ = 1 (no slip), the driven wheels' contact forces
  (``mj_contactForce``: tangential magnitude over normal), largest over the run after the
  first 0.5 s (the start's contact transient);
* **loads on the circle** (t ≥ 5 s, mean): each driven wheel's N from the load model
  along the engine's run (the monitor on the MuJoCo plant) against MuJoCo's normal force;
  the supports' as MuJoCo carries them.

Run: ``python -m runtime.tooling.bench.grip_note [--out FILE]`` (Markdown; about 2 minutes
on an idle core).
"""

from __future__ import annotations

import argparse
import math
from dataclasses import replace
from pathlib import Path

import mujoco
import numpy as np

from modeling.contact_loads import contact_points, static_loads
from runtime.bindings.generated import RobotCode
from runtime.commands.options import loaded_setting
from runtime.experiment.settings import Experiment, load_experiment
from runtime.plant_comparison import SENSINGS, SlipRecordingPlant, engine_loads
from runtime.plants import plant_for
from runtime.setting.layout import robot_layout
from runtime.sim import loop, paths
from runtime.sim.slip_monitor import MonitoredPlant, SlipMonitor

START = 0.5  # s: the start's contact transient, left out of the measured μ needed
STEADY = 5.0  # s: the circle's loads are averaged from here on


class ContactRecordingPlant(SlipRecordingPlant):
    """The MuJoCo plant, recording every contact's normal and tangential force (N) after
    every sample, by contact name (wheel names, supports)."""

    def __init__(self, code: RobotCode, exp: Experiment, base: dict[str, float],
                 names: list[str]) -> None:
        super().__init__(code, exp, base)
        self.names = names
        self.normal: list[list[float]] = []
        self.tangent: list[list[float]] = []

    def advance(self, tau: list[float], dt: float, nsub: int) -> bool:
        ok = super().advance(tau, dt, nsub)
        m, d = self.model, self.data
        normal = dict.fromkeys(self.names, 0.0)
        tangent = dict.fromkeys(self.names, 0.0)
        force = np.zeros(6)
        for i in range(d.ncon):
            c = d.contact[i]
            mujoco.mj_contactForce(m, d, i, force)
            name = (m.geom(c.geom[1]).name or m.geom(c.geom[0]).name).removeprefix("tyre_")
            if name in normal:
                normal[name] += float(force[0])
                tangent[name] += math.hypot(force[1], force[2])
        self.normal.append([normal[k] for k in self.names])
        self.tangent.append([tangent[k] for k in self.names])
        return ok


def note() -> list[str]:
    """The note's Markdown lines."""
    setting = loaded_setting(None, None, load_experiment(None))
    setup, code = setting.robot, setting.robot.code
    exp = setting.experiment
    robot = robot_layout(code, setup.plant)
    names = list(contact_points(robot))
    driven = [w.name for w in robot.wheels if w.driven]
    engine = replace(exp, plant=replace(exp.plant, model="mujoco", friction=1.0))
    pl = exp.plant
    stated = static_loads(robot, ((pl.fixed_payload, pl.fixed_payload_x, pl.fixed_payload_y),))
    measured = engine_loads(code, engine, setup.plant)
    out = ["# Grip: loads and friction needed, load model against MuJoCo", "",
           "Written by `python -m runtime.tooling.bench.grip_note` (issue 45). Drishti, the "
           "paper's experiment, the fixed payload on.", "",
           "## Loads at rest (N)", "", "| contact | load model | MuJoCo |", "|---|---:|---:|"]
    out += [f"| {k} | {v:.1f} | {measured.get(k, math.nan):.1f} |" for k, v in stated.items()]
    out += ["", "## Friction needed per run; loads on the circle", "",
            f"μ needed: predicted (slip monitor on the model plant, largest over the run) "
            f"and measured (MuJoCo μ = 1, the driven wheels' tangential over normal contact "
            f"force, largest after {START:g} s). Circle loads: mean over t ≥ {STEADY:g} s, "
            "load model along the engine's run / MuJoCo (N).", "",
            "| sensing | path | formulation | controller | μ needed predicted | measured "
            "| circle loads: model / MuJoCo (N) |", "|---|---|---|---|---:|---:|---|"]
    h = exp.controller.h
    for sensing in SENSINGS:
        e = replace(exp, sensing=replace(exp.sensing, velocity=sensing))
        em = replace(engine, sensing=replace(engine.sensing, velocity=sensing))
        model_exp = replace(e, plant=replace(e.plant, model="generated"))
        for name in paths.PATHS:
            ref = paths.reference(code, setup.nominal, e, name)
            for form, info in code.runs():
                model = MonitoredPlant(plant_for(code, model_exp, setup.nominal, setup.plant),
                                       SlipMonitor(code, robot, e))
                loop.run(code, info.name, form, ref, setup.nominal, model_exp,
                         plant_params=setup.plant, plant=model)
                rec = ContactRecordingPlant(code, em, setup.plant, names)
                watched = MonitoredPlant(rec, SlipMonitor(code, robot, em))
                loop.run(code, info.name, form, ref, setup.nominal, em,
                         plant_params=setup.plant, plant=watched)
                normal, tangent = np.array(rec.normal), np.array(rec.tangent)
                cols = [names.index(w) for w in driven]
                k0 = round(START / h)
                need = float(np.max(tangent[k0:, cols] / np.maximum(normal[k0:, cols], 1e-9)))
                loads = ""
                if name == "circle":
                    k1 = round(STEADY / h)
                    model_n = np.array(watched.loads)[k1:].mean(axis=0)
                    engine_n = normal[k1:].mean(axis=0)
                    loads = ", ".join(f"{w} {model_n[i]:.1f} / {engine_n[names.index(w)]:.1f}"
                                      for i, w in enumerate(driven))
                    loads += "; " + ", ".join(f"{k} — / {engine_n[names.index(k)]:.1f}"
                                              for k in names if k not in driven)
                out.append(f"| {sensing} | {name} | {form} | {info.label} "
                           f"| {max(model.needed):.3f} | {need:.3f} | {loads} |")
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m runtime.tooling.bench.grip_note")
    parser.add_argument("--out", type=Path, default=None, help="Markdown file (default: print)")
    args = parser.parse_args(argv)
    text = "\n".join(note()) + "\n"
    if args.out is None:
        print(text, end="")
    else:
        args.out.write_text(text, encoding="utf-8")
        print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
