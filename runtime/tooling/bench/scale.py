"""How the toolchain's cost grows with the robot (issues 30, 51): the shipped ladder Drishti, a
tractor with one, two and three trailers and the five-cart tugger train (train5), measured
the way a user meets each cost.

* ``wmr model --robot`` (a fresh process per robot): wall time, peak memory, the time of
  each step it reports, and the bytes it writes (C, Python, CasADi; the longest Python line);
* operations per forward-dynamics call and per TDROC step (minimal formulation: the kernels
  the step calls, each once), from the operation counts of the robot's ``MODEL.md``;
* ``gcc -O2 -c`` of every generated C file: the slowest file's time and the largest peak
  memory;
* a Cortex-M4 float32 image with TDROC alone (``arm-none-eabi-gcc -Os``, newlib-nano,
  --gc-sections): the generated code's bytes and the step's worst-case stack;
* x86 ``<prefix>_tdroc_step`` (gcc -O2, double): ns a step, best of interleaved passes;
* the growth per added cart of the operations of forward dynamics, the minimal form, the
  contact forces and the TDROC step (:func:`growth`), and issue 51's budgets against the
  measurements (:func:`budgets`).

Everything reads a generated folder (the shipped ``generated/`` by default), so that the
same measurement can be run on another checkout (``--root``): the before/after of a change.
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import subprocess
import sys
import tempfile
import time
import tomllib
from dataclasses import asdict, dataclass, field
from itertools import pairwise
from pathlib import Path
from typing import NamedTuple

ROOT = Path(__file__).resolve().parents[3]
LADDER = ("drishti", "trailer", "trailer2", "trailer3")  # 0, 1, 2, 3 trailers
# The scaling section's robots: the ladder and the tugger train of five carts (issue 51).
# LADDER stays the per-function benchmarks' set (robot_c_bench: CasADi's C of every robot).
SCALING = (*LADDER, "train5")
STEP_LINE = re.compile(r"^\S+: (.+?) \.\.\. ([0-9.]+) s$", re.M)
OP_ROW = re.compile(r"^\| `?(\w+)`? \| operations after CSE: ([^|]+)\|", re.M)
# The values of the TDROC configuration a measured image and step use (valid, not tuned).
TDROC_FIELDS = {"k1": "4.0", "k2": "4.0", "q_pos": "1.0", "q_vel": "1.0", "h": "0.01",
                "tau_max": "40.0", "eps": "0.5", "a": "0.9"}


@dataclass
class Rung:
    """One robot's measurements (``None``: not measured, e.g. no cross-compiler)."""

    robot: str
    trailers: int
    coordinates: int
    model_s: float = 0.0  # wall
    model_cpu_s: float = 0.0  # user + system
    model_peak_mb: float = 0.0
    model_steps: dict[str, float] = field(default_factory=dict)
    c_bytes: int = 0
    python_bytes: int = 0
    casadi_bytes: int = 0
    longest_python_line: int = 0
    forward_dynamics_ops: int = 0
    tdroc_step_ops: int = 0
    minimal_forward_dynamics_ops: int = 0
    contact_forces_ops: int = 0
    gcc_slowest_s: float = 0.0  # CPU seconds of the slowest file
    gcc_slowest_file: str = ""
    gcc_peak_mb: float = 0.0
    m4_tdroc_code: int | None = None
    m4_tdroc_stack: int | None = None
    x86_step_ns: float | None = None


# Runs a command and prints its own peak resident set (KB). The kernel records a child's
# peak including the memory it had between fork and exec, the parent's pages: measured from
# a large process (a pytest worker, 300 MB), every child read 300 MB. This launcher is small,
# so its own children's figures are theirs.
_PEAK_LAUNCHER = """
import os, subprocess, sys
proc = subprocess.Popen(sys.argv[1:])
_, status, usage = os.wait4(proc.pid, 0)
sys.stderr.write(f"\\n@peak-kb {usage.ru_maxrss} {usage.ru_utime + usage.ru_stime}\\n")
sys.exit(os.waitstatus_to_exitcode(status))
"""


class Measured(NamedTuple):
    """A command's wall and CPU (user + system) seconds, peak resident MB and output."""

    seconds: float
    peak_mb: float
    stdout: str
    stderr: str
    cpu_s: float


