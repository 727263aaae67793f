"""Supports as a robot-file field (``[[support]]``, ``modeling.supports``): every kind of
robot file states where it stands; the one load model, the MJCF and the runtime's layout
read the stated positions; a file without the field stands where the exporter always put
it (the default); bad positions get one line naming the file and the field.

The engine check: the loads the load model states for a stated caster are the ones MuJoCo
carries at rest (within the issue's 2 %), so the field is realised, not only read.
About 3 s on one core.
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest

from modeling.contact_loads import support_loads
from modeling.mjcf_command import main as mjcf_main
from modeling.mjcf_command import planar_robot
from modeling.mjcf_export import GRAVITY, ContactSettings, mjcf
from modeling.planar_robot import PlanarSupport
from modeling.robot_io import RobotFileError
from modeling.supports import default_supports, robot_supports
from runtime.bindings.generated import load_robot_code
from runtime.setting.layout import robot_layout

ROOT = Path(__file__).resolve().parents[2]
DRISHTI = (ROOT / "modeling" / "robots" / "drishti" / "drishti.toml").read_text()
TRAILER = (ROOT / "modeling" / "robots" / "trailer" / "trailer.toml").read_text()
LOAD_RTOL = 0.02


def _file(tmp_path: Path, text: str, name: str = "bot.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def _engine_loads(xml: str) -> dict[str, float]:
    """The normal force on each contact geom after 0.5 s at rest (tyre_ prefix dropped)."""
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    mujoco.mj_step(model, data, nstep=500)
    out: dict[str, float] = {}
    force = np.zeros(6)
    for i in range(data.ncon):
        c = data.contact[i]
        mujoco.mj_contactForce(model, data, i, force)
        name = (model.geom(c.geom[1]).name or model.geom(c.geom[0]).name).removeprefix("tyre_")
        out[name] = out.get(name, 0.0) + float(force[0])
    return out


def test_a_file_without_supports_stands_on_the_default_and_stating_it_changes_nothing(
        tmp_path: Path) -> None:
    robot = planar_robot(_file(tmp_path, DRISHTI))
    assert robot.supports is None
    default = default_supports(robot)
    # the documented default: across the axle (x = -d = -0.12) at +-0.2211 m
    reach = 2 * (0.12 - 0.34 / 36.0)  # twice the centre of mass's distance from the axle
    assert [(s.name, *s.position) for s in default] == [
        ("support_rear", pytest.approx(-0.12 - reach), 0.0),
        ("support_front", pytest.approx(-0.12 + reach), 0.0)]
    stated = DRISHTI + "".join(
        f'\n[[support]]\nname = "{s.name}"\nposition = [{s.position[0]!r}, '
        f"{s.position[1]!r}]\nradius = {s.radius!r}\n" for s in default)
    same = planar_robot(_file(tmp_path, stated, "stated.toml"))
    assert same.supports == default
    assert mjcf(same) == mjcf(robot)
    assert support_loads(same) == support_loads(robot)


def test_a_stated_caster_moves_the_loads_and_the_engine_carries_them(tmp_path: Path) -> None:
    """Drishti on one front caster 0.25 m ahead of C (body frame: the platform's, origin
    C): the load model's split is the engine's within 2 %, and it is not the default's."""
    text = DRISHTI + '\n[[support]]\nname = "caster"\nposition = [0.25, 0.0]\n'
    robot = planar_robot(_file(tmp_path, text))
    assert robot_supports(robot) == (PlanarSupport("caster", "platform", (0.25, 0.0), 0.048),)
    stated = support_loads(robot)
    assert set(stated.loads) == {"right", "left", "caster"} and not stated.lifted
    # statics by hand: the centre of mass 0.0094 m behind C, the axle 0.12 m behind it
    weight = GRAVITY * robot.total_mass()
    com = -0.34 / 36.0
    assert stated["caster"] == pytest.approx(weight * (com + 0.12) / 0.37, rel=1e-9)
    measured = _engine_loads(mjcf(robot))
    assert set(measured) == set(stated.loads)
    for contact, load in stated.loads.items():
        assert abs(measured[contact] - load) <= LOAD_RTOL * load, (contact, load, measured)


