"""docs/TUTORIAL.md, run as a new user would: the wheel built from this tree, installed into
a fresh virtual environment, every command of the tutorial run in order from a folder
outside the repository, and what the tutorial says about the results checked.

The tutorial's files are its code blocks preceded by ``<!-- file: NAME -->``; its commands
are the ``$ `` lines of its ``console`` blocks. About two minutes (most of it pip installing
the dependencies into the new environment, and the simulation of step 6; step 7, the URDF,
adds about 15 s)."""

from __future__ import annotations

import csv
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from generated_code_support import ROOT

from modeling.version import VERSION
from runtime.bindings.generated import load_robot_code

TUTORIAL = ROOT / "docs" / "TUTORIAL.md"
MARK = "### tutorial command "


def tutorial_files(text: str) -> dict[str, str]:
    return {m.group(1): m.group(2) for m in
            re.finditer(r"<!-- file: (\S+) -->\n```\w*\n(.*?)```", text, re.S)}


def tutorial_commands(text: str) -> list[str]:
    blocks = re.findall(r"```console\n(.*?)```", text, re.S)
    return [line[2:] for block in blocks for line in block.splitlines() if line.startswith("$ ")]


def test_the_tutorial_parses() -> None:
    text = TUTORIAL.read_text()
    assert set(tutorial_files(text)) == {"my_robot.toml", "my_firmware.toml", "firmware_loop.c",
                                         "my_robot.urdf", "quick.toml"}
    commands = tutorial_commands(text)
    assert commands[0] == "python3 -m venv venv"
    wheel = f"wmr_toolchain-{VERSION}-py3-none-any.whl"
    assert any(wheel in c for c in commands), f"the tutorial must install {wheel}"


def _tree_copy(dst: Path) -> None:
    """The working tree's files (tracked and new, not ignored): what a clone would hold."""
    listed = subprocess.run(["git", "ls-files", "-co", "--exclude-standard", "-z"], cwd=ROOT,
                            capture_output=True, check=True).stdout.decode().split("\0")
    for name in filter(None, listed):
        src = ROOT / name
        if src.is_file():
            (dst / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dst / name)


def _user_env(cache: Path) -> dict[str, str]:
    """The environment of a user's shell: no project virtual environment on PATH."""
    venv = Path(sys.prefix)
    path = [p for p in os.environ.get("PATH", "").split(os.pathsep)
            if p and not Path(p).resolve().is_relative_to(venv.resolve())]
    env = {k: v for k, v in os.environ.items()
           if k not in ("VIRTUAL_ENV", "PYTHONPATH", "PYTHONHOME")}
    env["PATH"] = os.pathsep.join(path)
    env["WMR_CACHE_DIR"] = str(cache)  # compiled objects: not in the user's ~/.cache
    return env


