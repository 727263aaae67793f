"""Robot kinds as one table (``modeling.robot_file.KINDS``), issue 44 item 3.

* A copy of Drishti's ``[lumped]`` file with another name and mass is its own robot: it
  goes to ``<out>/<name>/`` with prefix ``<name>_``, the robots already in ``--out``
  (Drishti at the root, the trailers) stay byte-identical, its ``robot.py`` declares its
  kind and that it is the paper's model but not the paper's robot, and its C compiles and
  equals its generated Python (with its own mass).
* Two robots that would write the same path are refused before anything is written, with
  one line naming both and the path (exit 2): two names with one prefix in one command, a
  robot already in ``--out`` under another name, a robot folder inside another's ``c/``.
* The runtime decides "the paper's robot" and "the paper's model" from what ``robot.py``
  declares (``PAPER_ROBOT``, ``PAPER_MODEL``), never from the prefix.
* A command reads and parses the robot file once.
"""

from __future__ import annotations

import pathlib
import shutil
import tomllib
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from generated_code_support import C_FLAGS, GENERATED

from codegen.__main__ import main as model_main
from codegen.output_plan import Placed, folder_collision, shared_path
from modeling.robot_file import (
    KINDS,
    kind_of,
    read_robot_file,
    robot_source,
    shipped_robot_file,
)
from modeling.robot_io import SHIPPED_NAMING, naming_of, packaged_source
from runtime.bindings import cbuild
from runtime.bindings import generated as generated_bindings
from runtime.bindings.generated import RobotCode, load_robot_code
from runtime.bindings.robots import RobotSetup, resolve
from runtime.experiment.settings import Experiment
from runtime.setting.layout import robot_layout
from runtime.setting.robot import Setting

DRISHTI_FILE = shipped_robot_file("drishti")
MASS = 40.0  # Drishti's is 36 kg


def _copy(folder: Path, name: str, mass: float = MASS) -> Path:
    """Drishti's robot file with another name and total mass."""
    text = DRISHTI_FILE.read_text(encoding="utf-8")
    assert 'name = "drishti"' in text and "\nm = 36.0 " in text
    text = text.replace('name = "drishti"', f'name = "{name}"').replace(
        "\nm = 36.0 ", f"\nm = {mass} ")
    path = folder / f"{name}.toml"
    path.write_text(text, encoding="utf-8")
    return path


def _tree(root: Path) -> dict[str, bytes]:
    if not root.exists():
        return {}
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in sorted(root.rglob("*"))
            if p.is_file() and "__pycache__" not in p.parts}


def _counting(monkeypatch: pytest.MonkeyPatch, path: Path) -> dict[str, int]:
    """Count the opens of ``path`` and the TOML parses of its text from now on."""
    counts = {"opened": 0, "parsed": 0}
    target, text = path.resolve(), path.read_text(encoding="utf-8")
    real_open, real_loads = pathlib.Path.open, tomllib.loads

    def opened(self: Path, *args: Any, **kwargs: Any) -> Any:
        if self.resolve() == target:
            counts["opened"] += 1
        return real_open(self, *args, **kwargs)

    def loads(s: str, *args: Any, **kwargs: Any) -> dict[str, Any]:
        if s == text:
            counts["parsed"] += 1
        return real_loads(s, *args, **kwargs)

    monkeypatch.setattr(pathlib.Path, "open", opened)
    monkeypatch.setattr(tomllib, "loads", loads)
    return counts


@pytest.fixture(scope="module")
def mybot(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Any]]:
    """``wmr model --robot mybot.toml --out OUT`` where OUT is a copy of the shipped
    generated/ (Drishti at its root), counting how often the file is read and parsed."""
    tmp = tmp_path_factory.mktemp("kinds")
    robot = _copy(tmp, "mybot")
    out = tmp / "generated"
    shutil.copytree(GENERATED, out, ignore=shutil.ignore_patterns("__pycache__"))
    before = _tree(out)
    with pytest.MonkeyPatch.context() as mp:
        counts = _counting(mp, robot)
        rc = model_main(["--robot", str(robot), "--out", str(out)])
    yield {"rc": rc, "out": out, "before": before, "after": _tree(out), "counts": counts,
           "robot": robot, "tmp": tmp}