def test_a_bodies_file_states_a_support_on_a_trailing_body(tmp_path: Path) -> None:
    """The trailer with a skid under its cart's tail: it is on the cart body in the MJCF,
    the load model puts load on it, and the engine carries the split within 2 %."""
    text = TRAILER + ('\n[[support]]\nname = "skid"\nbody = "cart"\n'
                      "position = [-0.2, 0.0]\nradius = 0.03\n")
    robot = planar_robot(_file(tmp_path, text))
    xml = mjcf(robot)
    model = mujoco.MjModel.from_xml_string(xml)
    assert model.body(int(model.geom("skid").bodyid[0])).name == "cart"
    stated = support_loads(robot)
    assert stated["skid"] > 10.0
    measured = _engine_loads(xml)
    for contact, load in stated.loads.items():
        assert abs(measured[contact] - load) <= LOAD_RTOL * load, (contact, load, measured)


@pytest.mark.parametrize(("extra", "message"), [
    ('[[support]]\nname = "c"\nbody = "cart"\nposition = [0.3, 0.0]\n',
     "field 'support[0].body' names unknown body 'cart'"),
    ('[[support]]\nname = "c"\nposition = [0.3]\n', "field 'support[0].position' must be"),
    ('[[support]]\nname = "c"\nposition = [0.3, 0.0]\nradius = 0\n',
     "field 'support[0].radius' must be a positive"),
    ('[[support]]\nname = "c"\nposition = [300.0, 0.0]\n',
     "field 'support[0].position' = [300, 0] puts 'c'"),
    ('[[support]]\nname = "left"\nposition = [0.3, 0.0]\n',
     "field 'support[0].name': 'left' already names a wheel"),
    ('[[support]]\nname = "c"\nposition = [0.3, 0.0]\nheight = 1\n',
     "unknown field 'support[0].height'"),
    # on the axle line: every contact on one line, the load split singular
    ('[[support]]\nname = "c"\nposition = [-0.12, 0.5]\n', "every contact (right, left, c) "
     "is on one line"),
    # all behind the axle: the weight's moment tips the robot forward off them
    ('[[support]]\nname = "c"\nposition = [-0.4, 0.1]\n', "it tips over"),
    ("support = []\n", "every contact (right, left) is on one line"),
])
def test_a_bad_support_is_one_line_naming_the_field(tmp_path: Path, extra: str,
                                                    message: str) -> None:
    lines = DRISHTI.splitlines()
    at = lines.index("[lumped]")  # a top-level key must come before the first table
    text = "\n".join(lines[:at] + ([extra] if extra.startswith("support =") else [])
                     + lines[at:]) + ("\n" + extra if not extra.startswith("support =") else "")
    path = _file(tmp_path, text)
    with pytest.raises(RobotFileError) as err:
        planar_robot(path)
    assert message in str(err.value) and "\n" not in str(err.value), str(err.value)
    assert str(err.value).startswith(str(path))


def test_wmr_mjcf_refuses_a_bad_support_and_writes_nothing(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = _file(tmp_path, DRISHTI + '\n[[support]]\nname = "c"\nposition = [-0.12, 0.5]\n')
    out = tmp_path / "bot.xml"
    assert mjcf_main(["--robot", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "on one line" in err
    assert not out.exists()


def test_the_runtime_layout_stands_on_the_generated_supports(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """robot.py's ``SUPPORTS`` (the file's stated supports) reach the engine's robot and
    its loads; None (not stated) keeps the default."""
    code = load_robot_code("")
    assert code.supports is None
    default = robot_layout(code, code.plant_defaults)
    assert [s.name for s in robot_supports(default)] == ["support_rear", "support_front"]
    monkeypatch.setattr(code.robot, "SUPPORTS", [["caster", "platform", [0.25, 0.0], 0.04]])
    robot = robot_layout(code, code.plant_defaults)
    assert robot_supports(robot) == (PlanarSupport("caster", "platform", (0.25, 0.0), 0.04),)
    assert set(support_loads(robot).loads) == {"right", "left", "caster"}
    assert 'name="caster"' in mjcf(robot, ContactSettings())
