"""Robot description files: Drishti, the physical form, and every kind of bad input.

Each bad input must raise RobotFileError (a ValueError) whose message names the offending
field (or table), and for files on disk the file.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import pytest

from modeling.robot_file import RobotFileError, load_robot, parse_robot

PAPER = {"m": 36.0, "I": 5.72, "K": 0.34, "Iw": 0.07, "r": 0.096, "b": 0.414, "d": 0.12}
PHYSICAL = {"m_P": 30.0, "I_P": 2.0, "x_P": 0.05, "y_P": -0.02, "m_w": 3.0, "Iw": 0.07,
            "Im": 0.04, "r": 0.096, "b": 0.414, "d": 0.12}


def toml(table: str, values: dict[str, Any], extra: str = "", name: str = "test") -> str:
    lines = [f'name = "{name}"', extra, f"[{table}]"]
    lines += [f"{k} = {v}" for k, v in values.items()]
    return "\n".join(lines) + "\n"


def with_(base: dict[str, Any], **changes: Any) -> dict[str, Any]:
    out = dict(base)
    out.update(changes)
    return out


def without(base: dict[str, Any], key: str) -> dict[str, Any]:
    return {k: v for k, v in base.items() if k != key}


# ---------------------------------------------------------------------------------------
# good files
# ---------------------------------------------------------------------------------------
def test_drishti_default_has_the_papers_values() -> None:
    robot = load_robot()
    assert robot.name == "drishti"
    assert robot.lumped == PAPER  # exact: the file holds the printed decimals
    assert robot.physical is None
    assert robot.K_lat == 0.0


def test_lumped_file_round_trip(tmp_path: Path) -> None:
    path = tmp_path / "mine.toml"
    path.write_text(toml("lumped", with_(PAPER, K=-0.5, d=0.0)).replace('name = "test"\n', ""))
    robot = load_robot(path)
    assert robot.name == "mine"  # defaults to the file's stem
    assert robot.lumped == with_(PAPER, K=-0.5, d=0.0)  # K may be negative, d zero
    assert robot.source == str(path)


def test_integer_values_are_accepted_as_floats() -> None:
    robot = parse_robot(toml("lumped", with_(PAPER, m=36)))
    assert robot.lumped["m"] == 36.0 and isinstance(robot.lumped["m"], float)


def test_physical_form_derives_lumped_parameters() -> None:
    """m = m_P + 2 m_w, I = I_P + 2 I_m + m_P((d − x_P)² + y_P²) + 2 m_w(b²/4 + d²),
    K = m_P (d − x_P) + 2 m_w d, K_lat = m_P y_P; I_w, r, b, d are passed through."""
    robot = parse_robot(toml("physical", PHYSICAL))
    v = PHYSICAL
    m = v["m_P"] + 2 * v["m_w"]
    i = (v["I_P"] + 2 * v["Im"] + v["m_P"] * ((v["d"] - v["x_P"]) ** 2 + v["y_P"] ** 2)
         + 2 * v["m_w"] * (v["b"] ** 2 / 4 + v["d"] ** 2))
    k = v["m_P"] * (v["d"] - v["x_P"]) + 2 * v["m_w"] * v["d"]
    expected = {"m": m, "I": i, "K": k, "Iw": v["Iw"], "r": v["r"], "b": v["b"], "d": v["d"]}
    assert robot.lumped.keys() == expected.keys()
    for key, value in expected.items():
        assert math.isclose(robot.lumped[key], value, rel_tol=1e-14), key
    assert math.isclose(robot.K_lat, v["m_P"] * v["y_P"], rel_tol=1e-14)
    assert robot.physical == PHYSICAL


def test_physical_form_reproduces_the_papers_relation() -> None:
    """With the platform's centre of mass on the axle (x_P = y_P = 0) the paper's
    I = I_P + m_P d² + 2 m_w (b²/4 + d²) + 2 I_m holds and K = m d, K_lat = 0."""
    v = with_(PHYSICAL, x_P=0.0, y_P=0.0)
    robot = parse_robot(toml("physical", v))
    m = v["m_P"] + 2 * v["m_w"]
    i = (v["I_P"] + v["m_P"] * v["d"] ** 2
         + 2 * v["m_w"] * (v["b"] ** 2 / 4 + v["d"] ** 2) + 2 * v["Im"])
    assert math.isclose(robot.lumped["m"], m, rel_tol=1e-14)
    assert math.isclose(robot.lumped["I"], i, rel_tol=1e-14)
    assert math.isclose(robot.lumped["K"], m * v["d"], rel_tol=1e-14)
    assert robot.K_lat == 0.0


# ---------------------------------------------------------------------------------------
# bad files: (text, words the message must contain)
# ---------------------------------------------------------------------------------------
BAD: list[tuple[str, str, tuple[str, ...]]] = [
    ("missing lumped field", toml("lumped", without(PAPER, "Iw")), ("'Iw'", "missing")),
    ("missing physical field", toml("physical", without(PHYSICAL, "y_P")), ("'y_P'", "missing")),
    ("unknown lumped field", toml("lumped", with_(PAPER, mass=1.0)), ("'mass'", "unknown")),
    ("unknown physical field", toml("physical", with_(PHYSICAL, K=0.3)), ("'K'", "unknown")),
    ("unknown top-level key", toml("lumped", PAPER, extra="colour = 'red'"),
     ("'colour'", "unknown")),
    ("string", toml("lumped", with_(PAPER, m='"36"')), ("'lumped.m'", "number")),
    ("array", toml("lumped", with_(PAPER, r="[0.1]")), ("'lumped.r'", "number")),
    ("bool", toml("lumped", with_(PAPER, b="true")), ("'lumped.b'", "number")),
    ("NaN", toml("lumped", with_(PAPER, I="nan")), ("'lumped.I'", "finite")),
    ("Inf", toml("lumped", with_(PAPER, K="inf")), ("'lumped.K'", "finite")),
    ("-Inf", toml("physical", with_(PHYSICAL, x_P="-inf")), ("'physical.x_P'", "finite")),
    ("overflow to inf", toml("lumped", with_(PAPER, Iw="1e400")), ("'lumped.Iw'", "finite")),
    ("zero m", toml("lumped", with_(PAPER, m=0.0)), ("'lumped.m'", "positive")),
    ("negative m", toml("lumped", with_(PAPER, m=-36.0)), ("'lumped.m'", "positive")),
    ("zero I", toml("lumped", with_(PAPER, I=0)), ("'lumped.I'", "positive")),
    ("negative I", toml("lumped", with_(PAPER, I=-5.72)), ("'lumped.I'", "positive")),
    ("zero Iw", toml("lumped", with_(PAPER, Iw=0.0)), ("'lumped.Iw'", "positive")),
    ("negative Iw", toml("lumped", with_(PAPER, Iw=-0.07)), ("'lumped.Iw'", "positive")),
    ("zero r", toml("lumped", with_(PAPER, r=0.0)), ("'lumped.r'", "positive")),
    ("negative r", toml("lumped", with_(PAPER, r=-0.096)), ("'lumped.r'", "positive")),
    ("zero b", toml("lumped", with_(PAPER, b=0.0)), ("'lumped.b'", "positive")),
    ("negative b", toml("lumped", with_(PAPER, b=-0.414)), ("'lumped.b'", "positive")),
    ("negative d", toml("lumped", with_(PAPER, d=-0.12)), ("'lumped.d'", "non-negative")),
    ("zero m_P", toml("physical", with_(PHYSICAL, m_P=0.0)), ("'physical.m_P'", "positive")),
    ("zero m_w", toml("physical", with_(PHYSICAL, m_w=0.0)), ("'physical.m_w'", "positive")),
    ("negative I_P", toml("physical", with_(PHYSICAL, I_P=-1.0)), ("'physical.I_P'", "positive")),
    ("negative Im", toml("physical", with_(PHYSICAL, Im=-0.01)),
     ("'physical.Im'", "non-negative")),
    ("negative physical d", toml("physical", with_(PHYSICAL, d=-0.1)),
     ("'physical.d'", "non-negative")),
    ("both tables", toml("lumped", PAPER) + toml("physical", PHYSICAL).split("\n", 1)[1],
     ("[lumped]", "[physical]", "exactly one")),
    ("neither table", 'name = "x"\n', ("[lumped]", "[physical]", "exactly one")),
    ("lumped not a table", 'name = "x"\nlumped = 3\n', ("[lumped]", "table")),
    ("empty name", toml("lumped", PAPER, name=""), ("'name'",)),
    ("name not a string", toml("lumped", PAPER).replace('name = "test"', "name = 3"),
     ("'name'",)),
    ("invalid TOML", "name = \"x\"\n[lumped\nm = 36\n", ("not valid TOML",)),
    ("invalid TOML value", toml("lumped", with_(PAPER, m="36 kg")), ("not valid TOML",)),
    ("I equal to K^2/m", toml("lumped", with_(PAPER, K=6.0, I=1.0)), ("'I'", "K")),
    ("I below K^2/m", toml("lumped", with_(PAPER, K=-2.0, I=0.1)), ("'I'", "positive definite")),
]


@pytest.mark.parametrize(("text", "words"), [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_input_is_rejected_naming_the_field(text: str, words: tuple[str, ...]) -> None:
    with pytest.raises(RobotFileError) as info:
        parse_robot(text, "bad.toml")
    message = str(info.value)
    assert message.startswith("bad.toml: "), message
    for word in words:
        assert word in message, (word, message)


def test_i_equal_to_k_squared_over_m_is_exactly_the_boundary() -> None:
    """I = K²/m exactly (36 · 1 = 6²) is rejected; a hair above is accepted."""
    with pytest.raises(RobotFileError, match="'I'"):
        parse_robot(toml("lumped", with_(PAPER, K=6.0, I=1.0)))
    parse_robot(toml("lumped", with_(PAPER, K=6.0, I=1.0 + 1e-12)))


def test_bad_file_on_disk_names_the_file(tmp_path: Path) -> None:
    path = tmp_path / "broken.toml"
    path.write_text(toml("lumped", with_(PAPER, r="false")))
    with pytest.raises(RobotFileError) as info:
        load_robot(path)
    assert str(path) in str(info.value) and "'lumped.r'" in str(info.value)


def test_missing_file(tmp_path: Path) -> None:
    path = tmp_path / "nowhere.toml"
    with pytest.raises(RobotFileError) as info:
        load_robot(path)
    assert str(path) in str(info.value) and "not found" in str(info.value)


def test_undecodable_file(tmp_path: Path) -> None:
    path = tmp_path / "latin1.toml"
    path.write_bytes(b'name = "caf\xe9"\n')
    with pytest.raises(RobotFileError) as info:
        load_robot(path)
    assert str(path) in str(info.value)


def test_errors_are_value_errors() -> None:
    assert issubclass(RobotFileError, ValueError)