def test_a_copied_lumped_file_gets_its_own_folder_and_prefix(mybot: dict[str, Any]) -> None:
    assert mybot["rc"] == 0
    before, after = mybot["before"], mybot["after"]
    new = sorted(set(after) - set(before))
    assert {n for n in before if after.get(n) != before[n]} == set()  # Drishti untouched
    assert new and all(n.startswith("mybot/") for n in new), new
    c_files = {n.split("/")[-1] for n in new if n.startswith("mybot/c/")}
    assert "mybot_model.c" in c_files and "mybot_controller.h" in c_files
    assert not any(f.startswith("wmr_") for f in c_files)
    code = load_robot_code(mybot["out"] / "mybot")
    assert (code.name, code.prefix, code.params["m"]) == ("mybot", "mybot", MASS)
    assert (code.robot.KIND, code.paper_model, code.is_paper_robot) == ("lumped", True, False)


def test_the_copy_compiles_and_its_c_equals_its_python(mybot: dict[str, Any]) -> None:
    assert mybot["rc"] == 0
    folder = mybot["out"] / "mybot"
    code = load_robot_code(folder)
    for float32 in (False, True):  # every .c under the strict flags (example_main too)
        defines = ["-DMYBOT_FLOAT32"] if float32 else []
        objects = [(src, mybot["tmp"] / f"{src.stem}{'_f' if float32 else ''}.o")
                   for src in sorted((folder / "c").glob("*.c"))]
        cbuild.run_compiler([cbuild.gcc_command([src], obj, kind="object",
                                                flags=[*C_FLAGS, *defines],
                                                include_dirs=[folder / "c"])
                             for src, obj in objects], jobs=2, silent=True)
    lib = cbuild.build(c_dir=folder / "c", prefix="mybot")
    params = cbuild.params_struct(lib, code.params, "mybot_params_t",
                                  code.controllers.C_FIELD_NAMES)
    qdd = lib.ffi.new(f"mybot_real_t[{code.nq}]")
    q, qdot, tau = np.array([0.1, -0.2, 0.3, 0.0, 0.0]), np.zeros(5), np.array([1.0, -0.5])
    qdot[:] = code.velocities(q, np.array([2.0, 1.0]), code.params)
    assert lib.lib.mybot_forward_dynamics(params, list(q), list(qdot), list(tau), qdd) == 0
    ref = code.model.forward_dynamics(q, qdot, tau, code.params)
    np.testing.assert_allclose(np.array(list(qdd)), ref, rtol=1e-12, atol=1e-12)
    drishti = load_robot_code("")  # the same model: heavier robot, smaller acceleration
    assert not np.allclose(ref, drishti.model.forward_dynamics(q, qdot, tau, drishti.params))


def test_the_robot_file_is_read_and_parsed_once(mybot: dict[str, Any],
                                                monkeypatch: pytest.MonkeyPatch) -> None:
    assert mybot["counts"] == {"opened": 1, "parsed": 1}  # wmr model --robot
    counts = _counting(monkeypatch, mybot["robot"])
    setup = resolve(mybot["robot"])  # the runtime's --robot: Drishti's code, its numbers
    assert counts == {"opened": 1, "parsed": 1}
    assert (setup.name, setup.nominal["m"]) == ("mybot", MASS)


def _run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    rc = model_main(argv)
    return rc, capsys.readouterr().err


def test_a_robot_colliding_with_one_in_out_is_refused_before_writing(
        mybot: dict[str, Any], capsys: pytest.CaptureFixture[str]) -> None:
    out = mybot["out"]
    before = _tree(out)
    other = _copy(mybot["tmp"], "MyBot", mass=50.0)  # another name, the same prefix mybot
    rc, err = _run(["--robot", str(other), "--out", str(out)], capsys)
    assert rc == 2 and _tree(out) == before
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: robots ")
    assert "'mybot'" in lines[0] and "'MyBot'" in lines[0]
    assert str(out / "mybot" / "python" / "robot.py") in lines[0]
    # A robot whose folder would be Drishti's c/ folder (name "c", prefix c_).
    inside = _copy(mybot["tmp"], "c")
    rc, err = _run(["--robot", str(inside), "--out", str(out)], capsys)
    assert rc == 2 and _tree(out) == before
    assert "'drishti'" in err and "'c'" in err and str(out / "c" / "python" / "robot.py") in err


