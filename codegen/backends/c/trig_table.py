"""The constants of float32's sin/cos in double (``<prefix>_types.h`` on an x86 host without
FMA): x = k pi/8 + r, then sin x and cos x from sin r, cos r and a table of (sin, cos) of
j pi/8. Each value is the double nearest the exact one (mpmath at 40 digits), printed so
that it reads back to that double."""

from __future__ import annotations

import mpmath

STEPS = 4  # table points per quarter turn: k pi/8, |r| <= pi/16
ROWS = 5 * STEPS  # k mod 16, and the row a quarter turn on (sin, cos)(a + pi/2) = (cos, -sin)
PART_BITS = 29  # pi/8's first part: k part0 is exact for |k| < 2^24


def _double(value: mpmath.mpf) -> str:
    return repr(float(value))


def context() -> dict[str, object]:
    """The template's ``trig_table`` (rows of two C literals), ``pio8`` (pi/8's two parts)
    and ``inv_pio8`` (8/pi)."""
    with mpmath.workdps(40):
        step = mpmath.pi / (2 * STEPS)
        # sinpi/cospi: exact zeros at the multiples of pi/2
        turns = [mpmath.mpf(j) / (2 * STEPS) for j in range(ROWS)]
        rows = [(_double(mpmath.sinpi(t)), _double(mpmath.cospi(t))) for t in turns]
        # sin(-0) = -0: k = 0's sin r is kept, its product with -0.0 added to it
        rows[0] = ("-0.0", rows[0][1])
        scale = mpmath.mpf(2) ** (PART_BITS - 1 - int(mpmath.floor(mpmath.log(step, 2))))
        part0 = mpmath.floor(step * scale) / scale
        return {"trig_table": [f"{{{s}, {c}}}" for s, c in rows],
                "pio8": (_double(part0), _double(step - part0)),
                "inv_pio8": _double(1 / step)}
