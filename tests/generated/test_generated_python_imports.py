"""Every generated Python module compiles and imports on the oldest Python the project
supports (``requires-python`` in pyproject.toml).

CPython 3.11 and 3.12 refuse deeply nested expressions at compile time
(``RecursionError: maximum recursion depth exceeded during compilation``; 3.13 does not):
a tractor with two trailers generated as closed forms had lines of 186,891 characters and
could not be imported there. The staged generation keeps expressions shallow; these tests
hold it to that on the oldest supported interpreter (this one when it is that version, else
``python3.<minor>`` from PATH) and bound the nesting itself, whatever the interpreter.
"""

from __future__ import annotations

import ast
import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
GENERATED = ROOT / "generated"
MODULES = sorted(GENERATED.rglob("python/*.py"))
# Deepest expression nesting accepted in generated Python. CPython 3.11 gives up near its
# recursion limit (1000): a sum of 1,000 products compiles, of 5,000 does not. The closed-form
# one-trailer model nested 378 deep; the staged models stay under 40.
MAX_DEPTH = 200


def oldest_supported() -> tuple[int, int]:
    spec = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["requires-python"]
    match = re.fullmatch(r">=\s*(\d+)\.(\d+)", spec.strip())
    assert match, f"requires-python {spec!r}: expected '>=X.Y'"
    return int(match.group(1)), int(match.group(2))


def oldest_interpreter() -> str | None:
    major, minor = oldest_supported()
    if sys.version_info[:2] == (major, minor):
        return sys.executable
    return shutil.which(f"python{major}.{minor}")


def depth(node: ast.AST) -> int:
    """Nesting depth of ``node``'s expression tree (iterative: the tree may be deep)."""
    deepest, todo = 0, [(node, 1)]
    while todo:
        n, d = todo.pop()
        deepest = max(deepest, d)
        todo += [(c, d + 1) for c in ast.iter_child_nodes(n) if isinstance(c, ast.expr)]
    return deepest


def test_every_robot_has_generated_python() -> None:
    robots = {p.parent.parent for p in MODULES}
    assert {GENERATED, GENERATED / "trailer", GENERATED / "trailer2",
            GENERATED / "trailer3"} <= robots


def test_generated_python_compiles_and_imports_on_the_oldest_supported_python() -> None:
    python = oldest_interpreter()
    if python is None:
        pytest.skip("python{}.{} not installed".format(*oldest_supported()))
    names = [".".join(p.relative_to(ROOT).with_suffix("").parts) for p in MODULES]
    script = ("import importlib, sys\n"
              "for name in sys.argv[1:]:\n"
              "    importlib.import_module(name)\n"
              "print(sys.version_info[:2])\n")
    result = subprocess.run([python, "-c", script, *names], capture_output=True, text=True,
                            cwd=ROOT, timeout=300)
    assert result.returncode == 0, result.stderr[-3000:]
    assert result.stdout.strip() == str(oldest_supported())


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(GENERATED)))
def test_generated_expressions_stay_shallow(path: Path) -> None:
    tree = ast.parse(path.read_text())
    worst = max((depth(n) for n in ast.walk(tree) if isinstance(n, ast.stmt)), default=0)
    assert worst <= MAX_DEPTH, f"{path.name}: an expression nested {worst} deep"
