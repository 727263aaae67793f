"""The corpus of public descriptions (tests/robots/public/, sources.toml): each real file,
as published, is imported or refused with its reason.

* An import: the robot's total mass (bodies and wheels) is the sum of the file's own link
  masses, computed here from the file (expanded by xacro where it is a template) without
  the importer, and its track (the distance between its driven wheels) the file's.
* A refusal: one line naming the file and the reason recorded in sources.toml.
* The imported ones go on through ``wmr model``, ``wmr stability`` and a short ``wmr
  reproduce`` in tests/robot_files/test_public_pipeline.py.
* The corpus: at least 20 files, each with its repository, path, 40-digit commit and a
  licence that allows redistribution, all in README.md's table; no mesh files.
"""

from __future__ import annotations

import re
import tomllib
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pytest

from modeling.importers import import_robot
from modeling.importers.expand import expand, uses_xacro
from modeling.robot_io import RobotFileError

PUBLIC = Path(__file__).resolve().parents[1] / "robots" / "public"
ROBOTS: list[dict[str, Any]] = tomllib.loads((PUBLIC / "sources.toml").read_text())["robot"]
FREE = ("Apache-2.0", "BSD-3-Clause", "MIT")


def own_mass(path: Path) -> float:
    """The sum of the file's link masses, read from its (expanded) XML."""
    text = path.read_text()
    if uses_xacro(path, text):
        text, _ = expand(path)
    root = ET.fromstring(text)
    return sum(float(m.get("value", "0")) for m in root.findall("link/inertial/mass"))


@pytest.mark.parametrize("entry", ROBOTS, ids=[r["file"] for r in ROBOTS])
def test_public_robot(entry: dict[str, Any]) -> None:
    path = PUBLIC / entry["file"]
    if entry["outcome"] == "refused":
        with pytest.raises(RobotFileError) as exc:
            import_robot(path)
        message = str(exc.value)
        assert "\n" not in message and message.startswith(f"{path}: ")
        assert entry["reason"] in message, message
        return
    desc = import_robot(path).description
    mass = sum(float(b.mass) for b in desc.bodies) + sum(float(w.mass) for w in desc.wheels)
    assert mass == pytest.approx(entry["mass"], rel=1e-9)
    assert mass == pytest.approx(own_mass(path), rel=1e-9)
    driven = [float(w.position[1]) for w in desc.wheels if w.driven]
    assert len(driven) == 2 and abs(driven[0] - driven[1]) == pytest.approx(entry["track"],
                                                                             rel=1e-9)


def test_the_corpus_is_recorded() -> None:
    assert len(ROBOTS) >= 20
    table = (PUBLIC / "README.md").read_text()
    for entry in ROBOTS:
        assert (PUBLIC / entry["file"]).is_file(), entry["file"]
        assert re.fullmatch(r"[0-9a-f]{40}", entry["commit"]), entry["file"]
        assert entry["licence"].startswith(FREE), entry["file"]
        assert entry["repository"].count("/") == 1 and entry["path"], entry["file"]
        assert f"`{entry['file']}`" in table, entry["file"]
        assert entry["outcome"] in ("imported", "refused")
    meshes = [p for p in PUBLIC.rglob("*") if p.suffix.lower() in (".stl", ".dae", ".obj")]
    assert meshes == []
