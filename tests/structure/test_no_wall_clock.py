"""No test asserts wall-clock time: the machines that run the suite are shared, and a timed
assertion fails under load with no bug (it did: a reproduction "within 30 s" read 41.7,
53.0 and 61.8 s on a loaded machine). Speed is measured by ``make bench``
(runtime/tooling/bench: derivation, ``wmr model``, ``wmr reproduce``, the steps).

Every test file is parsed with ``ast`` (nothing is run). An ``assert`` fails this check
when its expression reads a clock (``time.time``, ``perf_counter``, ``monotonic``, their
``_ns`` forms) or a name bound in the same function from such a call. A CPU-time reading
(``process_time``) of a child process is not wall time and is allowed.
"""

from __future__ import annotations

import ast
from pathlib import Path

TESTS = Path(__file__).resolve().parents[1]
CLOCKS = frozenset({"time", "perf_counter", "monotonic", "time_ns", "perf_counter_ns",
                    "monotonic_ns"})


def _reads_clock(node: ast.AST) -> bool:
    """Whether ``node`` calls a wall clock (``time.perf_counter()``, ``perf_counter()``)."""
    for sub in ast.walk(node):
        if isinstance(sub, ast.Call):
            f = sub.func
            name = f.attr if isinstance(f, ast.Attribute) else getattr(f, "id", "")
            owner = f.value.id if (isinstance(f, ast.Attribute)
                                   and isinstance(f.value, ast.Name)) else "time"
            if name in CLOCKS and owner == "time":
                return True
    return False


def timed_assertions(source: str) -> list[int]:
    """The lines of ``source``'s asserts that read a wall clock, directly or through a name
    bound from a clock reading in the same function."""
    tree = ast.parse(source)
    found = [n.lineno for n in ast.walk(tree)
             if isinstance(n, ast.Assert) and _reads_clock(n.test)]
    for scope in (n for n in ast.walk(tree)
                  if isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef)):
        clocked = {t.id for n in ast.walk(scope) if isinstance(n, ast.Assign)
                   and _reads_clock(n.value) for t in n.targets if isinstance(t, ast.Name)}
        for n in ast.walk(scope):
            if isinstance(n, ast.Assert) and any(
                    isinstance(s, ast.Name) and s.id in clocked for s in ast.walk(n.test)):
                found.append(n.lineno)
    return sorted(set(found))


def test_the_scan_finds_timed_assertions() -> None:
    """The scan on made-up tests: a checker that cannot fail proves nothing."""
    direct = "import time\ndef test():\n    t0 = time.perf_counter()\n    f()\n" \
             "    assert time.perf_counter() - t0 < 30\n"
    via_name = "import time\ndef test():\n    t0 = time.time()\n    f()\n" \
               "    t1 = time.time()\n    assert t1 - t0 < 2\n"
    cpu = "import time\ndef test():\n    t = time.process_time()\n    assert t >= 0\n"
    assert timed_assertions(direct) == [5]
    assert timed_assertions(via_name) == [6]
    assert timed_assertions(cpu) == []


def test_no_test_asserts_wall_clock_time() -> None:
    offenders = [f"{path.relative_to(TESTS)}:{line}"
                 for path in sorted(TESTS.rglob("*.py"))
                 for line in timed_assertions(path.read_text(encoding="utf-8"))]
    assert not offenders, f"tests asserting wall-clock time (measure in make bench): {offenders}"
