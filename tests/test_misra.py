"""The generated C under cppcheck's MISRA C:2012 addon: exactly the deviations that
docs/STATIC_CHECKS.md lists and justifies, as many findings as it says, in double and in
float32; and the clang exclusions the document states are the ones the clang test uses."""

from __future__ import annotations

import re
import shutil
from collections import Counter

import pytest
from test_controller_contract import CLANG_EXCLUSIONS

from runtime import cbuild
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


def test_no_mandatory_rule_is_deviated() -> None:
    assert all(d.category in ("required", "advisory") for d in documented_rules().values())
    assert documented_rules(), "the deviations table did not parse"


def test_clang_exclusions_are_the_documented_ones() -> None:
    text = DOC.read_text(encoding="utf-8")
    section = text.split("## clang `-Weverything`: exclusions", 1)[1].split("\n## ", 1)[0]
    assert tuple(re.findall(r"^\| `(-Wno-[a-z-]+)` \|", section, re.M)) == CLANG_EXCLUSIONS
