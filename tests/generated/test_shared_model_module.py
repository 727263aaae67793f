"""Each staged robot's generated C model module evaluates S(q), M̄ and H̄ once per call
(issue 51, ``codegen.shared``): one static helper holds their arithmetic, the model
functions that read them call it, and the forward dynamics is a call of its prepared pair
(whose results it equals bit for bit: tests/generated/test_prepared_model.py); Drishti's
closed-form module has neither. The values are checked by the crosscheck and KKT tests."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
STAGED = ("trailer", "trailer2", "trailer3", "train5")
CALLERS = ("minimal_bias_forces", "minimal_forward_dynamics", "linearization",
           "wheel_contact_forces")


def functions(text: str) -> dict[str, str]:
    """Each function's definition in a generated .c, by name."""
    parts = re.split(r"\n(?=(?:static )?\w+ \w+\([^;]*?\)\n\{)", text)
    out = {}
    for part in parts:
        m = re.match(r"(?:static )?\w+ (\w+)\(", part)
        if m:
            out[m.group(1)] = part
    return out


@pytest.mark.parametrize("robot", STAGED)
def test_the_staged_quantities_are_printed_once_and_called(robot: str) -> None:
    text = (ROOT / "generated" / robot / "c" / f"{robot}_model.c").read_text()
    helper = f"{robot}_staged_quantities"
    assert len(re.findall(rf"^static void {helper}\(", text, re.M)) == 1
    fns = functions(text)
    for name in CALLERS:
        assert f"{helper}(p, q, wheel_rates, _shared);" in fns[f"{robot}_{name}"], name
    fd = fns[f"{robot}_forward_dynamics"]
    assert f"{robot}_model_prepare(p, &prepared)" in fd
    assert f"return {robot}_forward_dynamics_prepared(&prepared, q, qdot, tau, qddot);" in fd
    assert "_t0" not in fd  # no arithmetic of its own


def test_drishti_prints_no_helper() -> None:
    text = (ROOT / "generated" / "c" / "wmr_model.c").read_text()
    assert "static" not in text and "_shared" not in text
