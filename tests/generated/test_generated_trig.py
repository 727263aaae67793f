"""The generated sin and cos of ``wmr_types.h``: the double build's ``wmr_sin``/``wmr_cos``
within 2 ulp of glibc's over the reduced range (a dense grid, the neighbours of multiples of
π/2 up to the bound, random arguments up to it), libm's own results beyond it and for ±Inf
and NaN, the sign of a zero kept; ``wmr_sincos_bounded`` in float32 within 2 ulp of the
exact values (every float of a range, and samples up to the bound), NaN beyond the bound,
and ``wmr_sincos_checked`` (what the controller steps call) the same values, in both
float32 builds (the x86 one in double, the pure-float one of a Cortex-M4F by ``-mfma``);
``-DWMR_LIBM_TRIG`` gives libm's functions, and a build whose evaluation would break the
reduction is refused."""

from __future__ import annotations

import json
import math
import platform
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from runtime.bindings import cbuild

PROGRAM = r"""
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "wmr_types.h"

static double ulps(double got, double want)
{
    const double ulp = nextafter(fabs(want), INFINITY) - fabs(want);
    return fabs(got - want) / ulp;
}

static int same_bits(double a, double b)
{
    return memcmp(&a, &b, sizeof a) == 0 || (isnan(a) && isnan(b));
}

static double worst = 0.0, worst_x = 0.0;
static long checked = 0, exact_failures = 0;

static void in_range(double x)
{
    const double es = ulps(WMR_SIN(x), sin(x)), ec = ulps(WMR_COS(x), cos(x));
    const double e = es > ec ? es : ec;
    if (!(e <= worst)) { worst = e; worst_x = x; }
    ++checked;
}

static void as_libm(double x)
{
    if (!same_bits(WMR_SIN(x), sin(x)) || !same_bits(WMR_COS(x), cos(x))) ++exact_failures;
}

int main(void)
{
    long i;
    unsigned long long state = 88172645463325252ull;
    for (i = -200000; i <= 200000; ++i) in_range(i * 5.0e-5);          /* |x| <= 10 */
    for (i = 1; i <= 1272000; i += 997) {                                /* near k pi/2 */
        const double c = (double)i * 1.5707963267948966;
        in_range(c); in_range(-c);
        in_range(nextafter(c, 0.0)); in_range(nextafter(c, INFINITY));
        in_range(c + 1e-9); in_range(c - 0.7853981633974483);
    }
    for (i = 0; i < 200000; ++i) {                                       /* random, |x| <= 2e6 */
        state ^= state << 13; state ^= state >> 7; state ^= state << 17;
        in_range(((double)(state >> 11) / 9007199254740992.0 * 2.0 - 1.0) * 2.0e6);
    }
    in_range(2.0e6); in_range(-2.0e6); in_range(1e-300); in_range(4.9e-324);
    {
        const double beyond[] = {2.0000001e6, -3.0e6, 1.0e10, 1.0e300, -1.0e308, INFINITY,
                                 -INFINITY, NAN, 0.0, -0.0};
        for (i = 0; i < (long)(sizeof beyond / sizeof beyond[0]); ++i) as_libm(beyond[i]);
    }
    printf("{\"checked\": %ld, \"worst_ulp\": %.3f, \"worst_x\": %.17g, \"exact_failures\": %ld, "
           "\"neg_zero\": %d}\n", checked, worst, worst_x, exact_failures,
           signbit(WMR_SIN(-0.0)) != 0);
    return 0;
}
"""


