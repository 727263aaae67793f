"""Each staged robot's generated C model module evaluates S(q), M̄ and H̄ once per call
(issue 51, ``codegen.shared``): one static helper holds their arithmetic, the model
functions that read them call it, and the forward dynamics is a call of its prepared pair
(whose results it equals bit for bit: tests/generated/test_prepared_model.py); Drishti's
closed-form module has neither (its one static function tests the forward
dynamics' late-checked inputs). The values are checked by the crosscheck and KKT tests."""

from __future__ import annotations

import re
import shutil
import subprocess
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
    inline = f"{robot.upper()}_SHARED_INLINE"
    assert len(re.findall(rf"^{inline} void {helper}\(", text, re.M)) == 1
    fns = functions(text)
    for name in CALLERS:
        assert f"{helper}(p, q, wheel_rates, _shared);" in fns[f"{robot}_{name}"], name
    fd = fns[f"{robot}_forward_dynamics"]
    assert f"{robot}_model_prepare(p, &prepared)" in fd
    assert f"return {robot}_forward_dynamics_prepared(&prepared, q, qdot, tau, qddot);" in fd
    assert "_t0" not in fd  # no arithmetic of its own


def test_drishti_prints_no_helper() -> None:
    """No staged quantities; its one static function is the forward dynamics' test of the
    inputs it checks late (tests/codegen/test_late_input_checks.py)."""
    text = (ROOT / "generated" / "c" / "wmr_model.c").read_text()
    assert "_shared" not in text and "staged_quantities" not in text
    assert re.findall(r"^WMR_SHARED_INLINE \w+ (\w+)\(", text, re.M) == [
        "wmr_forward_dynamics_late_inputs"]
    assert "static" not in text.split("#endif", 1)[1]  # but the helpers' macro


@pytest.mark.skipif(shutil.which("gcc") is None or shutil.which("nm") is None,
                    reason="gcc and nm needed")
@pytest.mark.parametrize(("flag", "called"), [("-O2", False), ("-Os", True)])
def test_the_helper_is_inlined_unless_optimising_for_size(tmp_path: Path, flag: str,
                                                          called: bool) -> None:
    """Printed once, compiled into each caller at -O2 (a call would send its results
    through memory: the trailers' minimal forward dynamics ~1.2x the instructions of its own
    copy, callgrind), one copy called at -Os (the firmware's size)."""
    c_dir = ROOT / "generated" / "trailer" / "c"
    obj = tmp_path / "model.o"
    subprocess.run(["gcc", "-std=c99", flag, "-c", f"-I{c_dir}", str(c_dir / "trailer_model.c"),
                    "-o", str(obj)], check=True)
    symbols = subprocess.run(["nm", str(obj)], check=True, capture_output=True,
                             text=True).stdout
    assert ("trailer_staged_quantities" in symbols) is called
