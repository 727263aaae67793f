"""Cortex-M4 comparison with CasADi's C (issue 6): the facts the report rests on."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from runtime.tooling.firmware import compare_casadi as firmware_compare

pytestmark = pytest.mark.skipif(shutil.which("arm-none-eabi-gcc") is None,
                                reason="arm-none-eabi-gcc not installed (see .ci/run)")


def test_float_build_has_no_double_helpers_and_casadis_has(tmp_path: Path) -> None:
    results = firmware_compare.measure(tmp_path)
    for name in firmware_compare.FUNCTIONS:
        ours = results[(name, "ours", "float32")]
        theirs = results[(name, "casadi", "float32")]
        assert not ours.double_helpers, name
        assert theirs.double_helpers, name  # double literals and sin/cos in CasADi's C
        assert ours.text > 0 and theirs.text > 0
        assert results[(name, "ours", "double")].text > ours.text  # soft double is bigger