FLOAT_PROGRAM = r"""
#include <math.h>
#include <stdio.h>
#include "wmr_types.h"

static double worst = 0.0, worst_x = 0.0;
static long checked = 0, model_mismatch = 0;

static double ulps(float got, double exact)
{
    const float want = (float)exact;
    const double ulp = (double)(nextafterf(fabsf(want), INFINITY) - fabsf(want));
    return fabs((double)got - exact) / ulp - 0.5;  /* beyond the correctly rounded value */
}

static void in_range(float x)
{
    float s, c, sc, cc;
    double e;
    wmr_sincos_bounded(x, &s, &c);
    e = fmax(ulps(s, sin((double)x)), ulps(c, cos((double)x)));
    if (!(e <= worst)) { worst = e; worst_x = (double)x; }
    /* the model functions' WMR_SIN / WMR_COS and the steps' sincos_checked: the same
       kernel within the bound */
    model_mismatch += WMR_SIN(x) != s || WMR_COS(x) != c;
    wmr_sincos_checked(x, &sc, &cc);
    model_mismatch += sc != s || cc != c;
    ++checked;
}

int main(void)
{
    long i;
    unsigned int state = 2463534242u;
    float s, c;
    int beyond_nan = 1;
    for (i = -200000; i <= 200000; ++i) in_range((float)i * 5.0e-5f);
    for (i = 1; i <= 1272000; i += 997) {
        const float x = (float)((double)i * 1.5707963267948966);
        in_range(x); in_range(-x); in_range(nextafterf(x, 0.0f)); in_range(nextafterf(x, INFINITY));
    }
    for (i = 0; i < 200000; ++i) {
        state ^= state << 13; state ^= state >> 17; state ^= state << 5;
        in_range(((float)state / 4294967296.0f * 2.0f - 1.0f) * 2.0e6f);
    }
    in_range(2.0e6f); in_range(-2.0e6f); in_range(1e-30f);
    {
        const float beyond[] = {2.0000002e6f, -3.0e6f, 1.0e30f, INFINITY, -INFINITY, NAN};
        for (i = 0; i < (long)(sizeof beyond / sizeof beyond[0]); ++i) {
            wmr_sincos_bounded(beyond[i], &s, &c);
            beyond_nan = beyond_nan && isnan(s) && isnan(c);
            /* the model functions' beyond the bound: libm's sinf / cosf, bit for bit */
            model_mismatch += !((WMR_SIN(beyond[i]) == sinf(beyond[i])
                                 || (isnan(WMR_SIN(beyond[i])) && isnan(sinf(beyond[i]))))
                                && (WMR_COS(beyond[i]) == cosf(beyond[i])
                                    || (isnan(WMR_COS(beyond[i])) && isnan(cosf(beyond[i])))));
        }
    }
    wmr_sincos_checked(-0.0f, &s, &c);
    model_mismatch += !(signbit(s) != 0 && c == 1.0f);
    wmr_sincos_bounded(-0.0f, &s, &c);
    printf("{\"checked\": %ld, \"worst_ulp\": %.3f, \"worst_x\": %.9g, \"beyond_nan\": %d, "
           "\"neg_zero\": %d, \"model_mismatch\": %ld}\n", checked, worst, worst_x, beyond_nan,
           signbit(s) != 0 && c == 1.0f, model_mismatch);
    return 0;
}
"""


SWEEP_PROGRAM = r"""
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "wmr_types.h"

static double ulps(float got, double exact)  /* as FLOAT_PROGRAM's */
{
    const float want = (float)exact;
    const double ulp = (double)(nextafterf(fabsf(want), INFINITY) - fabsf(want));
    return fabs((double)got - exact) / ulp - 0.5;
}

int main(int argc, char **argv)
{
    /* every float from argv[1] to argv[2] (their bits in order: positive floats) */
    const float lo = strtof(argv[1], NULL), hi = strtof(argv[2], NULL);
    unsigned int bits, last;
    double worst = 0.0, worst_x = 0.0;
    long checked = 0, mismatch = 0;
    memcpy(&bits, &lo, sizeof bits);
    memcpy(&last, &hi, sizeof last);
    for (; bits <= last; ++bits) {
        float x, s, c, sc, cc;
        double e;
        memcpy(&x, &bits, sizeof x);
        wmr_sincos_bounded(x, &s, &c);
        wmr_sincos_checked(x, &sc, &cc);
        mismatch += memcmp(&s, &sc, sizeof s) != 0 || memcmp(&c, &cc, sizeof c) != 0;
        e = fmax(ulps(s, sin((double)x)), ulps(c, cos((double)x)));
        if (!(e <= worst)) { worst = e; worst_x = (double)x; }
        ++checked;
    }
    printf("{\"checked\": %ld, \"worst_ulp\": %.3f, \"worst_x\": %.9g, \"mismatch\": %ld}\n",
           checked, worst, worst_x, mismatch);
    return 0;
}
"""