def run_with_peak(cmd: list[str], cwd: Path) -> Measured:
    """``cmd`` run to completion: its wall time, and its own peak memory and CPU time from
    ``os.wait4`` in a small launcher process (the rusage of that child alone; CPU time is
    what a shared machine disturbs least)."""
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        start = time.perf_counter()
        code = subprocess.call([sys.executable, "-c", _PEAK_LAUNCHER, *cmd], cwd=cwd,
                               stdout=out, stderr=err, text=True)
        seconds = time.perf_counter() - start
        out.seek(0)
        err.seek(0)
        stdout, stderr = out.read(), err.read()
    stderr, _, usage = stderr.rpartition("\n@peak-kb ")
    if code != 0 or not usage:
        raise RuntimeError(f"{' '.join(cmd)} failed ({code}):\n{stderr[-2000:]}")
    peak_kb, cpu = usage.split()
    return Measured(seconds, float(peak_kb) / 1024, stdout, stderr, float(cpu))


def robot_file(root: Path, robot: str) -> Path:
    return root / "modeling" / "robots" / robot / f"{robot}.toml"


def trailers(root: Path, robot: str) -> int:
    """The robot file's towed bodies: its ``[[body]]`` tables but the root."""
    with robot_file(root, robot).open("rb") as f:
        return max(len(tomllib.load(f).get("body", [])) - 1, 0)


def generated_folder(root: Path, robot: str) -> Path:
    """Where ``make model`` puts ``robot`` (Drishti at the root of generated/)."""
    return root / "generated" if robot == "drishti" else root / "generated" / robot


def prefix_of(folder: Path) -> str:
    header = next((folder / "c").glob("*_robot.h"))
    return header.name.removesuffix("_robot.h")


def folder_bytes(folder: Path) -> int:
    return sum(p.stat().st_size for p in folder.rglob("*") if p.is_file()
               and "__pycache__" not in p.parts)


def measure_generation(root: Path, robot: str, rung: Rung) -> None:
    """``wmr model --robot`` into a fresh folder: time, memory, steps, output sizes."""
    with tempfile.TemporaryDirectory() as tmp:
        run = run_with_peak(
            [sys.executable, "-m", "codegen", "--robot", str(robot_file(root, robot)),
             "--out", tmp], root)
        rung.model_s, rung.model_cpu_s, rung.model_peak_mb = run.seconds, run.cpu_s, run.peak_mb
        rung.model_steps = {what: float(s) for what, s in STEP_LINE.findall(run.stderr)}
        out = next(p.parent for p in Path(tmp).rglob("c") if p.is_dir())
        rung.c_bytes = folder_bytes(out / "c")
        rung.python_bytes = folder_bytes(out / "python")
        rung.casadi_bytes = folder_bytes(out / "casadi")
        rung.longest_python_line = max(len(line) for p in (out / "python").glob("*.py")
                                       for line in p.read_text().splitlines())


def operations(summary: str) -> int:
    """Total operations of a ``"145 add, 251 mul, 27 div, 4 sin/cos, 1 sqrt"`` count."""
    return sum(int(n) for n in re.findall(r"(\d+) [a-z/]+", summary))


def tdroc_step_kernels(folder: Path, prefix: str, table: dict[str, str]) -> list[str]:
    """The kernels (functions of the op table) ``<prefix>_tdroc_step_detail`` calls for the
    minimal formulation: what a step evaluates (those _init calls once are not counted). The
    step calls them as ``<prefix>_k_<kernel>`` (``<prefix>_kernels.h``), a kernel's
    parameter-only part split off into a ``_keep`` that _init calls."""
    text = (folder / "c" / f"{prefix}_tdroc.c").read_text()
    # the step's body: specialised per formulation (step_as) where it has two, else inline
    marker = next(m for m in (f"{prefix}_status_t {prefix}_tdroc_step_as(",
                              f"{prefix}_status_t {prefix}_tdroc_step_detail(") if m in text)
    body = text[text.index(marker):]
    called = set(re.findall(rf"\b{prefix}_(?:k_)?(\w+)\(", body))
    return sorted(k for k in table if k in called and not k.startswith("paper_"))


def step_operations(folder: Path, prefix: str) -> dict[str, str]:
    """The operations of each kernel's per-step part as ``<prefix>_kernels.h`` documents it
    (``<prefix>_k_<kernel>``: the body, or the part after ``_keep``), by kernel name."""
    text = (folder / "c" / f"{prefix}_kernels.h").read_text()
    pattern = rf"/\* {prefix}_k_(\w+): .*?operations after CSE: ([^*]+)\*/"
    found: list[tuple[str, str]] = re.findall(pattern, text, re.S)
    return dict(found)


