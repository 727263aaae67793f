"""The physics audit's warnings travel with the robot (issue 47): the generated ``robot.py``
declares them (``AUDIT_WARNINGS``), every command that runs the robot prints them on stderr
(``runtime.commands.options.print_audit``), ``wmr reproduce`` writes them into REPORT.md,
``wmr faults`` into FAULTS.md, a campaign into its summary.md and ``wmr crosscheck`` into its
report (all four through ``modeling.audit.section``), and ``wmr freeze`` into the frozen
header's comment.

The robot: tests/robots/caster_robot.toml with bare driven wheels (spin inertia below a
disc's 1.5 m r²/2, no motor given: the audit asks for the rotor), derived once here (about
4 s). The commands run as processes, so that stderr is the real one and the audit's
once-per-process printing starts afresh, as it does for a user.
"""

from __future__ import annotations

import logging
import re
import subprocess
import sys
from pathlib import Path

import pytest

from runtime.bindings.generated import load_robot_code

ROOT = Path(__file__).resolve().parents[2]
CASTER = ROOT / "tests" / "robots" / "caster_robot.toml"
# The warning the bare wheels draw (modeling.audit), in the words every output repeats.
WARNING = re.compile(r"wheel\[0\] \(driven wheel 'right'\): spin inertia 0\.003 kg m\^2 "
                     r"[^\n]*without its motor")
# docs/TUTORIAL.md's robot, its Iw the bare wheel's (the file test_audit.py reads too).
PHYSICAL = (ROOT / "tests" / "robots" / "tutorial_physical.toml").read_text(encoding="utf-8")


def wmr(*args: str) -> subprocess.CompletedProcess[str]:
    """``wmr ARGS`` in a fresh process of this checkout's code."""
    return subprocess.run([sys.executable, "-m", "runtime", *args], capture_output=True,
                          text=True, cwd=ROOT, timeout=600)


