"""The order in which ``make test`` hands the test files to its two workers
(``tests/conftest.py``): the longest files it names exist, so that a renamed file is not
silently left to start last."""

from __future__ import annotations

from pathlib import Path

from conftest import LONGEST_FILES

TESTS = Path(__file__).resolve().parents[1]


def test_the_longest_files_exist_and_are_named_once() -> None:
    missing = [name for name in LONGEST_FILES if not (TESTS / name).is_file()]
    assert not missing, f"tests/conftest.py LONGEST_FILES names no file: {missing}"
    assert len(set(LONGEST_FILES)) == len(LONGEST_FILES)