def measure_operations(folder: Path, rung: Rung) -> None:
    table = dict(OP_ROW.findall((folder / "MODEL.md").read_text()))
    rung.forward_dynamics_ops = operations(table["forward_dynamics"])
    rung.minimal_forward_dynamics_ops = operations(table["minimal_forward_dynamics"])
    rung.contact_forces_ops = operations(table["wheel_contact_forces"])
    prefix = prefix_of(folder)
    per_step = step_operations(folder, prefix)  # a kernel's _keep runs at _init, not a step
    rung.tdroc_step_ops = sum(operations(per_step[k])
                              for k in tdroc_step_kernels(folder, prefix, table))


def measure_gcc(folder: Path, rung: Rung) -> None:
    """``gcc -O2 -std=c99 -c`` of each generated C file (double), one at a time."""
    with tempfile.TemporaryDirectory() as tmp:
        for src in sorted((folder / "c").glob("*.c")):
            run = run_with_peak(
                ["gcc", "-O2", "-std=c99", f"-I{folder / 'c'}", "-c", str(src), "-o",
                 f"{tmp}/{src.stem}.o"], folder)
            if run.cpu_s > rung.gcc_slowest_s:
                rung.gcc_slowest_s, rung.gcc_slowest_file = run.cpu_s, src.name
            rung.gcc_peak_mb = max(rung.gcc_peak_mb, run.peak_mb)


def tdroc_config_lines(prefix: str, nq: int) -> str:
    """C statements filling ``c`` (a TDROC configuration, minimal formulation)."""
    up = prefix.upper()
    lines = ["c.nominal = nominal;", f"c.formulation = {up}_FORMULATION_MINIMAL;",
             f"for (i = 0; i < {nq}; ++i) {{ c.k1[i] = {up}_LIT(4.0); "
             f"c.k2[i] = {up}_LIT(4.0); }}",
             f"c.accel_estimator = {up}_ACCEL_BACKWARD;", "c.n = 4;"]
    lines += [f"c.{name} = {up}_LIT({value});" for name, value in TDROC_FIELDS.items()
              if name not in ("k1", "k2")]
    return "\n    ".join(lines)


IMAGE_MAIN = """\
#include "{p}_tdroc.h"
#include "{p}_robot.h"

/* A minimal firmware image: TDROC initialised and stepped once (minimal formulation). */
static {p}_tdroc_state_t state;
volatile {p}_real_t sink;
volatile {p}_real_t sensor = {P}_LIT(0.1);

int main(void)
{{
    {p}_tdroc_config_t c = {{0}};
    const {p}_params_t nominal = {P}_ROBOT_PARAMS_INIT;
    {p}_real_t q[{n}], qdot[{n}], q_des[{n}], qdot_des[{n}], qddot_des[{n}], tau[{m}];
    int i;
    {config}
    for (i = 0; i < {n}; ++i) {{
        q[i] = sensor; qdot[i] = sensor; q_des[i] = sensor; qdot_des[i] = sensor;
        qddot_des[i] = sensor;
    }}
    if ({p}_tdroc_init(&state, &c) != {P}_OK) {{
        return 1;
    }}
    if ({p}_tdroc_step(&state, &c, q, qdot, q_des, qdot_des, qddot_des, tau) < 0) {{
        return 2;
    }}
    sink = tau[0];
    return 0;
}}
"""


def coordinates(folder: Path, prefix: str) -> tuple[int, int]:
    """(nq, nu) from ``<prefix>_robot.h``'s NQ/NU defines or the step's signature."""
    text = (folder / "c" / f"{prefix}_tdroc.h").read_text()
    match = re.search(rf"const {prefix}_real_t q\[(\d+)\].*?{prefix}_real_t tau\[(\d+)\]",
                      text, re.S)
    assert match, f"{prefix}_tdroc.h: no step signature"
    return int(match.group(1)), int(match.group(2))