@pytest.fixture(scope="module")
def bare(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """(robot file, --generated folder) of the caster robot with bare driven wheels."""
    from runtime.cli import main as run

    folder = tmp_path_factory.mktemp("bare")
    robot = folder / "bare.toml"
    text = CASTER.read_text(encoding="utf-8").replace(
        'name = "caster_robot"', 'name = "bare_caster"')
    robot.write_text(text.replace("spin_inertia = 0.02 ", "spin_inertia = 0.003 "),
                     encoding="utf-8")
    out = folder / "generated"
    assert run(["model", "--robot", str(robot), "--out", str(out)]) == 0
    return robot, out


def test_generated_robot_py_declares_the_warnings(bare: tuple[Path, Path]) -> None:
    _, out = bare
    code = load_robot_code(out / "bare_caster")
    assert len(code.audit_warnings) == 2
    assert WARNING.search(code.audit_warnings[0])
    model_md = (out / "bare_caster" / "MODEL.md").read_text(encoding="utf-8")
    assert all(w in model_md for w in code.audit_warnings)  # the same lines as MODEL.md


def test_stability_prints_them(bare: tuple[Path, Path]) -> None:
    robot, out = bare
    done = wmr("stability", "--robot", str(robot), "--generated", str(out), "--json",
               "--no-measure", "--no-delay", "--no-saturation")
    assert done.returncode == 0, done.stderr
    lines = [x for x in done.stderr.splitlines() if x.startswith(f"warning: {robot}: ")]
    assert len(lines) == 2 and WARNING.search(lines[0]), done.stderr
    # by the robot's name too: the generated folder's robot.py carries them
    done = wmr("stability", "--robot", str(out / "bare_caster"), "--json", "--no-measure",
               "--no-delay", "--no-saturation")
    assert done.returncode == 0, done.stderr
    assert WARNING.search(done.stderr), done.stderr


def test_freeze_prints_them_and_writes_them_into_the_header(
        bare: tuple[Path, Path], tmp_path: Path) -> None:
    robot, out = bare
    done = wmr("freeze", "--controller", "tdc", "--robot", str(robot), "--generated",
               str(out), "--out", str(tmp_path))
    assert done.returncode == 0, done.stderr
    assert WARNING.search(done.stderr), done.stderr
    header = (tmp_path / "bare_caster_tdc_frozen.h").read_text(encoding="utf-8")
    comment = header[:header.index("#ifndef ")]
    assert " * Robot file audit (2 warnings; see MODEL.md):" in comment
    assert WARNING.search(comment), comment


def test_reproduce_prints_them_and_writes_them_into_report_md(
        bare: tuple[Path, Path], tmp_path: Path) -> None:
    robot, out = bare
    experiment = tmp_path / "short.toml"
    experiment.write_text("[paths]\ncircle_duration = 1.0\nlawnmower_duration = 1.0\n")
    results = tmp_path / "results"
    done = wmr("reproduce", "--robot", str(robot), "--generated", str(out), "--experiment",
               str(experiment), "--sensing", "sample-instant", "--no-plots", "--out",
               str(results))
    assert done.returncode == 0, done.stderr
    assert WARNING.search(done.stderr), done.stderr
    report = (results / "REPORT.md").read_text(encoding="utf-8")
    section = report.split("## Robot file audit", 1)[1].split("\n## ", 1)[0]
    assert WARNING.search(section), report


def test_campaign_prints_them_before_any_run(bare: tuple[Path, Path],
                                            caplog: pytest.LogCaptureFixture) -> None:
    """`wmr campaign` resolves its robot (and prints them) before the cluster starts; in
    this process the audit's logger is pytest's, so the record is read there."""
    from runtime.commands.campaign import resolve_campaign

    _, out = bare
    with caplog.at_level(logging.WARNING, logger="wmr.audit"):
        resolve_campaign(None, out / "bare_caster", 1)
    lines = [r.getMessage() for r in caplog.records if r.name == "wmr.audit"]
    assert len(lines) == 2 and WARNING.search(lines[0]), lines
    assert lines[0].startswith(f"warning: {(out / 'bare_caster').resolve()}: ")


def test_a_lumped_files_warning_is_printed_once(tmp_path: Path) -> None:
    """A [physical] file runs on the paper model's code: its warnings are its own, printed
    once (the runtime's reading of the file and the command floor do not both print)."""
    robot = tmp_path / "my_robot.toml"
    robot.write_text(PHYSICAL, encoding="utf-8")
    done = wmr("stability", "--robot", str(robot), "--json", "--no-measure", "--no-delay",
               "--no-saturation")
    assert done.returncode == 0, done.stderr
    lines = [x for x in done.stderr.splitlines() if x.startswith("warning: ")]
    assert len(lines) == 1 and "field 'physical.Iw'" in lines[0], done.stderr


def test_a_clean_robot_prints_nothing() -> None:
    done = wmr("stability", "--json", "--no-measure", "--no-delay", "--no-saturation")
    assert done.returncode == 0, done.stderr
    assert "warning:" not in done.stderr
    assert load_robot_code("").audit_warnings == ()


def audit_section_of(text: str, heading: str = "## Robot file audit") -> str:
    """The text under the audit's heading, up to the next heading."""
    assert heading in text, text[:2000]
    return text.split(heading, 1)[1].split("\n## ", 1)[0]


def test_faults_writes_them_into_faults_md(bare: tuple[Path, Path], tmp_path: Path) -> None:
    robot, out = bare
    experiment = tmp_path / "short.toml"
    experiment.write_text('[paths]\ncircle_duration = 3.0\n[[fault]]\nkind = "repeated-sample"'
                          '\nstart = 2.5\n')
    results = tmp_path / "faults"
    done = wmr("faults", "--robot", str(robot), "--generated", str(out), "--experiment",
               str(experiment), "--out", str(results))
    assert done.returncode == 0, done.stderr
    section = audit_section_of((results / "FAULTS.md").read_text(encoding="utf-8"))
    assert WARNING.search(section) and section.count("\n- ") == 2, section


def test_a_campaigns_summary_md_carries_them(bare: tuple[Path, Path], tmp_path: Path) -> None:
    """One 3 s run, in this process (the function a Dask task runs), then the report."""
    import json

    from runtime.campaign import store
    from runtime.campaign.runner import run_chunk
    from runtime.commands.campaign import report, resolve_campaign

    _, out = bare
    spec = tmp_path / "campaign.toml"
    spec.write_text('seed = 1\ncontrollers = ["tdc"]\nduration = 3.0\n[vary."controller.eps"]'
                    '\nmin = 0.05\nmax = 0.1\n')
    campaign, tgt = resolve_campaign(spec, out / "bare_caster", 1)
    folder = tmp_path / "campaign"
    folder.mkdir()
    store.prepare(folder, campaign)
    payload = json.dumps(campaign.to_payload(), sort_keys=True)
    store.write_part(folder, run_chunk(payload, range(1)), store.schema(campaign))
    report(folder, campaign, tgt, "this process", plots=False)
    section = audit_section_of((folder / "summary.md").read_text(encoding="utf-8"))
    assert WARNING.search(section) and section.count("\n- ") == 2, section


def test_crosscheck_reports_them(bare: tuple[Path, Path]) -> None:
    """The quick crosscheck of the robot's generated code: its report opens with them."""
    _, out = bare
    done = wmr("crosscheck", "--robot", str(out / "bare_caster"), "--quick")
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr
    title = done.stdout.index("Robot bare_caster")
    section = done.stdout[title:].split("Robot file audit", 1)[1].split("\n\n", 3)
    assert WARNING.search(section[2]) and section[2].count("- ") == 2, section
    # a robot without warnings has no such section: tests/generated/test_crosscheck.py, on
    # the report of every shipped robot (the same rendering this command prints)
