"""Drishti's robot files: a ``[lumped]`` or ``[physical]`` file as a :class:`Robot`.

The format and its checks are ``parameters`` (beside this file). A ``[lumped]`` file is
read without SymPy; a ``[physical]`` file's lumped parameters follow from the lumped
relations ``model`` derives (imported in :func:`lumped_from_physical` only). Every error
names the file and the offending field; nothing is half-loaded.
``modeling.robot_file`` dispatches a robot file here or to ``modeling.description``.
"""

from __future__ import annotations

from pathlib import Path

from modeling.audit import audit_lumped, audit_physical
from modeling.contact_loads import checked_supports
from modeling.planar_robot import from_lumped
from modeling.robot_io import Robot, read_robot_text, text_digest
from modeling.robots.drishti.parameters import (
    RobotTables,
    check_lumped,
    packaged_text,
    read_tables,
)


def lumped_from_physical(phys: dict[str, float]) -> tuple[dict[str, float], float]:
    """m, I, K (and K_lat) from the physical parameters via the derived lumped relations
    (SymPy is imported here, not at module level: a [lumped] file is read without it)."""
    import sympy as sp

    from modeling.robots.drishti import model as wmr

    rel = wmr.lumped_relations(wmr.physical_bodies())
    values = {
        wmr.m_P: phys["m_P"],
        wmr.I_P: phys["I_P"],
        wmr.x_P: phys["x_P"],
        wmr.y_P: phys["y_P"],
        wmr.m_w: phys["m_w"],
        wmr.I_m: phys["Im"],
        wmr.b: phys["b"],
        wmr.d: phys["d"],
    }
    ev = {str(k): float(sp.N(v.subs(values))) for k, v in rel.items()}
    lumped = {
        "m": ev["m"],
        "I": ev["I"],
        "K": ev["K"],
        "Iw": phys["Iw"],
        "r": phys["r"],
        "b": phys["b"],
        "d": phys["d"],
    }
    return lumped, ev["K_lat"]


def parse_robot(text: str, where: str = "<string>") -> Robot:
    """The robot of a ``[lumped]`` or ``[physical]`` file's text; ``RobotFileError`` names
    ``where`` and the field. The physics audit (``modeling.audit``) runs first: an
    implausible file is refused before any work, its warnings go into ``Robot.warnings``."""
    return robot_of(read_tables(text, where), text, where)


def robot_of(tables: RobotTables, text: str, where: str) -> Robot:
    """The robot of a ``[lumped]``/``[physical]`` file's checked tables (``read_tables`` or
    ``tables_of``) and its ``text`` (for the digest); see :func:`parse_robot`."""
    if tables.lumped is not None:
        warnings = audit_lumped(where, tables.lumped)
        robot = Robot(tables.name, tables.lumped, source=where, digest=text_digest(text),
                      warnings=warnings, kind="lumped", supports=tables.supports)
    else:
        assert tables.physical is not None  # read_tables gives exactly one table
        warnings = audit_physical(where, tables.physical)
        lumped, k_lat = lumped_from_physical(tables.physical)
        check_lumped(where, lumped, k_lat)
        robot = Robot(tables.name, lumped, tables.physical, k_lat, source=where,
                      digest=text_digest(text), warnings=warnings, kind="physical",
                      supports=tables.supports)
    # where it stands: the stated supports (or the default) under its numbers
    checked_supports(from_lumped(robot.name, robot.plant_values(), robot.supports), where)
    return robot


def load_robot(path: str | Path | None = None) -> Robot:
    """Load a robot file; ``None`` loads the packaged default, Drishti."""
    if path is None:
        return parse_robot(*packaged_text())
    return parse_robot(read_robot_text(path), str(path))