def measure_m4(folder: Path, rung: Rung) -> None:
    """The TDROC image's generated code bytes and the step's worst-case stack (float32)."""
    from runtime.tooling.firmware.build import ARM_FLAGS, ARM_GCC, SECTION_FLAGS, run_tool
    from runtime.tooling.firmware.stack import compiled_frames, elf_frames, worst_stack
    from runtime.tooling.firmware.symbols import symbols

    if shutil.which(ARM_GCC) is None:
        return
    prefix = prefix_of(folder)
    nq, nu = coordinates(folder, prefix)
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        (work / "main.c").write_text(IMAGE_MAIN.format(
            p=prefix, P=prefix.upper(), n=nq, m=nu,
            config=tdroc_config_lines(prefix, nq)))
        flags = [*ARM_FLAGS, *SECTION_FLAGS, "-fstack-usage", "-fcallgraph-info=su",
                 f"-I{folder / 'c'}", f"-D{prefix.upper()}_FLOAT32"]
        sources = [p for p in sorted((folder / "c").glob(f"{prefix}_*.c"))]
        objs = []
        for src in [*sources, work / "main.c"]:
            obj = work / f"{src.stem}.o"
            run_tool([ARM_GCC, *flags, "-c", str(src), "-o", str(obj)], cwd=work)
            objs.append(obj)
        elf = work / "tdroc.elf"
        run_tool([ARM_GCC, *ARM_FLAGS, *SECTION_FLAGS, *map(str, objs),
                  "--specs=nano.specs", "--specs=nosys.specs", "-Wl,--gc-sections", "-lm",
                  "-o", str(elf)], cwd=work)
        own = {n: s for n, (_, s, k) in symbols(elf).items()
               if n.startswith(f"{prefix}_") and k in "tT"}
        frames = compiled_frames(sorted(work.glob("*.ci")), sorted(work.glob("*.su")))
        bound = worst_stack(f"{prefix}_tdroc_step", frames, elf_frames(elf))
        rung.m4_tdroc_code = sum(own.values())
        rung.m4_tdroc_stack = bound.bytes if bound.complete else None


STEP_HARNESS = """\
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <time.h>
#include "{p}_tdroc.h"
#include "{p}_robot.h"

static double now_ns(void) {{
    struct timespec t; clock_gettime(CLOCK_MONOTONIC, &t);
    return 1e9 * (double)t.tv_sec + (double)t.tv_nsec;
}}

/* Steps along a smooth trajectory with a small tracking error; prints ns a step (best of
   the passes) and a checksum of the torques. */
int main(int argc, char **argv) {{
    static {p}_tdroc_state_t state;
    {p}_tdroc_config_t c = {{0}};
    const {p}_params_t nominal = {P}_ROBOT_PARAMS_INIT;
    double q[{n}], qdot[{n}], q_des[{n}], qdot_des[{n}], qddot_des[{n}], tau[{m}];
    double best = 1e300, sum = 0.0;
    int i, k, pass, steps = argc > 1 ? atoi(argv[1]) : 20000;
    {config}
    if ({p}_tdroc_init(&state, &c) != {P}_OK) {{ puts("init failed"); return 1; }}
    for (pass = 0; pass < 7; ++pass) {{
        double start;
        {p}_tdroc_reset(&state);
        start = now_ns();
        for (k = 0; k < steps; ++k) {{
            double t = 0.01 * k;
            for (i = 0; i < {n}; ++i) {{
                q[i] = 0.1 * sin(t + i); qdot[i] = 0.1 * cos(t + i);
                q_des[i] = q[i] + 0.01; qdot_des[i] = qdot[i] + 0.01; qddot_des[i] = 0.0;
            }}
            if ({p}_tdroc_step(&state, &c, q, qdot, q_des, qdot_des, qddot_des, tau) < 0) {{
                printf("step %d failed\\n", k); return 1;
            }}
            sum += tau[0];
        }}
        start = (now_ns() - start) / steps;
        if (start < best) best = start;
    }}
    printf("%.3f %.17g\\n", best, sum);
    return 0;
}}
"""


def build_step(folder: Path, work: Path) -> Path:
    prefix = prefix_of(folder)
    nq, nu = coordinates(folder, prefix)
    src = work / f"{prefix}_step_bench.c"
    src.write_text(STEP_HARNESS.replace("#include <time.h>",
                                        "#include <stdlib.h>\n#include <time.h>").format(
        p=prefix, P=prefix.upper(), n=nq, m=nu, config=tdroc_config_lines(prefix, nq)))
    exe = work / f"{prefix}_{abs(hash(str(folder)))}"
    sources = [str(p) for p in sorted((folder / "c").glob(f"{prefix}_*.c"))
               if not p.name.endswith("_plant.c")]
    subprocess.run(["gcc", "-O2", "-std=c99", f"-I{folder / 'c'}", str(src), *sources, "-lm",
                    "-o", str(exe)], check=True, capture_output=True)
    return exe


