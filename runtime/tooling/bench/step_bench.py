"""The full controller step benchmark: ``wmr_tdroc_step`` (what firmware calls) against a
hand-written step with the same contract (``csrc/hand_tdroc.c``), on the controller inputs
of a recorded closed loop (consistent states, lawn-mower path, paper formulation).

One executable (gcc -O2) runs both: first every step of the recording through each
variant, checking that the statuses are equal and the torques agree (1e-9 relative to the
run's largest torque) — the timing is refused otherwise — then the timing, interleaved:
each repetition times every variant once, over whole passes of the recording (a fresh
``_init`` before each pass, not timed).
"""

from __future__ import annotations

import json
import statistics
import subprocess
import tempfile
from pathlib import Path
from typing import Any

from runtime.bindings.cbuild import GENERATED_C
from runtime.tooling.bench.c_bench import renamed_objects
from runtime.tooling.firmware.build import frozen_define

BENCH_CSRC = Path(__file__).resolve().parent / "csrc"
CFLAGS = ["-std=c99", "-O2"]
# ours = wmr_tdroc_step; hand = hand_tdroc_step; ours_libm = wmr_tdroc_step built with
# -DWMR_LIBM_TRIG (libm's sin/cos, as the hand-written step uses, instead of the generated);
# ours_frozen = wmr_tdroc_step built with the configuration compiled in (wmr freeze).
VARIANTS = ("ours", "hand", "ours_libm", "ours_frozen")
TORQUE_TOLERANCE = 1e-9  # relative to the run's largest |tau|

HARNESS = r"""
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "hand_tdroc.h"
#include "wmr_tdroc.h"

#define NV 4
wmr_status_t lm_wmr_tdroc_init(wmr_tdroc_state_t *state, const wmr_tdroc_config_t *config);
wmr_status_t lm_wmr_tdroc_step(wmr_tdroc_state_t *state, const wmr_tdroc_config_t *config,
    const double q[5], const double qdot[5], const double q_des[5], const double qdot_des[5],
    const double qddot_des[5], double tau[2]);
wmr_status_t fz_wmr_tdroc_init(wmr_tdroc_state_t *state, const wmr_tdroc_config_t *config);
wmr_status_t fz_wmr_tdroc_step(wmr_tdroc_state_t *state, const wmr_tdroc_config_t *config,
    const double q[5], const double qdot[5], const double q_des[5], const double qdot_des[5],
    const double qddot_des[5], double tau[2]);
extern const wmr_tdroc_config_t fz_wmr_tdroc_frozen_config;
static const char *const NAMES[NV] = {"ours", "hand", "ours_libm", "ours_frozen"};

static double now_ns(void) {
    struct timespec ts; clock_gettime(CLOCK_MONOTONIC, &ts);
    return 1e9 * (double)ts.tv_sec + (double)ts.tv_nsec;
}
static wmr_tdroc_config_t cfg;
static wmr_tdroc_state_t ours, ours_lm, ours_fz;
static hand_tdroc_state_t hand;

/* A fresh state for variant v (not timed). */
static void fresh(int v) {
    const int s = v == 0 ? wmr_tdroc_init(&ours, &cfg)
                : v == 1 ? hand_tdroc_init(&hand, &cfg)
                : v == 2 ? lm_wmr_tdroc_init(&ours_lm, &cfg)
                : fz_wmr_tdroc_init(&ours_fz, &fz_wmr_tdroc_frozen_config);
    if (s != WMR_OK) {
        fprintf(stderr, "init failed\n"); exit(2);
    }
}

/* One pass of the recording through variant v from its current state; statuses and
   torques into st, tq. */
static double pass(int v, int *st, double *tq) {
    int k, s;
    double tau[2], sink = 0.0;
    for (k = 0; k < NSTEPS; ++k) {
        const double *in = IN[k];
        if (v == 0) {
            s = wmr_tdroc_step(&ours, &cfg, in, in + 5, in + 10, in + 15, in + 20, tau);
        } else if (v == 1) {
            s = hand_tdroc_step(&hand, &cfg, in, in + 5, in + 10, in + 15, in + 20, tau);
        } else if (v == 2) {
            s = lm_wmr_tdroc_step(&ours_lm, &cfg, in, in + 5, in + 10, in + 15, in + 20, tau);
        } else {
            s = fz_wmr_tdroc_step(&ours_fz, &fz_wmr_tdroc_frozen_config, in, in + 5, in + 10,
                                  in + 15, in + 20, tau);
        }
        if (st != 0) { st[k] = s; tq[2 * k] = tau[0]; tq[2 * k + 1] = tau[1]; }
        sink += tau[0] + (double)s;
    }
    return sink;
}

int main(int argc, char **argv) {
    long calls = argc > 1 ? atol(argv[1]) : 1000000;
    int repeats = argc > 2 ? atoi(argv[2]) : 5;
    long passes = calls / NSTEPS > 0 ? calls / NSTEPS : 1;
    static int st[NV][NSTEPS];
    static double tq[NV][2 * NSTEPS];
    static double ns[NV][64];
    double scale = 0.0, worst = 0.0, sink = 0.0;
    int v, k, rep;
    long i;
    CONFIG
    for (v = 0; v < NV; ++v) { fresh(v); pass(v, st[v], tq[v]); }
    for (v = 1; v < NV; ++v) {
        for (k = 0; k < 2 * NSTEPS; ++k) {
            if (fabs(tq[0][k]) > scale) scale = fabs(tq[0][k]);
            if (!(fabs(tq[v][k] - tq[0][k]) <= worst)) worst = fabs(tq[v][k] - tq[0][k]);
        }
        for (k = 0; k < NSTEPS; ++k) {
            if (st[0][k] != st[v][k]) {
                printf("{\"error\": \"%s: status differs at step %d\"}\n", NAMES[v], k);
                return 3;
            }
        }
    }
    printf("{\"check\": {\"steps\": %d, \"max_abs_tau_diff\": %.6e, "
           "\"tau_scale\": %.6e}}\n", NSTEPS, worst, scale);
    if (!(worst <= TOL * (scale > 1.0 ? scale : 1.0))) return 3;
    if (repeats > 64) repeats = 64;
    for (rep = 0; rep < repeats; ++rep) {
        for (v = 0; v < NV; ++v) {
            double t = 0.0;
            for (i = 0; i < passes; ++i) {
                double t0;
                fresh(v);
                t0 = now_ns();
                sink += pass(v, 0, 0);
                t += now_ns() - t0;
            }
            ns[v][rep] = t / (double)(passes * NSTEPS);
        }
    }
    for (v = 0; v < NV; ++v) {
        printf("{\"function\": \"tdroc_step\", \"variant\": \"%s\", \"ns\": [",
               NAMES[v]);
        for (rep = 0; rep < repeats; ++rep) printf("%s%.4f", rep ? ", " : "", ns[v][rep]);
        printf("], \"checksum\": %.15e}\n", sink);
    }
    return 0;
}
"""