def test_two_robots_with_one_prefix_in_one_command_are_refused(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    a, b = _copy(tmp_path, "two-bots"), _copy(tmp_path, "two_bots")
    out = tmp_path / "out"
    rc, err = _run(["--robot", str(a), "--robot", str(b), "--out", str(out)], capsys)
    assert rc == 2 and not out.exists()
    assert len(err.strip().splitlines()) == 1
    assert "'two-bots'" in err and "'two_bots'" in err
    assert str(out / "two_bots" / "python" / "robot.py") in err


def test_regenerating_a_robot_in_place_is_not_a_collision() -> None:
    shipped = [read_robot_file(p) for p in (DRISHTI_FILE, shipped_robot_file("trailer"))]
    placed = [Placed(s.name, s.naming.output_dir, s.where) for s in shipped]
    assert [p.folder for p in placed] == ["", "trailer"]
    assert folder_collision(placed, GENERATED) is None
    clash = folder_collision([Placed("other", "", "x.toml")], GENERATED)
    assert clash is not None and "'drishti'" in clash and "'other'" in clash
    # The rendered paths are checked too, before writing: one path from two robots.
    a, b = Placed("a", "x", "a.toml"), Placed("b", "y", "b.toml")
    assert shared_path([(a, ["x/c/a.c"]), (b, ["y/c/b.c"])], Path("out")) is None
    shared = shared_path([(a, ["x/c/a.c", "z/MODEL.md"]), (b, ["z/MODEL.md"])], Path("out"))
    assert shared is not None and "'a'" in shared and "'b'" in shared and "z/MODEL.md" in shared


def test_kinds_and_names_come_from_the_file_and_the_shipped_table(tmp_path: Path) -> None:
    assert [k.name for k in KINDS] == ["bodies", "physical", "lumped"]
    assert naming_of("drishti", DRISHTI_FILE) == SHIPPED_NAMING["drishti"]
    # Drishti's own file, by any path, is one reading per process (its model's defaults too).
    assert robot_source(DRISHTI_FILE) is robot_source(None) is packaged_source()
    copy = _copy(tmp_path, "drishti")  # Drishti's name, not its file: its own folder
    source = read_robot_file(copy)
    assert (kind_of(source).name, source.naming.prefix, source.naming.output_dir,
            source.naming.paper_robot) == ("lumped", "drishti", "drishti", False)
    trailer = read_robot_file(shipped_robot_file("trailer"))
    assert (kind_of(trailer).name, trailer.naming.prefix) == ("bodies", "trailer")


def _declaring(monkeypatch: pytest.MonkeyPatch, code: RobotCode, **values: Any) -> None:
    for key, value in values.items():
        monkeypatch.setattr(code.robot, key, value)


def _setting(code: RobotCode) -> Setting:
    setup = RobotSetup("drishti", "<test>", code, code.params, code.plant_defaults)
    return Setting(setup, Experiment(), ())


def test_the_runtime_reads_the_declaration_not_the_prefix(
        mybot: dict[str, Any], monkeypatch: pytest.MonkeyPatch) -> None:
    drishti = load_robot_code("")
    assert drishti.prefix == "wmr" and drishti.is_paper_robot and _setting(drishti).is_paper_robot
    # The paper's robot: declared. The same wmr_ code declared otherwise is not it.
    with monkeypatch.context() as mp:
        _declaring(mp, drishti, PAPER_ROBOT=False)
        assert not _setting(drishti).is_paper_robot
        with pytest.raises(ImportError, match="not the paper"):
            generated_bindings.__getattr__("wmr_plant")
    with monkeypatch.context() as mp:  # another prefix, declared the paper's robot
        _declaring(mp, drishti, PREFIX="other")
        assert generated_bindings.__getattr__("wmr_plant").__name__.endswith("wmr_plant")
    # The paper's model, prefix mybot_: its layout follows from its parameters, and a
    # lumped robot file runs on its code.
    code = load_robot_code(mybot["out"] / "mybot")
    assert robot_layout(code, code.plant_defaults).name == "mybot"
    setup = resolve(mybot["robot"], generated=mybot["out"] / "mybot")
    assert setup.code.prefix == "mybot" and setup.nominal["m"] == MASS
    with monkeypatch.context() as mp:  # wmr_ code declared not the paper's model
        _declaring(mp, drishti, PAPER_MODEL=False)
        with pytest.raises(ValueError, match="no LAYOUT"):
            robot_layout(drishti, drishti.plant_defaults)