def step_times(executables: list[Path], rounds: int = 3) -> list[tuple[float, str]]:
    """(ns a step, torque checksum) per executable: the best over ``rounds`` interleaved
    runs (each round runs every executable once)."""
    best = [float("inf")] * len(executables)
    checks = [""] * len(executables)
    for _ in range(rounds):
        for i, exe in enumerate(executables):
            out = subprocess.run([str(exe)], check=True, capture_output=True,
                                 text=True).stdout.split()
            best[i] = min(best[i], float(out[0]))
            checks[i] = out[1]
    return list(zip(best, checks, strict=True))


def measure(root: Path = ROOT, robots: tuple[str, ...] = SCALING,
            generation: bool = True) -> list[Rung]:
    """The robots' measurements (progress on stdout: train5's derivation alone takes
    minutes)."""
    rungs = []
    for robot in robots:
        folder = generated_folder(root, robot)
        prefix = prefix_of(folder)
        rung = Rung(robot, trailers(root, robot), coordinates(folder, prefix)[0])
        print(f"scaling: {robot} ...", flush=True)
        if generation:
            measure_generation(root, robot, rung)
        measure_operations(folder, rung)
        measure_gcc(folder, rung)
        measure_m4(folder, rung)
        rungs.append(rung)
    with tempfile.TemporaryDirectory() as tmp:
        exes = [build_step(generated_folder(root, r.robot), Path(tmp)) for r in rungs]
        for rung, (ns, _) in zip(rungs, step_times(exes), strict=True):
            rung.x86_step_ns = ns
    return rungs


def _kb(n: int | None) -> str:
    return "—" if n is None else f"{n / 1000:,.1f}"


