"""``wmr_exp_carry`` of ``wmr_types.h``, the checked functions' non-finite test: the top bit
of the OR of its values is set exactly when one of them is NaN or ±Inf, in double and in
float32 — every finite class (±0, subnormals, the largest finite value, 1) and every
non-finite one (±Inf, quiet and signalling NaNs of both signs, NaN payloads) alone and
mixed with finite values, against ``isfinite``."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from runtime.bindings import cbuild

PROGRAM = r"""
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include "wmr_types.h"

#ifdef WMR_FLOAT32
#define BITS_OF(u) do { uint32_t b_ = (uint32_t)(u); memcpy(&v[n++], &b_, sizeof b_); } while (0)
#define TINY FLT_MIN
#define BIG FLT_MAX
#else
#define BITS_OF(u) do { uint64_t b_ = (uint64_t)(u); memcpy(&v[n++], &b_, sizeof b_); } while (0)
#define TINY DBL_MIN
#define BIG DBL_MAX
#endif

int main(void)
{
    wmr_real_t v[64];
    int n = 0, i, j, wrong = 0;
    const wmr_real_t finite[] = {WMR_LIT(0.0), -WMR_LIT(0.0), WMR_LIT(1.0), -WMR_LIT(1.0),
                                 TINY, TINY / WMR_LIT(4.0), -TINY / WMR_LIT(1024.0), BIG, -BIG};
    for (i = 0; i < (int)(sizeof finite / sizeof finite[0]); ++i) v[n++] = finite[i];
    v[n++] = (wmr_real_t)INFINITY;
    v[n++] = -(wmr_real_t)INFINITY;
    v[n++] = (wmr_real_t)NAN;
    v[n++] = -(wmr_real_t)NAN;
#ifdef WMR_FLOAT32
    BITS_OF(0x7f800001u); BITS_OF(0xff800001u); BITS_OF(0x7fbfffffu); BITS_OF(0x7fffffffu);
#else
    BITS_OF(UINT64_C(0x7ff0000000000001)); BITS_OF(UINT64_C(0xfff0000000000001));
    BITS_OF(UINT64_C(0x7ff7ffffffffffff)); BITS_OF(UINT64_C(0x7fffffffffffffff));
#endif
    for (i = 0; i < n; ++i) {
        for (j = 0; j < n; ++j) {
            const int flagged = ((wmr_exp_carry(v[i]) | wmr_exp_carry(v[j]))
                                 & WMR_EXP_CARRY_TOP) != 0u;
            const int nonfinite = !isfinite(v[i]) || !isfinite(v[j]);
            wrong += flagged != nonfinite;
        }
    }
    printf("%d %d\n", n, wrong);
    return 0;
}
"""


@pytest.mark.skipif(shutil.which("gcc") is None, reason="needs gcc")
@pytest.mark.parametrize("defines", [(), ("-DWMR_FLOAT32",)], ids=["double", "float32"])
def test_exp_carry_flags_exactly_the_nonfinite_values(tmp_path: Path,
                                                      defines: tuple[str, ...]) -> None:
    src, exe = tmp_path / "bits.c", tmp_path / "bits"
    src.write_text(PROGRAM)
    subprocess.run(["gcc", "-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", *defines,
                    f"-I{cbuild.GENERATED_C}", str(src), "-o", str(exe), "-lm"], check=True)
    n, wrong = map(int, subprocess.run([str(exe)], capture_output=True, text=True,
                                       check=True).stdout.split())
    assert n == 17 and wrong == 0