# The two float32 builds of the kernel: x86-64's (in double, no FMA) and the pure-float one
# a Cortex-M4F compiles (__FP_FAST_FMAF), here by -mfma on a host that has FMA.
FLOAT_BUILDS = [pytest.param((), id="x86-double"),
                pytest.param(("-mfma",), id="float-fma")]


def _host_has_fma() -> bool:
    cpuinfo = Path("/proc/cpuinfo")
    return cpuinfo.exists() and " fma " in f" {cpuinfo.read_text()} ".replace("\n", " ")


def _float_build(build: tuple[str, ...]) -> tuple[str, ...]:
    if build and not (platform.machine() in ("x86_64", "AMD64") and _host_has_fma()):
        pytest.skip("the pure-float build runs here with -mfma: needs an x86-64 host with FMA")
    return ("-DWMR_FLOAT32", *build)


def _run(tmp_path: Path, *defines: str, program: str = PROGRAM,
         args: tuple[str, ...] = ()) -> dict[str, float]:
    src = tmp_path / "trig.c"
    src.write_text(program)
    exe = tmp_path / "trig"
    subprocess.run(["gcc", "-std=c99", "-O2", *defines, f"-I{cbuild.GENERATED_C}", str(src),
                    "-lm", "-o", str(exe)], check=True)
    out = subprocess.run([str(exe), *args], capture_output=True, text=True, check=True).stdout
    return json.loads(out)


@pytest.mark.skipif(shutil.which("gcc") is None, reason="needs gcc")
def test_generated_sin_cos_are_within_two_ulp_and_libm_beyond(tmp_path: Path) -> None:
    result = _run(tmp_path)
    assert result["checked"] > 600_000
    assert result["worst_ulp"] <= 2.0, result
    assert result["exact_failures"] == 0
    assert result["neg_zero"] == 1


@pytest.mark.skipif(shutil.which("gcc") is None, reason="needs gcc")
def test_fast_math_and_x87_builds_are_refused(tmp_path: Path) -> None:
    """-ffast-math folds (a + 1.5 * 2^52) - 1.5 * 2^52 to a, and x87 evaluation
    (FLT_EVAL_METHOD 2) keeps the excess precision that rounding relies on: both would give
    wrong sin/cos silently, so the header stops them (the x87 case needs a 32-bit compiler
    and is not exercised here); -DWMR_LIBM_TRIG builds either way."""
    src = tmp_path / "t.c"
    src.write_text('#include "wmr_types.h"\nint main(void) { return wmr_sin(0.5) > 1.0; }\n')
    base = ["gcc", "-std=c99", "-O2", f"-I{cbuild.GENERATED_C}", "-c", str(src), "-o",
            str(tmp_path / "t.o")]
    fast = subprocess.run([*base, "-ffast-math"], capture_output=True, text=True)
    assert fast.returncode != 0 and "IEEE evaluation" in fast.stderr
    subprocess.run([*base, "-ffast-math", "-DWMR_LIBM_TRIG"], check=True)
    subprocess.run(base, check=True)


@pytest.mark.skipif(shutil.which("gcc") is None, reason="needs gcc")
def test_libm_trig_define_gives_libm(tmp_path: Path) -> None:
    result = _run(tmp_path, "-DWMR_LIBM_TRIG")
    assert result["worst_ulp"] == 0.0 and result["exact_failures"] == 0


@pytest.mark.skipif(shutil.which("gcc") is None, reason="needs gcc")
@pytest.mark.parametrize("build", FLOAT_BUILDS)
def test_float32_sincos_bounded_is_within_two_ulp_and_nan_beyond(
        tmp_path: Path, build: tuple[str, ...]) -> None:
    result = _run(tmp_path, *_float_build(build), program=FLOAT_PROGRAM)
    assert result["checked"] > 600_000
    assert result["worst_ulp"] <= 1.5, result  # within 2 ulp of the exact value
    assert result["beyond_nan"] == 1 and result["neg_zero"] == 1
    # WMR_SIN/WMR_COS: the kernel, libm's beyond; sincos_checked: the same values
    assert result["model_mismatch"] == 0


