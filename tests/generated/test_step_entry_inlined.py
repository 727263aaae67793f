"""The TDROC step firmware calls (``<prefix>_tdroc_step``) is its own copy of the step's body
when gcc optimises for speed (issue 52): no call of ``_step_detail`` (nine arguments, three
on an x86-64's stack, not a tail call) and no out-of-line kernel, in either precision; and
when gcc optimises for size (-Os, the firmware images) it calls ``_step_detail`` as before,
so the image has one body."""

from __future__ import annotations

import platform
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from runtime.bindings.generated import load_robot_code

pytestmark = pytest.mark.skipif(
    shutil.which("gcc") is None or shutil.which("objdump") is None
    or platform.machine() != "x86_64", reason="needs gcc and objdump on an x86-64 host")


def _calls_of(robot: str, opt: str, float32: bool, tmp_path: Path) -> set[str]:
    """The functions ``<prefix>_tdroc_step`` calls, from gcc ``opt``'s object file."""
    code = load_robot_code(robot)
    pre = code.prefix
    obj = tmp_path / f"{pre}_{opt}_{float32}.o"
    defines = [f"-D{pre.upper()}_FLOAT32"] if float32 else []
    subprocess.run(["gcc", "-std=c99", opt, *defines, "-c", f"-I{code.c_dir}",
                    str(code.c_dir / f"{pre}_tdroc.c"), "-o", str(obj)], check=True)
    text = subprocess.run(["objdump", "-dr", "--no-show-raw-insn", str(obj)], check=True,
                          capture_output=True, text=True).stdout
    body = text.split(f"<{pre}_tdroc_step>:\n", 1)[1].split("\n\n", 1)[0]
    # a call's target: a function of this object by its name (a static one has no
    # relocation), another by its relocation's symbol
    local = set(re.findall(r"\bcall\s+[0-9a-f]+ <([A-Za-z_][\w.]*?)(?:\+0x[0-9a-f]+)?>", body))
    external = set(re.findall(r"R_X86_64_PLT32\s+([A-Za-z_]\w*)", body))
    return (local - {f"{pre}_tdroc_step"}) | external


@pytest.mark.parametrize("robot", ["", "trailer"])
@pytest.mark.parametrize("float32", [False, True], ids=["double", "float32"])
def test_the_step_inlines_its_body_at_o2(robot: str, float32: bool, tmp_path: Path) -> None:
    pre = load_robot_code(robot).prefix
    calls = _calls_of(robot, "-O2", float32, tmp_path)
    assert f"{pre}_tdroc_step_detail" not in calls, calls
    assert not {c for c in calls if c.startswith(f"{pre}_k_")}, calls


@pytest.mark.parametrize("robot", ["", "trailer"])
def test_the_step_calls_step_detail_at_os(robot: str, tmp_path: Path) -> None:
    pre = load_robot_code(robot).prefix
    assert f"{pre}_tdroc_step_detail" in _calls_of(robot, "-Os", True, tmp_path)