def _config_lines(config: dict[str, Any]) -> str:
    from runtime.tooling.firmware.emulator import PARAM_FIELDS

    lines = [f"cfg.nominal.{p} = {v!r};" for p, v in zip(PARAM_FIELDS, config["params"],
                                                          strict=True)]
    for name, value in config.items():
        if name == "params":
            continue
        if isinstance(value, list):
            lines += [f"cfg.{name}[{i}] = {x!r};" for i, x in enumerate(value)]
        else:
            lines.append(f"cfg.{name} = {value!r};")
    return "\n    ".join(lines)


def frozen_header(workdir: Path, config: dict[str, Any]) -> Path:
    """``wmr freeze`` of the recorded configuration (double) into ``workdir``."""
    from runtime.bindings import cbuild
    from runtime.bindings.generated import load_robot_code
    from runtime.freeze.header import freeze
    from runtime.tooling.firmware.emulated_run import tdroc_config

    lib = cbuild.build(False)
    frozen = freeze(lib, load_robot_code(""), "tdroc", tdroc_config(lib.ffi, config))
    path = workdir / frozen.filename
    path.write_text(frozen.text)
    return path


def build_step_bench(workdir: Path, config: dict[str, Any],
                     inputs: list[list[list[float]]]) -> Path:
    """Compile the generated controller C (double; again with ``-DWMR_LIBM_TRIG``, renamed
    ``lm_wmr_*``, and with the configuration frozen, renamed ``fz_wmr_*``), the
    hand-written step and the harness with the recorded inputs into one executable;
    returns its path."""
    rows = ",\n".join("{" + ", ".join(repr(x) for v in step for x in v) + "}" for step in inputs)
    head = (f"#define NSTEPS {len(inputs)}\n#define TOL {TORQUE_TOLERANCE!r}\n"
            f"static const double IN[NSTEPS][25] = {{\n{rows}\n}};\n")
    body = HARNESS.replace("CONFIG", _config_lines(config))
    first, rest = body.split('#include "hand_tdroc.h"', 1)
    src = workdir / "step_main.c"
    src.write_text(first + '#include "hand_tdroc.h"\n' + head + rest)
    sources = [p for p in sorted(GENERATED_C.glob("wmr_*.c")) if p.name != "wmr_plant.c"]
    libm = renamed_objects(workdir, sources, ("-DWMR_LIBM_TRIG",), "lm_")
    frozen_header(workdir, config)
    frozen = renamed_objects(workdir, sources, (frozen_define("tdroc"), f"-I{workdir}"), "fz_")
    exe = workdir / "step_bench"
    subprocess.run(
        ["gcc", *CFLAGS, f"-I{GENERATED_C}", f"-I{BENCH_CSRC}", str(src),
         str(BENCH_CSRC / "hand_tdroc.c"), *map(str, sources), *libm, *frozen, "-lm", "-o",
         str(exe)],
        check=True,
    )
    return exe


def run_steps(calls: int, repeats: int) -> dict[str, Any]:
    """Record the closed loop (double), check the variants agree, time them interleaved.

    Returns {"check": {...}, "rows": [{"function", "variant", "ns": [...]}, ...]}; raises
    RuntimeError when statuses or torques differ (no timing is reported then).
    """
    from runtime.tooling.firmware.emulated_run import record_closed_loop

    rec = record_closed_loop("tdroc", "paper", eps=0.5, float32=False)
    with tempfile.TemporaryDirectory() as tmp:
        exe = build_step_bench(Path(tmp), rec.config, rec.inputs)
        proc = subprocess.run([str(exe), str(calls), str(repeats)], capture_output=True,
                              text=True, check=False)
    lines = [json.loads(line) for line in proc.stdout.splitlines() if line.startswith("{")]
    if proc.returncode != 0:
        raise RuntimeError(f"step benchmark refused to time: {lines or proc.stderr}")
    check = next(x["check"] for x in lines if "check" in x)
    return {"check": check, "rows": [x for x in lines if "function" in x]}


def summarise_steps(result: dict[str, Any]) -> dict[tuple[str, str], dict[str, float]]:
    """(function, variant) -> median, min, max ns per step."""
    return {
        (r["function"], r["variant"]): {
            "median": statistics.median(r["ns"]), "min": min(r["ns"]), "max": max(r["ns"])
        }
        for r in result["rows"]
    }