def section(rungs: list[Rung]) -> list[str]:
    """The BENCHMARKS.md section (and README table) of the measurements."""
    lines = [
        "| robot (trailers, coordinates) | `wmr model` wall s / CPU s (peak MB) "
        "| C / Python / CasADi kB "
        "| ops: forward dynamics / TDROC step | gcc -O2 slowest file CPU s (peak MB) "
        "| M4 TDROC code B / stack B | x86 TDROC step ns |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rungs:
        lines.append(
            f"| {r.robot} ({r.trailers}, {r.coordinates}) | {r.model_s:.1f} / "
            f"{r.model_cpu_s:.1f} ({r.model_peak_mb:.0f}) | {_kb(r.c_bytes)} / "
            f"{_kb(r.python_bytes)} / "
            f"{_kb(r.casadi_bytes)} | {r.forward_dynamics_ops:,} / {r.tdroc_step_ops:,} "
            f"| {r.gcc_slowest_s:.2f} ({r.gcc_peak_mb:.0f}) "
            f"| {'—' if r.m4_tdroc_code is None else f'{r.m4_tdroc_code:,}'} / "
            f"{'—' if r.m4_tdroc_stack is None else r.m4_tdroc_stack} "
            f"| {'—' if r.x86_step_ns is None else f'{r.x86_step_ns:.0f}'} |")
    return lines


# The figures whose growth per added cart issue 51 asks to be flat (within ±20 %).
GROWTH_FIGURES = (("forward dynamics", "forward_dynamics_ops"),
                  ("minimal forward dynamics", "minimal_forward_dynamics_ops"),
                  ("contact forces", "contact_forces_ops"),
                  ("TDROC step", "tdroc_step_ops"))
FLAT = 0.20


class Growth(NamedTuple):
    """One figure's operations added per cart between consecutive towing robots."""

    figure: str
    steps: tuple[tuple[int, int, float], ...]  # (carts before, carts after, ops a cart)

    @property
    def spread(self) -> tuple[float, float]:
        """(lowest, highest) step over their mean, minus one: (−0.2, +0.2) is ±20 %."""
        per_cart = [s[2] for s in self.steps]
        mean = sum(per_cart) / len(per_cart)
        return min(per_cart) / mean - 1.0, max(per_cart) / mean - 1.0

    @property
    def flat(self) -> bool:
        low, high = self.spread
        return low >= -FLAT and high <= FLAT


def growth(rungs: list[Rung]) -> list[Growth]:
    """Operations added per cart, (ops(n) − ops(m)) / (n − m) between consecutive robots
    with at least one cart (a gap, e.g. three to five carts, is averaged over its carts)."""
    towing = sorted((r for r in rungs if r.trailers >= 1), key=lambda r: r.trailers)
    out = []
    for figure, attribute in GROWTH_FIGURES:
        steps = tuple(
            (a.trailers, b.trailers,
             (getattr(b, attribute) - getattr(a, attribute)) / (b.trailers - a.trailers))
            for a, b in pairwise(towing) if b.trailers > a.trailers)
        if steps:
            out.append(Growth(figure, steps))
    return out


class Budget(NamedTuple):
    """One of issue 51's budgets against its measurement (``None``: not measured)."""

    what: str
    measured: float | None
    limit: float
    unit: str

    @property
    def met(self) -> bool | None:
        return None if self.measured is None else self.measured < self.limit


def budgets(rungs: list[Rung]) -> list[Budget]:
    """Issue 51's budgets for the robots measured: five carts derived in < 60 s (CPU, the
    figure a shared machine disturbs least) and < 1 GB, its generated C < 1 MB and two
    trailers' < 500 kB, gcc -O2 of any file < 30 s, the M4 TDROC step < 16 KB code and
    < 1 KB stack, the x86 TDROC step of five carts < 2 µs."""
    by = {r.robot: r for r in rungs}
    out = []
    if "train5" in by:
        t = by["train5"]
        out += [Budget("train5 `wmr model` CPU", t.model_cpu_s or None, 60.0, "s"),
                Budget("train5 `wmr model` peak memory", t.model_peak_mb or None, 1000.0,
                       "MB"),
                Budget("train5 generated C", t.c_bytes / 1000, 1000.0, "kB")]
    if "trailer2" in by:
        out.append(Budget("trailer2 generated C", by["trailer2"].c_bytes / 1000, 500.0, "kB"))
    if rungs:
        out.append(Budget("gcc -O2 slowest file CPU (any robot)",
                          max(r.gcc_slowest_s for r in rungs), 30.0, "s"))
    for r in rungs:
        if r.trailers >= 1:
            out += [Budget(f"{r.robot} M4 TDROC code", r.m4_tdroc_code, 16_000.0, "B"),
                    Budget(f"{r.robot} M4 TDROC stack", r.m4_tdroc_stack, 1024.0, "B")]
    if "train5" in by:
        ns = by["train5"].x86_step_ns
        out.append(Budget("train5 x86 TDROC step", ns, 2000.0, "ns"))
    return out


def growth_section(rungs: list[Rung]) -> list[str]:
    """Operations added per cart, and whether each figure's growth is flat within ±20 %."""
    found = growth(rungs)
    if not found:
        return []
    steps = [f"{a} → {b}" for a, b, _ in found[0].steps]
    lines = ["| operations added per cart | " + " | ".join(steps)
             + " | spread around the mean | flat within ±20 % |",
             "|---|" + "---:|" * (len(steps) + 2)]
    for g in found:
        low, high = g.spread
        lines.append(f"| {g.figure} | " + " | ".join(f"{s[2]:,.0f}" for s in g.steps)
                     + f" | {100 * low:+.0f} % / {100 * high:+.0f} % "
                     f"| {'yes' if g.flat else 'no'} |")
    return lines


def budget_section(rungs: list[Rung]) -> list[str]:
    lines = ["| budget (issue 51) | measured | limit | met |", "|---|---:|---:|---|"]
    for b in budgets(rungs):
        measured = "—" if b.measured is None else f"{b.measured:,.1f} {b.unit}"
        met = "not measured" if b.met is None else ("yes" if b.met else "**no**")
        lines.append(f"| {b.what} | {measured} | {b.limit:,.0f} {b.unit} | {met} |")
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m runtime.tooling.bench.scale",
        description="Measure how generation, code size, compile time and step cost grow "
        "with the robot (Drishti, one, two, three trailers, five carts).")
    parser.add_argument("--root", type=Path, default=ROOT,
                        help="checkout to measure (its modeling/robots and generated/)")
    parser.add_argument("--robots", nargs="+", default=list(SCALING), choices=SCALING)
    parser.add_argument("--json", type=Path, default=None, help="write the rows here")
    args = parser.parse_args(argv)
    rungs = measure(args.root.resolve(), tuple(args.robots))
    print("\n".join([*section(rungs), "", *growth_section(rungs), "",
                     *budget_section(rungs)]))
    if args.json is not None:
        args.json.write_text(json.dumps([asdict(r) for r in rungs], indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
