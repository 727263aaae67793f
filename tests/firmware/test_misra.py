"""The generated C under cppcheck's MISRA C:2012 addon: exactly the deviations that
docs/STATIC_CHECKS.md lists and justifies, as many findings as it says, in double and in
float32; and the clang exclusions the document states are the ones the clang test uses."""

from __future__ import annotations

import re
import shutil
from collections import Counter
from pathlib import Path

import pytest
from test_controller_contract import CLANG_EXCLUSIONS

from runtime.bindings import cbuild
from runtime.commands.freeze import main as freeze_main
from runtime.tooling.misra.check import DOC, documented_rules, run_cppcheck


@pytest.mark.skipif(shutil.which("cppcheck") is None, reason="needs cppcheck (apt-get)")
@pytest.mark.parametrize("float32", [False, True], ids=["double", "float32"])
def test_misra_findings_are_the_documented_deviations(float32: bool) -> None:
    found = Counter(f.rule for f in run_cppcheck(cbuild.GENERATED_C, float32))
    documented = documented_rules()
    assert set(found) == set(documented), (
        f"undocumented: {sorted(set(found) - set(documented))}, "
        f"no longer found: {sorted(set(documented) - set(found))}")
    assert {r: found[r] for r in found} == {r: d.findings for r, d in documented.items()}


@pytest.mark.skipif(shutil.which("cppcheck") is None, reason="needs cppcheck (apt-get)")
def test_frozen_build_adds_no_deviation(tmp_path: Path) -> None:
    """The TDROC build with its configuration compiled in (`wmr freeze`, float32): only
    documented rules, and no more findings of any than the run-time build has."""
    assert freeze_main(["--controller", "tdroc", "--float32", "--out", str(tmp_path)]) == 0
    found = Counter(f.rule for f in run_cppcheck(cbuild.GENERATED_C, True,
                                                 tmp_path / "wmr_tdroc_frozen.h"))
    documented = documented_rules()
    assert set(found) <= set(documented), sorted(set(found) - set(documented))
    assert all(found[r] <= documented[r].findings for r in found), found
    # the step's comparison and re-validation are not in this build (so cppcheck analysed it)
    assert found["15.5"] < documented["15.5"].findings


def test_no_mandatory_rule_is_deviated() -> None:
    assert all(d.category in ("required", "advisory") for d in documented_rules().values())
    assert documented_rules(), "the deviations table did not parse"


def test_clang_exclusions_are_the_documented_ones() -> None:
    text = DOC.read_text(encoding="utf-8")
    section = text.split("## clang `-Weverything`: exclusions", 1)[1].split("\n## ", 1)[0]
    assert tuple(re.findall(r"^\| `(-Wno-[a-z-]+)` \|", section, re.M)) == CLANG_EXCLUSIONS
