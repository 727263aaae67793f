"""The numbers of issue 48's note: ROC's α over physical boxes, the two plants on the same
drawn robots, the cost of the map.

    python -m runtime.tooling.bench.physical_uncertainty [--runs 12] [--duration 30]
                                                         [--skip-campaign]

* ROC's α (sound bound, :mod:`runtime.bindings.physical_bounds`) over ±10/20/30 % of every
  body's mass and yaw inertia for trailer, trailer2, trailer3, next to the largest α of a
  robot evaluated in the box (the box's corners and the sub-boxes' centres) and the lumped
  box's α at the same percentage (``controller.uncertainty``, every base parameter
  independently, nominal or above it);
* a campaign on the trailer run on both plants with the same draws (±20 % masses and yaw
  inertias, centres of mass ±2 cm, TDC/TDROC/ROC in turn, circle): per run the RMS
  position error on the generated plant and on MuJoCo;
* the map's cost: operations after CSE (from the generated code) and ns per call of the
  generated C (a loop of 10⁶ calls compiled with -O2) and of the generated NumPy.

Prints Markdown. Not part of ``make bench`` (the campaign takes minutes).
"""

from __future__ import annotations

import argparse
import re
import subprocess
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from runtime.bindings import cbuild
from runtime.bindings.generated import load_robot_code
from runtime.bindings.physical_bounds import box_of, physical_model, physical_roc_bounds
from runtime.bindings.uncertainty import roc_bounds
from runtime.campaign.runner import run_one, target
from runtime.campaign.sampling import base_values
from runtime.campaign.spec import parse_campaign
from runtime.commands.campaign import with_plant
from runtime.experiment.physical import parse_physical

ROBOTS = ("trailer", "trailer2", "trailer3")
SPREADS = (0.1, 0.2, 0.3)
MAX_RATE = 8.0  # the experiment's default roc_max_rate
CAMPAIGN = """
seed = 48
runs = {runs}
controllers = ["tdc", "tdroc", "roc"]
duration = {duration}
[physical_uncertainty]
mass = 0.2
yaw_inertia = 0.2
com = 0.02
"""
C_BENCH = """
#include <stdio.h>
#include <time.h>
#include "{prefix}_plant.h"
int main(void) {{
    {prefix}_real_t phys[{n}] = {{ {values} }};
    {prefix}_real_t base[{m}];
    volatile {prefix}_real_t sink = 0;
    struct timespec a, b;
    const long calls = 1000000;
    clock_gettime(CLOCK_MONOTONIC, &a);
    for (long i = 0; i < calls; ++i) {{
        phys[0] += 1e-9;
        {prefix}_plant_params_from_physical(phys, base);
        sink += base[0];
    }}
    clock_gettime(CLOCK_MONOTONIC, &b);
    printf("%.3f\\n", ((b.tv_sec - a.tv_sec) * 1e9 + (b.tv_nsec - a.tv_nsec)) / calls);
    return sink == 0.0;
}}
"""


def alpha_table() -> list[str]:
    lines = ["| robot | box (mass, yaw inertia) | α bound (physical) | largest α found "
             "in the box | lumped box α | φ bound | seconds |",
             "|---|---|---:|---:|---:|---:|---:|"]
    for name in ROBOTS:
        code = load_robot_code(name)
        for s in SPREADS:
            t = time.process_time()
            box = box_of(code, parse_physical({"mass": s, "yaw_inertia": s}, "note"))
            b = physical_roc_bounds(code, code.params, box, "minimal", MAX_RATE)
            took = time.process_time() - t
            lumped = roc_bounds(code, code.params, s, "minimal", MAX_RATE)[0]
            lines.append(f"| {name} | ±{s:.0%} | {b.alpha:.3f} | {b.alpha_seen:.3f} | "
                         f"{lumped:.3f} | {b.phi:.3g} | {took:.1f} |")
    return lines


