"""The compile-time choice of formulation (issue 12): built with
``-DWMR_FORMULATION_ONLY=WMR_FORMULATION_PAPER`` (or ``_MINIMAL``) the controllers accept
that formulation only (the other is WMR_ERR_BAD_FORMULATION, as an invalid value), give
the same statuses and torques as the default build on it, and a linked image keeps none
of the other formulation's kernels.
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from runtime.bindings.cbuild import GENERATED_C

HARNESS = r"""
#include <stdio.h>
#include "wmr_tdroc.h"
#include "wmr_robot.h"

/* Steps TDROC in formulation F on a smooth reference; prints the init status of the other
   formulation, then per step the status and the torques. */
int main(void)
{
    wmr_tdroc_config_t c = {0};
    wmr_tdroc_state_t s;
    const wmr_params_t nominal = WMR_ROBOT_PARAMS_INIT;
    int i, k;
    c.nominal = nominal;
    for (i = 0; i < 5; ++i) { c.k1[i] = 4.0; c.k2[i] = 4.0; }
    c.q_pos = 1.0; c.q_vel = 1.0; c.h = 0.01; c.tau_max = 40.0; c.eps = 0.5; c.n = 4;
    c.a = 0.9; c.accel_estimator = WMR_ACCEL_BACKWARD;
    c.formulation = 1 - F;
    printf("other %d\n", (int)wmr_tdroc_init(&s, &c));
    c.formulation = F;
    if (wmr_tdroc_init(&s, &c) != WMR_OK) return 1;
    for (k = 0; k < 40; ++k) {
        const double t = 0.01 * k;
        double q[5], qd[5], qr[5], qdr[5], qddr[5], tau[2] = {0.0, 0.0};
        wmr_status_t st;
        for (i = 0; i < 5; ++i) {
            q[i] = 0.1 * (i + 1) * t * t; qd[i] = 0.2 * (i + 1) * t;
            qr[i] = 0.3 * t + 0.05 * i; qdr[i] = 0.3; qddr[i] = 0.01 * i;
        }
        st = wmr_tdroc_step(&s, &c, q, qd, qr, qdr, qddr, tau);
        printf("%d %.17g %.17g\n", (int)st, tau[0], tau[1]);
    }
    return 0;
}
"""


def _run(tmp: Path, formulation: int, only: str | None) -> tuple[str, set[str]]:
    gcc = shutil.which("gcc")
    if gcc is None:
        pytest.skip("gcc not available")
    src = tmp / "main.c"
    src.write_text(HARNESS)
    exe = tmp / f"t_{formulation}_{only}"
    defines = [f"-DF={formulation}"]
    if only:
        defines.append(f"-DWMR_FORMULATION_ONLY=WMR_FORMULATION_{only}")
    sources = [str(p) for p in sorted(GENERATED_C.glob("wmr_*.c"))]
    subprocess.run(
        # -Os, as the firmware images are built (at -O2 the kernels are always inlined and
        # leave no symbol); -fno-inline: the kernels keep their (local) symbols to look for
        [gcc, "-std=c99", "-Os", "-fno-inline", "-Wall", "-Wextra", "-Werror",
         "-ffunction-sections",
         "-Wl,--gc-sections", *defines, f"-I{GENERATED_C}", str(src), *sources, "-lm",
         "-o", str(exe)],
        check=True, capture_output=True, text=True,
    )
    out = subprocess.run([str(exe)], check=True, capture_output=True, text=True).stdout
    names = subprocess.run(["nm", str(exe)], check=True, capture_output=True, text=True).stdout
    # a static clone (f.constprop.0, f.isra.0) counts as f
    return out, {line.split()[-1].split(".")[0] for line in names.splitlines() if line.strip()}


@pytest.mark.parametrize(("only", "formulation", "other"),
                         [("PAPER", 0, "minimal"), ("MINIMAL", 1, "paper")])
def test_one_formulation_at_compile_time(tmp_path: Path, only: str, formulation: int,
                                         other: str) -> None:
    default_out, default_syms = _run(tmp_path, formulation, None)
    only_out, only_syms = _run(tmp_path, formulation, only)
    d_lines, o_lines = default_out.splitlines(), only_out.splitlines()
    assert d_lines[0] == "other 0"  # the default build accepts both formulations
    assert o_lines[0] == "other -14"  # WMR_ERR_BAD_FORMULATION
    assert o_lines[1:] == d_lines[1:]  # same statuses and torques, to the last bit
    assert any(line.split()[0] == "0" and float(line.split()[1]) != 0.0 for line in o_lines[1:])
    trig = "_trig" if other == "paper" else ""  # the paper's M-hat depends on the heading
    # the kernels the step calls (wmr_k_*, wmr_kernels.h), and _init's ||Mhat^-1||
    for name in [*(f"wmr_k_{other}_{kernel}"
                   for kernel in (f"tde{trig}", "omega_difference", f"tdroc_law{trig}")),
                 f"wmr_{other}_minv_norm"]:
        assert name in default_syms
        assert name not in only_syms