@pytest.mark.skipif(shutil.which("cc") is None, reason="needs a C compiler")
def test_tutorial_runs_from_an_installed_wheel(tmp_path: Path) -> None:
    text = TUTORIAL.read_text()
    src, dist, work = tmp_path / "src", tmp_path / "dist", tmp_path / "my_project"
    _tree_copy(src)
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", "-w",
                    str(dist), str(src)], check=True, capture_output=True, timeout=600)
    wheel = dist / f"wmr_toolchain-{VERSION}-py3-none-any.whl"
    assert wheel.is_file(), sorted(p.name for p in dist.iterdir())
    work.mkdir()
    shutil.copy2(wheel, work / wheel.name)
    for name, body in tutorial_files(text).items():
        (work / name).write_text(body)
    commands = tutorial_commands(text)
    script = ["set -euo pipefail"]
    for i, cmd in enumerate(commands):
        script += [f"echo '{MARK}{i}'", cmd]
    env = _user_env(tmp_path / "cache")
    done = subprocess.run(["bash", "-c", "\n".join(script)], cwd=work, env=env,
                          capture_output=True, text=True, timeout=1200)
    outputs = dict(zip(commands, re.split(rf"^{MARK}\d+\n", done.stdout, flags=re.M)[1:],
                       strict=False))
    assert done.returncode == 0, f"{done.stdout[-3000:]}\n{done.stderr[-3000:]}"

    assert outputs["wmr --version"].strip() == f"wmr-toolchain {VERSION}"
    # The installed package ran, not this tree, and wrote nothing into site-packages.
    site = next((work / "venv" / "lib").glob("python3*/site-packages"))
    assert (site / "runtime" / "cli.py").is_file()
    assert not (site / "build").exists()
    shipped = sorted(p.relative_to(site).as_posix() for p in (site / "generated").rglob("*")
                     if "__pycache__" not in p.parts)
    wheel_files = subprocess.run([sys.executable, "-m", "zipfile", "-l", str(wheel)],
                                 capture_output=True, text=True, check=True).stdout
    assert all(f"generated/{p.split('/', 1)[1]}" in wheel_files or (site / p).is_dir()
               for p in shipped), "files appeared in the installed generated/"

    # Step 3: the robot's code, in a folder and with a prefix of its own.
    code = work / "my_robot_code" / "my_robot"
    assert (code / "c" / "my_robot_tdroc.c").is_file() and (code / "MODEL.md").is_file()
    assert '"my_robot"' in (code / "c" / "my_robot_robot.h").read_text()
    assert not (work / "my_robot_code" / "c").exists()

    # Step 4: what the tutorial says about the verdicts.
    stability = next(v for k, v in outputs.items() if k.startswith("wmr stability"))
    rows = {(m.group(1), m.group(2)): m.group(3) for m in re.finditer(
        r"^\| (TDC|TDROC|ROC|ASMC) \| (paper|minimal) \|.*\| (yes|\*\*no\*\*) "
        r"\|[^|]*\|[^|]*\|[^|]*\|$",
        stability, re.M)}
    assert len(rows) == 8, stability
    assert all(rows[(c, "minimal")] == "yes" for c in ("TDC", "TDROC", "ROC", "ASMC")), rows
    assert all(rows[(c, "paper")] == "**no**" for c in ("TDC", "TDROC", "ASMC")), rows
    assert "TDE condition, paper formulation" in stability
    assert "TDE condition, minimal formulation" not in stability  # it holds over ±15 %

    # Step 5: the firmware loop built and tracked (it exits 1 otherwise).
    assert "worst wheel-angle error after 5 s" in outputs["./firmware_loop"]

    # Step 6: the simulated runs, and "the minimal formulation tracks the circle to within a
    # few millimetres".
    results = work / "results"
    for name in ("REPORT.md", "metrics.csv", "tracking.png"):
        assert (results / name).is_file(), name
    with (results / "metrics.csv").open() as f:
        metrics = list(csv.DictReader(f))
    pairs = load_robot_code("").runs()  # the same registry generated my_robot_code
    assert len(metrics) == 2 * len(pairs)  # circle and lawn mower
    circle_minimal = [r for r in metrics
                      if r["path"] == "circle" and r["formulation"] == "minimal"]
    assert len(circle_minimal) == sum(f == "minimal" for f, _ in pairs)
    assert all(r["status"] == "ok" for r in circle_minimal), circle_minimal
    assert all(float(r["rms_error_m"]) < 0.02 for r in circle_minimal), circle_minimal
    # ... and the paper formulation, predicted unstable in step 4, is refused, not run
    paper_rows = [r for r in metrics if r["formulation"] == "paper"]
    assert paper_rows and all(r["status"] == "refused" for r in paper_rows), paper_rows

    # Step 7: the URDF, imported twice (the second time with the motors), modelled and run.
    imported = (work / "my_urdf_robot.toml").read_text()
    assert imported.count("rotor_inertia = 1.2e-06") == 2
    assert imported.count("gear_ratio = 30.0") == 2
    assert "link 'laser': ixx = iyy = izz = 0.001 kg m^2" in imported
    report = (work / "my_urdf_code" / "my_urdf_robot" / "MODEL.md").read_text()
    assert "## Physics audit of the robot file" in report
    assert "contributes 8 % of the yaw inertia of body 'base'" in report
    with (work / "urdf_results" / "metrics.csv").open() as f:
        urdf_runs = list(csv.DictReader(f))
    assert len(urdf_runs) == 2 * len(pairs), urdf_runs
    assert all(r["status"] == ("ok" if r["formulation"] == "minimal" else "refused")
               for r in urdf_runs), urdf_runs