def campaign_agreement(runs: int, duration: float) -> list[str]:
    tgt = target("trailer")
    code = tgt.setup.code
    c = parse_campaign(CAMPAIGN.format(runs=runs, duration=duration), "note", tgt.plant,
                       available=lambda f: code.controller_names,
                       physical_box=lambda d: box_of(code, d))
    records = {}
    for plant in ("generated", "mujoco"):
        cp = replace(with_plant(c, plant), robot="trailer")
        base = base_values(cp, tgt.plant, tgt.physical)
        records[plant] = [run_one(cp, i, tgt, base) for i in range(runs)]
    # the robot file's robot, no draws (ROC's bounds still over the declared box): the
    # plants' own difference, for comparison
    nominal = replace(c, vary=())
    base_rms = {}
    for plant in ("generated", "mujoco"):
        cp = replace(with_plant(nominal, plant), robot="trailer")
        for i in range(3):
            r = run_one(cp, i, tgt, base_values(cp, tgt.plant, tgt.physical))
            base_rms[(plant, r["controller"])] = float(r["rms_error"])
    lines = ["| run | controller | mass_tractor | mass_cart | RMS error model (mm) | "
             "RMS error MuJoCo (mm) | MuJoCo − model (mm) |", "|---:|---|---:|---:|---:|---:|---:|"]
    for ctrl in ("tdc", "tdroc", "roc"):
        ea, eb = base_rms[("generated", ctrl)], base_rms[("mujoco", ctrl)]
        lines.append(f"| nominal | {ctrl} | — | — | {1000 * ea:.2f} | {1000 * eb:.2f} | "
                     f"{1000 * (eb - ea):+.2f} |")
    excess = []
    for a, b in zip(records["generated"], records["mujoco"], strict=True):
        assert all(a[k] == b[k] for k in a if k.startswith("p.physical."))
        ea, eb = float(a["rms_error"]), float(b["rms_error"])
        ctrl = str(a["controller"])
        excess.append((eb - ea) - (base_rms[("mujoco", ctrl)] - base_rms[("generated", ctrl)]))
        lines.append(f"| {a['index']} | {ctrl} | {a['p.physical.mass_tractor']:.2f} "
                     f"| {a['p.physical.mass_cart']:.2f} | {1000 * ea:.2f} ({a['status']}) | "
                     f"{1000 * eb:.2f} ({b['status']}) | {1000 * (eb - ea):+.2f} |")
    d = 1000 * np.abs(np.array(excess))
    lines += ["", f"Per run, the MuJoCo − model difference of the RMS position error on the "
              f"same drawn robot departs from the nominal robot's difference (same controller) "
              f"by {np.nanmedian(d):.2f} mm median, {np.nanmax(d):.2f} mm at most, over "
              f"{runs} runs of {duration:g} s."]
    return lines


def map_cost() -> list[str]:
    lines = ["| robot | inputs | outputs | operations after CSE | C ns/call | NumPy µs/call |",
             "|---|---:|---:|---|---:|---:|"]
    for name in ROBOTS:
        code = load_robot_code(name)
        pm = physical_model(code)
        doc = code.plant.plant_params_from_physical.__doc__ or ""
        ops = re.search(r"operations after CSE: ([^\n]+)", doc)
        x = np.array(pm.nominal)
        t = time.perf_counter()
        for _ in range(10000):
            code.plant.plant_params_from_physical(x)
        numpy_us = (time.perf_counter() - t) / 10000 * 1e6
        with tempfile.TemporaryDirectory() as tmp:
            src = Path(tmp) / "bench.c"
            src.write_text(C_BENCH.format(prefix=code.prefix, n=len(x), m=len(pm.outputs),
                                          values=", ".join(repr(float(v)) for v in x)))
            exe = Path(tmp) / "bench"
            cbuild.run_compiler([cbuild.gcc_command(
                [src, code.c_dir / f"{code.prefix}_plant.c"], exe, kind="executable",
                flags=["-O2", "-std=c99", "-D_POSIX_C_SOURCE=199309L"],
                include_dirs=[code.c_dir], libs=["-lm"])])
            c_ns = float(subprocess.run([str(exe)], capture_output=True, text=True,
                                        check=False).stdout)
        lines.append(f"| {name} | {len(x)} | {len(pm.outputs)} | "
                     f"{ops.group(1) if ops else '?'} | {c_ns:.1f} | {numpy_us:.1f} |")
    return lines


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m runtime.tooling.bench.physical_uncertainty")
    p.add_argument("--runs", type=int, default=12)
    p.add_argument("--duration", type=float, default=30.0)
    p.add_argument("--skip-campaign", action="store_true")
    args = p.parse_args(argv)
    out = ["## ROC's α over physical boxes", "", *alpha_table(), "",
           "## The map's cost", "", *map_cost()]
    if not args.skip_campaign:
        out += ["", "## Both plants on the same drawn robots (trailer)", "",
                *campaign_agreement(args.runs, args.duration)]
    print("\n".join(out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
