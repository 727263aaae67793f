"""A robot's run-time parameters as every layer names them, declared once per robot.

A :class:`ParameterInfo` is what a parameter is called and measured in: its key (Python,
robot files, the generated ``PARAMS``), its meaning, its unit and its C spelling. A robot
declares one table of them (Drishti: ``modeling.robots.drishti.parameters``; a described
robot: ``modeling.robot_model.described_model``), and ``modeling.robot_model.Parameter``
pairs each with the model's symbol. The C structs' field names and comments, the generated
Python's ``C_FIELD_NAMES``, the robot files' error messages and the MODEL.md tables read it
from there. No SymPy: the runtime reads robot files with these tables.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass


@dataclass(frozen=True)
class ParameterInfo:
    """One parameter: ``key``, what it is (``doc``), its ``unit`` ("" when none is stated),
    ``c_name`` where the key cannot be a C struct field ("" = the key), and a ``remark``
    shown after the unit (when it matters, not what it is)."""

    key: str
    doc: str
    unit: str = ""
    c_name: str = ""
    remark: str = ""

    @property
    def c_field(self) -> str:
        """The C struct field: ``c_name``, else the key."""
        return self.c_name or self.key

    @property
    def with_unit(self) -> str:
        """``doc [unit]``, as robot files' error messages name a field."""
        return f"{self.doc} [{self.unit}]" if self.unit else self.doc

    @property
    def comment(self) -> str:
        """``doc [unit] (remark; C field c)``: one line for generated code and reports."""
        notes = [self.remark] if self.remark else []
        if self.c_field != self.key:
            notes.append(f"C field {self.c_field}")
        return self.with_unit + (f" ({'; '.join(notes)})" if notes else "")


def c_field_names(params: Iterable[ParameterInfo]) -> dict[str, str]:
    """Key → C struct field, for the parameters whose C spelling differs from their key."""
    return {p.key: p.c_field for p in params if p.c_field != p.key}
