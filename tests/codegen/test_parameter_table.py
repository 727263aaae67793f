"""One parameter table per robot: key, meaning, unit and C spelling are declared once
(``modeling.parameter_table.ParameterInfo``; Drishti's in ``modeling.robots.drishti.parameters``)
and every layer reads them from there: the generated C structs (members and comments),
the generated Python's ``C_FIELD_NAMES``, Drishti's MODEL.md and its robot-file errors."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import sympy as sp

from codegen.backends.c.config import CConfig
from codegen.backends.c.files import cdef
from codegen.spec import Argument, Field, FunctionSpec
from modeling.parameter_table import ParameterInfo, c_field_names
from modeling.robot_file import RobotFileError, parse_robot
from modeling.robots.drishti.parameters import K_LAT, LUMPED, PHYSICAL
from runtime.bindings.generated import GENERATED
from runtime.bindings.robots import code_in, generated_robots

PLANT = (*LUMPED[:3], K_LAT, *LUMPED[3:])  # wmr_plant_params_t's order


def _members(header: str, ctype: str) -> list[tuple[str, str]]:
    """(member, comment) of ``typedef struct {...} ctype;`` in a generated header (a comment
    wrapped over several lines is joined)."""
    body = re.search(r"typedef struct \{\n([^{}]*)\n\} " + ctype + ";", header)
    assert body is not None, ctype
    found = re.findall(r"^\s+\w+ (\w+); /\* (.*?) \*/", body.group(1), re.S | re.M)
    return [(name, " ".join(comment.split())) for name, comment in found]


def test_a_parameter_is_described_from_its_declaration() -> None:
    assert ParameterInfo("I", "yaw inertia about C", "kg m^2", c_name="Iz").comment == (
        "yaw inertia about C [kg m^2] (C field Iz)")
    assert K_LAT.comment == "first moment of mass left of C [kg m] (off-axis payload)"
    assert ParameterInfo("x", "a", "m", c_name="y", remark="r").comment == "a [m] (r; C field y)"
    assert ParameterInfo("J_x", "m_1 + m_2").comment == "m_1 + m_2"  # no unit stated
    assert ParameterInfo("r", "wheel radius", "m").with_unit == "wheel radius [m]"
    assert c_field_names(PLANT) == {"I": "Iz"}


@pytest.mark.parametrize("folder", generated_robots(GENERATED), ids=lambda p: p.name)
def test_generated_c_and_python_spell_every_parameter_alike(folder: Path) -> None:
    """For every generated robot: the C params struct's members are the generated Python's
    keys spelled by its ``C_FIELD_NAMES``, in the same order."""
    code = code_in(folder)
    header = (folder / "c" / f"{code.prefix}_types.h").read_text(encoding="utf-8")
    members = [name for name, _ in _members(header, f"{code.prefix}_params_t")]
    names = code.controllers.C_FIELD_NAMES
    assert members == [names.get(k, k) for k in code.robot.PARAMS]
    assert set(names) <= set(code.robot.PLANT_PARAMS)  # no rename of a parameter it lacks


def test_drishti_generated_code_reads_the_table() -> None:
    code = code_in(GENERATED)
    header = (GENERATED / "c" / "wmr_types.h").read_text(encoding="utf-8")
    assert _members(header, "wmr_params_t") == [(p.c_field, p.comment) for p in LUMPED]
    assert _members(header, "wmr_plant_params_t") == [(p.c_field, p.comment) for p in PLANT]
    assert c_field_names(PLANT) == code.controllers.C_FIELD_NAMES
    assert tuple(code.robot.PARAMS) == tuple(p.key for p in LUMPED)
    assert tuple(code.robot.PLANT_PARAMS) == tuple(p.key for p in PLANT)


def test_drishti_model_report_reads_the_table() -> None:
    rows = {
        cells[0]: cells
        for line in (GENERATED / "MODEL.md").read_text(encoding="utf-8").splitlines()
        if line.startswith("| ")
        and len(cells := [c.strip() for c in line.strip().strip("|").split("|")]) == 5
    }
    for p in LUMPED:
        assert rows[p.key][2] == p.unit.replace("^2", "²"), p.key
        assert rows[p.key][3] == p.doc, p.key


DRISHTI_LUMPED = {"m": 36.0, "I": 5.72, "K": 0.34, "Iw": 0.07, "r": 0.096, "b": 0.414,
                  "d": 0.12}
DRISHTI_PHYSICAL = {"m_P": 30.0, "I_P": 2.0, "x_P": 0.0, "y_P": 0.0, "m_w": 3.0, "Iw": 0.07,
                    "Im": 0.04, "r": 0.096, "b": 0.414, "d": 0.12}


@pytest.mark.parametrize(
    ("section", "info"),
    [("lumped", p) for p in LUMPED] + [("physical", p) for p in PHYSICAL],
    ids=lambda x: x if isinstance(x, str) else x.key,
)
def test_a_missing_field_is_named_with_its_meaning_and_unit(
    section: str, info: ParameterInfo
) -> None:
    values = DRISHTI_LUMPED if section == "lumped" else DRISHTI_PHYSICAL
    body = "\n".join(f"{k} = {v!r}" for k, v in values.items() if k != info.key)
    with pytest.raises(RobotFileError) as err:
        parse_robot(f"[{section}]\n{body}\n", "x.toml")
    assert str(err.value) == (
        f"x.toml: missing field '{info.key}' in [{section}] ({info.doc} [{info.unit}])"
    )


def test_the_c_backend_takes_the_declared_spelling_and_refuses_complex_h_names() -> None:
    """A struct member is the field's C spelling; one spelled like a macro of <complex.h>
    (Drishti's I without its declared Iz) is refused, not silently renamed."""
    s = sp.Symbol("I", real=True)

    def spec(field: Field) -> FunctionSpec:
        args = (Argument("p", "params", fields=(field,)),)
        out = (Argument("y", "array", exprs=(2 * s,)),)
        return FunctionSpec("f", "", inputs=args, outputs=out)

    assert "Iz;" in cdef([spec(Field("I", (s,), c_name="Iz"))], CConfig())
    with pytest.raises(ValueError, match=r"field names \['I'\] are not usable in C"):
        cdef([spec(Field("I", (s,)))], CConfig())
