"""The mutation check (runtime/tooling/mutation) on a planted project, and its mutant list
against this tree: a mutant whose snippet is gone would silently test nothing.

The planted project is a git repository of one module and one test: a mutant the test
catches, one it does not (in code no test reads), one that breaks the import, and one whose
snippet is not there. The tool must tell the four apart and leave the project as it was.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from runtime.tooling.mutation.engine import (
    CAUGHT,
    ERROR,
    STALE,
    UNCAUGHT,
    Mutant,
    report,
    run_all,
    stale,
)
from runtime.tooling.mutation.mutants import MUTANTS

ROOT = Path(__file__).resolve().parents[2]
MODULE = "def add_one(x):\n    return x + 1\n\n\ndef unused(x):\n    return x * 2\n"
TEST = "from m import add_one\n\n\ndef test_add_one():\n    assert add_one(1) == 2\n"


def _planted(tmp: Path) -> Path:
    root = tmp / "planted"
    root.mkdir()
    (root / "m.py").write_text(MODULE)
    (root / "test_m.py").write_text(TEST)
    for cmd in (["git", "init", "-q"], ["git", "add", "m.py", "test_m.py"]):
        subprocess.run(cmd, cwd=root, check=True)
    return root


def test_the_tool_tells_caught_uncaught_error_and_stale(tmp_path: Path) -> None:
    root = _planted(tmp_path)
    mutants = [
        Mutant("off-by-one", "m.py", "return x + 1", "return x + 2", ("test_m.py",), "wrong"),
        Mutant("unused", "m.py", "return x * 2", "return x * 3", ("test_m.py",), "unread"),
        Mutant("syntax", "m.py", "def add_one(x):", "def add_one(x)", ("test_m.py",), "broken"),
        Mutant("gone", "m.py", "return x - 1", "return x", ("test_m.py",), "not there"),
    ]
    assert stale(root, mutants) == ["gone: m.py holds its snippet 0 times"]
    results = run_all(root, mutants, python=sys.executable)
    assert [r.verdict for r in results] == [CAUGHT, UNCAUGHT, ERROR, STALE]
    assert "test_add_one" in results[0].detail
    assert (root / "m.py").read_text() == MODULE  # the project itself is never written
    text = report(results)
    assert text.startswith("2 of 4 mutants caught (1 uncaught, 1 stale, 0 timed out).")
    assert "| off-by-one | `m.py` | caught |" in text


def test_every_mutant_is_live_in_this_tree() -> None:
    assert not stale(ROOT, MUTANTS)
    assert len(MUTANTS) >= 30
    assert len({m.name for m in MUTANTS}) == len(MUTANTS)
    for m in MUTANTS:
        assert m.original != m.replacement and m.tests, m.name
        for t in m.tests:
            assert (ROOT / t.split("::")[0]).is_file(), (m.name, t)