@pytest.mark.skipif(shutil.which("gcc") is None, reason="needs gcc")
@pytest.mark.parametrize("build", FLOAT_BUILDS)
def test_float32_sincos_every_float_to_the_bound(tmp_path: Path,
                                                build: tuple[str, ...]) -> None:
    """Every float in [2^-12, 2e6] (2.8e8 of them; below 2^-12 sin x = x and cos x = 1 to
    the float, sampled above): within 2 ulp of glibc's double sin/cos (a reference we did
    not write, within 2^-52 of the exact values), and sincos_checked bit for bit
    sincos_bounded's. The kernel is odd and even exactly (the rounding to k is symmetric):
    the negative floats are the random and near-multiple samples above. The pure-float
    reduction rounded r once, 2.08 ulp at 1605625.62: found here, not by the samples."""
    result = _run(tmp_path, *_float_build(build), program=SWEEP_PROGRAM,
                  args=("0x1p-12", "2e6"))
    assert result["checked"] > 2.7e8
    # measured: 0.18 (x86, in double: within 0.68 ulp), 1.20 (pure float: 1.70 ulp)
    assert result["worst_ulp"] <= 1.5, result
    assert result["mismatch"] == 0


def test_the_bound_covers_the_steps_inputs() -> None:
    """A step checks |q| <= MAX_ABS_INPUT before sincos_bounded, which is exact to its bound:
    an input angle or the difference of two (a yaw relative to the root's). Exact: k times
    each of pi/2's two leading parts (as wmr_types.h has them) fits in 53 bits."""
    import struct

    from codegen.backends.c.files import TRIG_BOUND
    from codegen.controller_api import MAX_ABS_INPUT

    assert 2 * float(MAX_ABS_INPUT) <= float(TRIG_BOUND)
    k_bits = math.ceil(math.log2(float(TRIG_BOUND) * 2 / math.pi + 1))
    types = (cbuild.GENERATED_C / "wmr_types.h").read_text()
    kernel = types[types.index("sincos_kernel(double x"):]
    parts = re.findall(r"k \* ([0-9.e+-]+)", kernel)[:2]
    assert len(parts) == 2, parts
    for text in parts:
        mantissa = struct.unpack("<Q", struct.pack("<d", float(text)))[0] & ((1 << 52) - 1)
        significant = 53 - ((mantissa & -mantissa).bit_length() - 1 if mantissa else 52)
        assert significant + k_bits <= 53, (text, significant, k_bits)


def test_float32_model_functions_use_the_generated_sin_cos() -> None:
    """Both precisions' model functions call <prefix>_sin / _cos (the kernel within the
    bound, libm's beyond: test_float32_sincos_bounded_is_within_two_ulp_and_nan_beyond
    checks the values); -DWMR_LIBM_TRIG, libm's throughout."""
    types = (cbuild.GENERATED_C / "wmr_types.h").read_text()
    float_part = types[types.index("#ifdef WMR_FLOAT32"):types.index("#else")]
    assert "#define WMR_SIN(x) wmr_sin(x)" in float_part
    assert "#define WMR_COS(x) wmr_cos(x)" in float_part
    libm = types[types.index("#ifdef WMR_LIBM_TRIG"):]
    assert "return sinf(x);" in libm[:libm.index("#else\n#if defined(__FAST_MATH__)")]


@pytest.mark.skipif(shutil.which("gcc") is None, reason="needs gcc")
@pytest.mark.parametrize("robot", ["", "trailer3"])
def test_sin_and_cos_of_one_angle_share_one_inlined_reduction(robot: str) -> None:
    """At -O2 the double model functions call no trig function but libm's fallback (one
    sincos, beyond the bound): the kernel is inlined, so a sin and a cos share it. A kernel
    left out of line would run twice (the benchmark saw 1.6x on the mass matrix); gcc did
    leave it out of line in the large functions of the trailers until it was forced inline
    (three trailers' forward dynamics: a call of <prefix>_sin and of <prefix>_cos for each
    angle)."""
    from runtime.bindings.generated import load_robot_code

    code = load_robot_code(robot)
    prefix = code.prefix
    asm = subprocess.run(["gcc", "-std=c99", "-O2", "-S", "-o", "-", f"-I{code.c_dir}",
                          str(code.c_dir / f"{prefix}_model.c")],
                         capture_output=True, text=True, check=True).stdout
    names = (("wmr_mass_matrix", "wmr_forward_dynamics", "wmr_forward_dynamics_prepared")
             if not robot else tuple(f"{prefix}_{n}" for n in (
                 # a staged robot's forward dynamics is a call of its prepared pair (its
                 # arithmetic is there); its minimal forward dynamics inlines the shared
                 # quantities' helper at -O2 (issue 51, <PREFIX>_SHARED_INLINE)
                 "forward_dynamics_prepared", "minimal_forward_dynamics",
                 "minimal_mass_matrix")))
    for name in names:
        body = asm[asm.index(f"\n{name}:"):]
        body = body[:body.index(".cfi_endproc")]
        calls = [line.split()[-1] for line in body.splitlines() if "\tcall\t" in line]
        assert calls and all(c.startswith(("sincos", "sin@", "cos@")) for c in calls), (name, calls)
        assert "mulsd" in body


