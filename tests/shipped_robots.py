"""Which shipped robots a test may derive the control laws of again (SymPy, in the test's
process).

Every shipped robot's generated code goes through the whole pipeline
(tests/generated/test_any_robot_pipeline.py reads it, deriving nothing), its robot file is
read into a model by tests/generated/test_prepared_model.py (seconds), and
``python -m codegen --check`` (tests/codegen/test_codegen_cli.py) derives every one. A test
that derives every robot's control laws again (``codegen.robot_functions.law_specs``) takes
every shipped robot but the tugger train of five carts: its laws take about half of its
50-60 s of CPU in ``wmr model`` (issue 51; docs/SCALING.md), more than such a test's other
robots together, and its code is staged like trailer2's and trailer3's, which those tests
keep. Its own checks: tests/derivation/test_train5.py (a NumPy KKT of its file),
tests/runtime/test_mujoco.py (its MJCF's mass matrix) and the pipeline test.
"""

from __future__ import annotations

from pathlib import Path

from modeling.robot_file import shipped_robot_files

DERIVED_ONLY_BY_CODEGEN = frozenset({"train5"})


def derivable_robot_files() -> dict[str, Path]:
    """The shipped robot files a test may derive the laws of, by file stem (see the module
    docstring)."""
    return {p.stem: p for p in shipped_robot_files() if p.stem not in DERIVED_ONLY_BY_CODEGEN}