@pytest.mark.skipif(shutil.which("gcc") is None, reason="needs gcc")
@pytest.mark.parametrize("robot", ["", "trailer", "trailer2"])
def test_controllers_link_no_libm_trig(tmp_path: Path, robot: str) -> None:
    """A controller's kernels (its laws and the step's own copies) whose sin and cos take the
    step's validated angles as they are use the bounded reduction: neither precision links a
    libm sin/cos (on a Cortex-M4, newlib's cosf argument reduction was 480 B of the
    two-trailer TDROC step's stack); the model functions keep libm's beyond the bound. The
    laws of (18)-(27) (a K1 field: error dynamics in q) take q's angles as they are; a law
    that forms an angle itself (the PI's heading error θ_des − θ, up to twice the steps'
    input bound) keeps libm's, and exactly such a law links it."""
    from runtime.bindings.generated import load_robot_code

    code = load_robot_code(robot)
    folder, prefix, up = code.c_dir, code.prefix, code.prefix.upper()
    libm = {"sin", "cos", "sincos", "sinf", "cosf", "sincosf"}
    laws = (folder / f"{prefix}_laws.c").read_text()
    kernels = (folder / f"{prefix}_kernels.h").read_text()

    def law_bodies(name: str) -> list[str]:
        """Each formulation's law: its laws.c body, or the kernel it wraps (kernels.h)."""
        bodies = []
        for form in code.controller(name).formulations:
            body = laws[laws.index(f"void {prefix}_{form}_{name}_law("):]
            body = body[:body.index("\n}\n")]
            if f"{prefix}_k_{form}_{name}_law(" in body:
                body = kernels[kernels.index(f"void {prefix}_k_{form}_{name}_law("):]
                body = body[:body.index("\n}\n")]
            bodies.append(body)
        return bodies

    unbounded = {c.name for c in code.controller_infos
                 if any(f"{up}_SIN(" in b or f"{up}_COS(" in b for b in law_bodies(c.name))}
    for float32 in (False, True):
        linked: dict[str, set[str]] = {}
        for stem in ("model", *(c.name for c in code.controller_infos)):
            obj = tmp_path / f"{stem}{float32:d}.o"
            subprocess.run(["gcc", "-std=c99", "-O2", "-c", f"-I{folder}",
                            *([f"-D{up}_FLOAT32"] if float32 else []),
                            str(folder / f"{prefix}_{stem}.c"), "-o", str(obj)], check=True)
            nm = subprocess.run(["nm", "-u", str(obj)], capture_output=True, text=True,
                                check=True).stdout
            linked[stem] = {line.split()[-1] for line in nm.splitlines() if line.strip()}
        assert linked["model"] & libm, (robot, float32)  # not vacuous: the model links them
        for c in code.controller_infos:
            assert bool(linked[c.name] & libm) == (c.name in unbounded), \
                (robot, float32, c.name, linked[c.name] & libm)
            if "k1" in c.field_names():
                assert c.name not in unbounded, (robot, c.name)
    assert unbounded, robot  # not vacuous: the PI forms its heading error in the kernel
    if robot:  # a trailer's M-hat depends on its hitch angles: the bounded macros are used
        lyapunov = next(c.name for c in code.controller_infos if "k1" in c.field_names())
        body = law_bodies(lyapunov)[0]
        assert f"{up}_SIN_BOUNDED(" in body or f"{up}_COS_BOUNDED(" in body
